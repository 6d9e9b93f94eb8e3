//! `tensegrity bench`: settle speed and accuracy on the built-in case sets, against a peer
//! simulator, or over the scale families; the tables are `bench::table`'s.

use super::args::{Command, DEFAULT_PEER};
use super::{bad_input, print_out, write_atomic, CliError, Outcome};
use crate::bench::{self, scale, table};
use std::path::Path;

pub fn bench(command: Command) -> Result<Outcome, CliError> {
    let Command::Bench {
        rounds,
        json,
        export_cases,
        mechanisms,
        peer,
        scale,
        max_struts,
        families,
        max_case_wall_s,
        motion,
    } = command
    else {
        unreachable!("dispatch passes bench commands only")
    };
    // `--peer` without a command: the default peer, run by the Python that has MuJoCo.
    let given_peer = peer.as_deref().filter(|p| *p != DEFAULT_PEER);
    if scale {
        let caps = scale::Caps { max_wall_s: max_case_wall_s, ..scale::DEFAULT_CAPS };
        let named = families;
        if motion {
            if peer.is_none() {
                return Err(bad_input("--motion needs --peer: its reference is MuJoCo's RK4"));
            }
            if let Some(f) = named.iter().find(|f| f.as_str() == "furet") {
                return Err(bad_input(format!(
                    "--motion covers the families whose equations MuJoCo shares ({}); '{f}' has loops MuJoCo closes softly, another model",
                    scale::motion::FAMILIES.join(", ")
                )));
            }
            let families = selected_families(&named, &scale::motion::FAMILIES)?;
            let command = bench::peer_command(given_peer, bench::SCALE_PEER_SCRIPT);
            return scale_motion(json, max_struts, &families, &command);
        }
        let families = selected_families(&named, &scale::FAMILIES)?;
        return match peer {
            Some(_) => {
                let command = bench::peer_command(given_peer, bench::SCALE_PEER_SCRIPT);
                scale_peer(json, max_struts, &families, &caps, &command)
            }
            None => scale_families(json, max_struts, &families, &caps),
        };
    }
    if let Some(dir) = export_cases {
        return export_case_sets(&dir);
    }
    let sets = selected_case_sets(&mechanisms)?;
    match peer {
        Some(_) => against_peer(rounds, json, &sets, &bench::peer_command(given_peer, bench::PEER_SCRIPT)),
        None => case_sets(rounds, json, &sets, mechanisms.is_empty()),
    }
}

/// The scale families that `--family` selects (all when none is named).
/// The families of `all` that `--family` names (all when none is named).
fn selected_families(only: &[String], all: &[&'static str]) -> Result<Vec<&'static str>, CliError> {
    if let Some(bad) = only.iter().find(|o| !all.contains(&o.as_str())) {
        return Err(bad_input(format!("no scale family '{bad}' (families: {})", all.join(", "))));
    }
    Ok(all.iter().copied().filter(|f| only.is_empty() || only.iter().any(|o| o == f)).collect())
}

/// The built-in case sets that `--mechanism` selects (all when none is named).
fn selected_case_sets(only: &[String]) -> Result<Vec<(&'static str, &'static str)>, CliError> {
    if let Some(bad) = only.iter().find(|m| !bench::CASE_SETS.iter().any(|(n, _)| n == m)) {
        return Err(bad_input(format!("no bench case set for mechanism '{bad}'")));
    }
    Ok(bench::CASE_SETS.iter().filter(|(m, _)| only.is_empty() || only.iter().any(|o| o == m)).copied().collect())
}

fn print_json(value: serde_json::Value) -> Result<(), CliError> {
    print_out(&format!("{}\n", serde_json::to_string_pretty(&value).unwrap_or_default()))
}

fn scale_families(
    json: bool,
    max_struts: usize,
    families: &[&'static str],
    caps: &scale::Caps,
) -> Result<Outcome, CliError> {
    let mut reports = Vec::new();
    for family in families {
        eprintln!("{family}: settling up to {max_struts} struts ...");
        let r = scale::run_family(family, max_struts, caps).map_err(|e| super::failed(format!("{family}: {e}")))?;
        if !json {
            print_out(&table::scale_family(&r))?;
        }
        reports.push(r);
    }
    if json {
        print_json(serde_json::json!({ "scale": reports }))?;
    }
    Ok(Outcome::Pass)
}

fn scale_peer(
    json: bool,
    max_struts: usize,
    families: &[&'static str],
    caps: &scale::Caps,
    command: &[String],
) -> Result<Outcome, CliError> {
    let dir = std::env::temp_dir().join(format!("tensegrity-bench-scale-peer-{}", std::process::id()));
    let out = scale::peer::compare(families, max_struts, caps, command, &dir, &|line| eprintln!("{line}"));
    let _ = std::fs::remove_dir_all(&dir);
    let (reports, rows) = out.map_err(bad_input)?;
    if json {
        print_json(serde_json::json!({ "scale": reports, "scale_peer": rows }))?;
    } else {
        for r in &reports {
            print_out(&table::scale_family(r))?;
        }
        print_out(&table::scale_peer(&rows))?;
    }
    Ok(Outcome::Pass)
}

fn scale_motion(
    json: bool,
    max_struts: usize,
    families: &[&'static str],
    command: &[String],
) -> Result<Outcome, CliError> {
    let dir = std::env::temp_dir().join(format!("tensegrity-bench-scale-motion-{}", std::process::id()));
    let out = scale::motion::compare(families, max_struts, command, &dir, &|line| eprintln!("{line}"));
    let _ = std::fs::remove_dir_all(&dir);
    let cases = out.map_err(bad_input)?;
    if json {
        print_json(serde_json::json!({ "scale_motion": cases }))?;
    } else {
        print_out(&table::scale_motion(&cases))?;
    }
    Ok(Outcome::Pass)
}

fn export_case_sets(dir: &Path) -> Result<Outcome, CliError> {
    std::fs::create_dir_all(dir).map_err(|e| bad_input(format!("cannot create {}: {e}", dir.display())))?;
    for (m, file) in bench::CASE_SETS {
        let set =
            bench::bench_scenario(Path::new(file)).and_then(|sc| bench::peer_case_set(m, &sc)).map_err(bad_input)?;
        let path = dir.join(format!("{m}.json"));
        let text = serde_json::to_string_pretty(&set).expect("case set serialises");
        write_atomic(&path, &text).map_err(|e| bad_input(format!("cannot write {}: {e}", path.display())))?;
        print_out(&format!("wrote {} ({} cases)\n", path.display(), set.cases.len()))?;
    }
    Ok(Outcome::Pass)
}

fn against_peer(rounds: usize, json: bool, sets: &[(&str, &str)], command: &[String]) -> Result<Outcome, CliError> {
    let dir = std::env::temp_dir().join(format!("tensegrity-bench-peer-{}", std::process::id()));
    let mut out = Vec::new();
    for (m, file) in sets {
        eprintln!("{m}: {rounds} rounds, testbed and peer alternating ...");
        let c = bench::bench_against_peer(m, Path::new(file), rounds, command, &dir);
        out.push(c.map_err(|e| {
            let _ = std::fs::remove_dir_all(&dir);
            bad_input(e)
        })?);
    }
    let _ = std::fs::remove_dir_all(&dir);
    if json {
        print_json(serde_json::json!({ "comparisons": out }))?;
    } else {
        print_out(&table::peer_comparison(&out))?;
    }
    Ok(Outcome::from_passed(out.iter().all(|c| c.testbed.all_settled)))
}

/// The case sets' medians; with every set (`all`), the interference observer's cost too.
fn case_sets(rounds: usize, json: bool, sets: &[(&str, &str)], all: bool) -> Result<Outcome, CliError> {
    let mut results = Vec::new();
    for (m, file) in sets {
        results.push(bench::bench_case_set(m, Path::new(file), rounds).map_err(bad_input)?);
    }
    let interference = if all {
        bench::bench_interference(&bench::INTERFERENCE_BENCH_SIZES, bench::INTERFERENCE_BENCH_REPEATS)
    } else {
        Vec::new()
    };
    if json {
        print_json(serde_json::json!({ "results": results, "interference": interference }))?;
    } else {
        print_out(&table::case_sets(&results, &interference))?;
    }
    Ok(Outcome::from_passed(results.iter().all(|r| r.all_settled)))
}
