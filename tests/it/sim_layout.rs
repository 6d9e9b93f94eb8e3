//! The simulator's layout, read from `src/sim/`: an immutable model beside the state that
//! steps (after MuJoCo's `mjModel` and `mjData`). Only the build writes the model; each
//! concept's state is its own struct, so no file takes another's state apart to get past the
//! borrow checker, and only `mod.rs` orders the concepts through a step.

use std::path::{Path, PathBuf};

/// Every `.rs` file under `src/sim/`, with its text up to its unit tests.
fn sim_sources() -> Vec<(PathBuf, String)> {
    super::common::rust_files(Path::new("src/sim"))
        .into_iter()
        .map(|p| {
            let text = std::fs::read_to_string(&p).unwrap();
            let code = text.split("#[cfg(test)]").next().unwrap_or_default().to_string();
            (p, code)
        })
        .collect()
}

#[test]
fn no_simulator_state_is_taken_apart_with_mem_take() {
    let sources = sim_sources();
    assert!(sources.len() >= 20, "read only {} files of src/sim", sources.len());
    let offenders: Vec<String> =
        sources.iter().filter(|(_, code)| code.contains("mem::take")).map(|(p, _)| p.display().to_string()).collect();
    assert!(offenders.is_empty(), "files of src/sim that mem::take state: {offenders:?}");
}

#[test]
fn only_the_simulators_own_file_orders_the_concepts() {
    let offenders: Vec<String> = sim_sources()
        .iter()
        .filter(|(p, code)| !p.ends_with("sim/mod.rs") && code.contains("impl Simulation"))
        .map(|(p, _)| p.display().to_string())
        .collect();
    assert!(offenders.is_empty(), "files of src/sim besides mod.rs with `impl Simulation`: {offenders:?}");
}

#[test]
fn only_the_build_writes_the_model() {
    // An assignment to a model's field (`model.x = ...` or `m.x = ...`) or a mutable borrow of
    // the model anywhere but the build.
    let mut offenders = Vec::new();
    for (p, code) in sim_sources() {
        if p.ends_with("sim/build.rs") {
            continue;
        }
        for (k, line) in code.lines().enumerate() {
            let l = line.trim();
            let writes = ["model.", "m."].iter().any(|prefix| {
                l.strip_prefix(prefix).is_some_and(|rest| {
                    let field: String = rest.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
                    let after = rest[field.len()..].trim_start();
                    !field.is_empty() && after.starts_with('=') && !after.starts_with("==")
                })
            });
            if writes || l.contains("&mut self.model") || l.contains("m: &mut Model") {
                offenders.push(format!("{}:{}: {l}", p.display(), k + 1));
            }
        }
    }
    assert!(offenders.is_empty(), "the model written outside the build: {offenders:?}");
}

/// The names a path's `prefix` (`super::`, `super::super::`, `crate::sim::`) reaches in `code`
/// that are items of that module itself rather than modules below it: `super::Model` or
/// `super::{Data, build}`'s `Data` (a name not followed by `::`), once per occurrence.
fn items_reached_through(code: &str, prefix: &str) -> Vec<String> {
    let mut out = Vec::new();
    for (at, _) in code.match_indices(prefix) {
        // `super::super::` also contains `super::`: only the longest prefix counts.
        if prefix == "super::" && code[at + prefix.len()..].starts_with("super::") {
            continue;
        }
        if prefix == "super::" && code[..at].ends_with("super::") {
            continue;
        }
        let rest = &code[at + prefix.len()..];
        let names: Vec<&str> = match rest.strip_prefix('{') {
            Some(list) => list.split('}').next().unwrap_or_default().split(',').map(str::trim).collect(),
            None => vec![rest],
        };
        for name in names {
            let ident: String = name.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
            if !ident.is_empty() && !name[ident.len()..].starts_with("::") && ident != "self" {
                out.push(ident);
            }
        }
    }
    out
}

/// The simulator's shared types live beneath its step (`sim/model.rs`, `sim/data.rs`): no
/// concept file reaches back up into `sim/mod.rs` for an item (it only orders the step), and
/// `model.rs` imports no concept file. Measured at e95ee92 with the same reading: 62 such
/// references from 24 files.
#[test]
fn no_concept_file_reaches_back_up_into_the_simulators_step() {
    let mut offenders = Vec::new();
    for (p, code) in sim_sources() {
        if p.ends_with("sim/mod.rs") {
            continue;
        }
        let nested = p.parent().is_some_and(|d| !d.ends_with("sim"));
        let up = if nested { "super::super::" } else { "super::" };
        for item in items_reached_through(&code, up).into_iter().chain(items_reached_through(&code, "crate::sim::")) {
            offenders.push(format!("{}: {item}", p.display()));
        }
    }
    assert!(offenders.is_empty(), "{} reference(s) back up into sim/mod.rs: {offenders:?}", offenders.len());
    let model = sim_sources().into_iter().find(|(p, _)| p.ends_with("sim/model.rs")).expect("sim/model.rs");
    assert!(!model.1.contains("use super::"), "sim/model.rs imports a concept file");
}
