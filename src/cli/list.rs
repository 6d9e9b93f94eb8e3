//! `tensegrity list`: mechanisms, parameters, inputs, quantities and queries.

use super::{load_one, print_out, CliError, Outcome};
use crate::mechanisms::{self, Origin};
use crate::scenario::Override;
use std::fmt::Write;
use std::path::Path;

/// Every mechanism, or with a scenario file that file's mechanism and model symbols.
pub fn list(scenario: Option<&Path>, overrides: &[Override]) -> Result<Outcome, CliError> {
    match scenario {
        None if !overrides.is_empty() => return Err(super::bad_input("--set needs a scenario file to set values of")),
        None => print_out(&mechanisms::registry().iter().map(|m| mechanism_text(m.as_ref())).collect::<String>())?,
        Some(file) => print_out(&file_text(file, overrides)?)?,
    }
    Ok(Outcome::Pass)
}

/// `list FILE`: the file's mechanism with the parameter values the file gives, then the
/// symbols of its model section, if it has one.
fn file_text(file: &Path, overrides: &[Override]) -> Result<String, CliError> {
    let sc = load_one(file, overrides)?;
    let m = sc.mechanism();
    let mut out = mechanism_text(m.as_ref());
    let _ = writeln!(out, "  parameter values in {}:", file.display());
    for (k, v) in &sc.params {
        let _ = writeln!(out, "    {k:<12} = {v}");
    }
    if let Some(model) = &sc.model {
        let _ = writeln!(out, "  model symbols (for [[quantities]], [[predictions]], [[equations]]):");
        let _ = writeln!(out, "    {}", model.names().join(" "));
    }
    Ok(out)
}

/// A mechanism's parameters, inputs, start keys, quantities and queries.
fn mechanism_text(m: &dyn mechanisms::Mechanism) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "{}: {}", m.name(), m.title());
    let _ = writeln!(out, "  parameters:");
    for p in m.params() {
        let origin = match p.origin {
            // A custom file's own parameters.
            _ if m.name() == "custom" => "file",
            Origin::Paper => "paper",
            Origin::ModelChoice => "model choice",
        };
        let _ =
            writeln!(out, "    {:<12} [{}] default {} ({}): {}", p.symbol, p.unit, p.default, origin, p.description);
    }
    let _ = writeln!(out, "  inputs:");
    for i in m.inputs() {
        let _ = writeln!(out, "    {:<12} [{}] {}", i.symbol, i.unit, i.description);
    }
    let _ = writeln!(out, "  start keys ([start] table):");
    for (k, what) in m.start_keys() {
        let _ = writeln!(out, "    {k:<16} {what}");
    }
    let _ = writeln!(out, "  checkable quantities:");
    for q in m.quantities() {
        let _ = writeln!(out, "    {:<12} [{}] {}", q.symbol, q.unit, q.description);
    }
    let _ = writeln!(out, "  queries (tensegrity solve {} QUERY --set NAME=VALUE ...):", m.name());
    for q in m.queries() {
        let _ = writeln!(out, "    {:<12} inputs {}: {}", q.name, q.inputs.join(" "), q.description);
    }
    out
}
