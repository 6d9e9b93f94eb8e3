//! `tensegrity list`: mechanisms, parameters, inputs, quantities and queries.

use super::{load_one, CliError, Outcome};
use crate::mechanisms::{self, Origin};
use crate::scenario::Override;
use std::path::Path;

/// Every mechanism, or with a scenario file that file's mechanism and model symbols.
pub fn list(scenario: Option<&Path>, overrides: &[Override]) -> Result<Outcome, CliError> {
    match scenario {
        None if !overrides.is_empty() => return Err(super::bad_input("--set needs a scenario file to set values of")),
        None => mechanisms::registry().iter().for_each(|m| print_mechanism(m.as_ref())),
        Some(file) => list_file(file, overrides)?,
    }
    Ok(Outcome::Pass)
}

/// `list FILE`: the file's mechanism with the parameter values the file gives, then the
/// symbols of its model section, if it has one.
fn list_file(file: &Path, overrides: &[Override]) -> Result<(), CliError> {
    let sc = load_one(file, overrides)?;
    let m = sc.mechanism();
    print_mechanism(m.as_ref());
    println!("  parameter values in {}:", file.display());
    for (k, v) in &sc.params {
        println!("    {k:<12} = {v}");
    }
    if let Some(model) = &sc.model {
        println!("  model symbols (for [[quantities]], [[predictions]], [[equations]]):");
        println!("    {}", model.names().join(" "));
    }
    Ok(())
}

/// A mechanism's parameters, inputs, start keys, quantities and queries.
fn print_mechanism(m: &dyn mechanisms::Mechanism) {
    println!("{}: {}", m.name(), m.title());
    println!("  parameters:");
    for p in m.params() {
        let origin = match p.origin {
            // A custom file's own parameters.
            _ if m.name() == "custom" => "file",
            Origin::Paper => "paper",
            Origin::ModelChoice => "model choice",
        };
        println!("    {:<12} [{}] default {} ({}): {}", p.symbol, p.unit, p.default, origin, p.description);
    }
    println!("  inputs:");
    for i in m.inputs() {
        println!("    {:<12} [{}] {}", i.symbol, i.unit, i.description);
    }
    println!("  start keys ([start] table):");
    for (k, what) in m.start_keys() {
        println!("    {k:<16} {what}");
    }
    println!("  checkable quantities:");
    for q in m.quantities() {
        println!("    {:<12} [{}] {}", q.symbol, q.unit, q.description);
    }
    println!("  queries (tensegrity solve {} QUERY --set NAME=VALUE ...):", m.name());
    for q in m.queries() {
        println!("    {:<12} inputs {}: {}", q.name, q.inputs.join(" "), q.description);
    }
}
