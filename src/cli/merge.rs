//! `tensegrity merge`: the CSVs of a sharded sweep joined into one, rows in grid order.

use super::{check_outputs, write_atomic, CliError, Outcome};
use std::path::{Path, PathBuf};

/// Largest shard CSV read [bytes]: a million-point sweep's CSV is about 200 MB.
pub const MAX_SHARD_BYTES: u64 = 512 << 20;

pub fn merge(csvs: &[PathBuf], out: &Path, partial: bool) -> Result<Outcome, CliError> {
    check_outputs(csvs, &[("--out".into(), out.to_path_buf())])?;
    let mut texts = Vec::new();
    for p in csvs {
        let text = crate::input::read_text(p, MAX_SHARD_BYTES, false)
            .map_err(|e| super::bad_input(format!("{}: {e}", p.display())))?;
        texts.push((p.display().to_string(), text));
    }
    let merged = crate::study::sweep::merge_csv(&texts, partial).map_err(super::bad_input)?;
    write_atomic(out, &merged)?;
    Ok(Outcome::Pass)
}
