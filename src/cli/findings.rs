//! `tensegrity findings`: every printed equation of a paper checked against the derivation.

use super::solve::{find_mechanism, parse_sets};
use super::{print_out, CliError, Outcome};

pub fn findings(mechanism: &str, sets: &[String], json: bool) -> Result<Outcome, CliError> {
    let m = find_mechanism(mechanism)?;
    let (params, _) = parse_sets(m.as_ref(), sets, &[])?;
    let f = m.findings(&params);
    if json {
        let v: Vec<_> = f
            .iter()
            .map(|f| serde_json::json!({"equation": f.equation, "claim": f.claim, "measured": f.measured, "holds": f.holds}))
            .collect();
        print_out(&format!("{}\n", serde_json::to_string_pretty(&v).unwrap_or_default()))?;
    } else {
        for f in &f {
            print_out(&format!(
                "[{}] {}: {}\n      measured: {}\n",
                if f.holds { "holds" } else { "WRONG" },
                f.equation,
                f.claim,
                f.measured
            ))?;
        }
    }
    Ok(Outcome::Pass)
}
