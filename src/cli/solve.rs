//! `tensegrity solve`: the analytic model alone, every branch or solution of a query.

use super::{bad_input, print_out, CliError, Outcome};
use crate::mechanisms::{self, Mechanism, Solution, Values};

/// Splits `--set NAME=VALUE` flags into the mechanism's parameters (with their defaults,
/// validated) and the inputs in `allowed_inputs`.
pub(super) fn parse_sets(
    m: &dyn Mechanism,
    sets: &[String],
    allowed_inputs: &[&str],
) -> Result<(Values, Values), CliError> {
    let mut params = Values::new();
    let mut inputs = Values::new();
    for s in sets {
        let (k, v) = s.split_once('=').ok_or_else(|| bad_input(format!("--set {s}: expected NAME=VALUE")))?;
        let x: f64 = v.trim().parse().map_err(|_| bad_input(format!("--set {s}: '{v}' is not a number")))?;
        if !x.is_finite() {
            return Err(bad_input(format!("--set {s}: the value must be finite")));
        }
        if params.contains_key(k) || inputs.contains_key(k) {
            return Err(bad_input(format!("--set {s}: '{k}' is set twice (give each name once)")));
        }
        if m.params().iter().any(|p| p.symbol == k) {
            params.insert(k.into(), x);
        } else if allowed_inputs.contains(&k) {
            inputs.insert(k.into(), x);
        } else {
            let known: Vec<&str> = m.params().iter().map(|p| p.symbol).chain(allowed_inputs.iter().copied()).collect();
            return Err(bad_input(format!("--set {s}: unknown name '{k}' (expected one of: {})", known.join(", "))));
        }
    }
    let params = mechanisms::with_defaults(m, &params);
    m.validate_params(&params).map_err(bad_input)?;
    Ok((params, inputs))
}

/// The built-in mechanism called `name`.
pub(super) fn find_mechanism(name: &str) -> Result<Box<dyn Mechanism>, CliError> {
    mechanisms::find_named(name).map_err(bad_input)
}

pub fn solve(mechanism: &str, query: &str, sets: &[String], json: bool) -> Result<Outcome, CliError> {
    let m = find_mechanism(mechanism)?;
    let q = mechanisms::query_named(m.as_ref(), query).map_err(bad_input)?;
    let (params, inputs) = parse_sets(m.as_ref(), sets, q.inputs)?;
    if let Some(i) = q.inputs.iter().find(|i| !inputs.contains_key(**i)) {
        return Err(bad_input(format!("query '{query}' needs --set {i}=VALUE (inputs: {})", q.inputs.join(" "))));
    }
    let sols = m.solve(query, &params, &inputs).map_err(bad_input)?;
    let non_finite = sols.iter().find_map(|s| s.values.iter().find(|(_, v)| !v.is_finite()).map(|kv| (s, kv)));
    if let Some((s, (k, v))) = non_finite {
        return Err(bad_input(format!(
            "{mechanism} {query}: {} gives {k} = {v} with these values: outside the range where the model is a \
             number (nothing printed)",
            s.label
        )));
    }
    if json {
        let v = serde_json::json!({
            "mechanism": mechanism, "query": query, "params": params, "inputs": inputs,
            "solutions": sols.iter().map(|s| serde_json::json!({"label": s.label, "values": s.values, "stable": s.stable})).collect::<Vec<_>>(),
        });
        print_out(&format!("{}\n", serde_json::to_string_pretty(&v).unwrap_or_default()))?;
    } else {
        print_out(&solutions_text(mechanism, query, &sols))?;
    }
    Ok(Outcome::Pass)
}

fn solutions_text(mechanism: &str, query: &str, sols: &[Solution]) -> String {
    use std::fmt::Write;
    let mut out = format!("{mechanism} {query}: {} result(s)\n", sols.len());
    for s in sols {
        let st = match s.stable {
            Some(true) => ", stable",
            Some(false) => ", unstable",
            None => "",
        };
        let _ = writeln!(out, "  {}{st}:", s.label);
        for (k, v) in &s.values {
            let _ = writeln!(out, "    {k:<12} = {v:.12}");
        }
    }
    out
}
