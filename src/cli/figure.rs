//! `tensegrity figure`: one of the papers' figures as PNG and SVG, or the list of them.

use super::{print_out, CliError, Outcome};
use std::path::Path;

pub fn figure(name: Option<&str>, out: &Path, list: bool) -> Result<Outcome, CliError> {
    let name = match (name, list) {
        (Some(n), false) => n,
        _ => {
            for f in crate::figures::all() {
                print_out(&format!("{}: {}\n", f.name, f.description))?;
            }
            return if list {
                Ok(Outcome::Pass)
            } else {
                Err(super::bad_input("name one of the figures listed above"))
            };
        }
    };
    for f in crate::figures::draw(name, out).map_err(super::bad_input)? {
        print_out(&format!("wrote {}\n", f.display()))?;
    }
    Ok(Outcome::Pass)
}
