//! `tensegrity merge`: the CSVs of a sharded sweep joined into one, rows in grid order.

use super::{check_outputs, write_atomic, CliError, Outcome};
use std::path::{Path, PathBuf};

pub fn merge(csvs: &[PathBuf], out: &Path, partial: bool) -> Result<Outcome, CliError> {
    check_outputs(csvs, &[("--out".into(), out.to_path_buf())])?;
    let mut texts = Vec::new();
    for p in csvs {
        let text =
            std::fs::read_to_string(p).map_err(|e| super::bad_input(format!("cannot read {}: {e}", p.display())))?;
        texts.push((p.display().to_string(), text));
    }
    let merged = crate::sweep::merge_csv(&texts, partial).map_err(super::bad_input)?;
    write_atomic(out, &merged)?;
    Ok(Outcome::Pass)
}
