//! `tensegrity check`: validate scenario files without running them.

use super::{load_all, print_out, CliError, Outcome};
use crate::scenario::Override;
use std::path::PathBuf;

pub fn check(paths: &[PathBuf], overrides: &[Override]) -> Result<Outcome, CliError> {
    for s in load_all(paths, overrides)? {
        print_out(&format!("{}: ok ({} on {})\n", s.file.display(), s.name, s.mechanism))?;
    }
    Ok(Outcome::Pass)
}
