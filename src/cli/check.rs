//! `tensegrity check`: validate scenario files without running them.

use super::{load_all, CliError, Outcome};
use std::path::PathBuf;

pub fn check(paths: &[PathBuf]) -> Result<Outcome, CliError> {
    for s in load_all(paths)? {
        println!("{}: ok ({} on {})", s.file.display(), s.name, s.mechanism);
    }
    Ok(Outcome::Pass)
}
