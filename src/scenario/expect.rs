//! `[expect]`: what the run must do.

use super::error::{Ctx, ScenarioError};
use super::raw::RawExpect;
use crate::settings::Check;
use toml::Spanned;

/// `[expect]`: `verdict = "pass"`, or `"fail"` with the parts that must fail (`failing`), each
/// a part this scenario has (a `check:` names one of its `[[checks]]`).
pub(super) fn expectation(
    ctx: &Ctx,
    raw: &Spanned<RawExpect>,
    checks: &[Check],
) -> Result<crate::settings::Expectation, ScenarioError> {
    use crate::settings::{Expectation, Failure};
    let e = raw.get_ref();
    let mut failing = Vec::new();
    for f in &e.failing {
        let failure: Failure = f.get_ref().parse().map_err(|m: String| ctx.err(f, m))?;
        if let Failure::Check(q) = &failure {
            if !checks.iter().any(|c| &c.quantity == q) {
                let known: Vec<_> = checks.iter().map(|c| c.quantity.as_str()).collect();
                return Err(ctx.err(f, format!("'{q}' is not among this scenario's checks ({})", known.join(", "))));
            }
        }
        failing.push(failure);
    }
    match e.verdict.get_ref().as_str() {
        "pass" if failing.is_empty() => Ok(Expectation::PASS),
        "pass" => Err(ctx.err(&e.failing[0], "expect.failing goes with verdict = \"fail\"")),
        "fail" if failing.is_empty() => Err(ctx.err(
            &e.verdict,
            "verdict = \"fail\" needs expect.failing: the parts that must fail (for example [\"interference\"])",
        )),
        "fail" => Ok(Expectation { failing }),
        other => Err(ctx.err(&e.verdict, format!("expect.verdict must be \"pass\" or \"fail\", got '{other}'"))),
    }
}
