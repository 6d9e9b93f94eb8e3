//! `[expect]`: what the run must do.

use super::error::{Ctx, ScenarioError};
use super::raw::RawExpect;
use crate::file_model::spec::ModelSpec;
use crate::settings::Check;
use toml::Spanned;

/// The parts of a scenario that `[expect] failing` may name.
pub(super) struct Parts<'a> {
    pub checks: &'a [Check],
    pub model: Option<&'a ModelSpec>,
    pub probe: bool,
    pub motion: Option<&'a crate::settings::Motion>,
    /// The prestress is judged (`[prestress]`, or a custom structure with cables).
    pub prestress: bool,
}

/// Names in a message: `none` for an empty list.
fn listed(names: Vec<&str>) -> String {
    if names.is_empty() {
        "none".into()
    } else {
        names.join(", ")
    }
}

/// The names of the frequency predictions: `[[energy.frequencies]]` and
/// `[[motion.frequencies]]`.
fn frequency_names<'a>(parts: &Parts<'a>) -> Vec<&'a str> {
    let dynamics = parts.model.and_then(|m| m.energy.as_ref()).and_then(|e| e.dynamics.as_ref());
    let model = dynamics.into_iter().flat_map(|d| d.frequencies.iter().map(|f| f.name.as_str()));
    let motion = parts.motion.into_iter().flat_map(|m| m.frequencies.iter().map(|f| f.name.as_str()));
    model.chain(motion).collect()
}

/// The `[energy]` coordinates a motion is compared by with the Lagrangian model.
fn trajectory_coordinates<'a>(parts: &Parts<'a>) -> Vec<&'a str> {
    let energy = parts.model.and_then(|m| m.energy.as_ref());
    let compared = energy.filter(|e| e.dynamics.as_ref().is_some_and(|d| d.trajectory.is_some()));
    compared.into_iter().flat_map(|e| e.coordinates.iter().map(|c| c.name.as_str())).collect()
}

/// A part `[expect] failing` names that the scenario does not have.
#[derive(Debug, thiserror::Error)]
enum MissingPart {
    /// A named part (a check, a prediction, ...) that is not among those `among` lists.
    #[error("'{name}' is not among {among} ({listed})")]
    NotAmong { name: String, among: &'static str, listed: String },
    /// A part that needs a section the scenario does not have.
    #[error("'{name}' needs {needs}")]
    Needs { name: &'static str, needs: &'static str },
}

/// Whether the scenario has the part `failure` names; else what it has.
fn has_part(parts: &Parts, failure: &crate::report::verdict::Failure) -> Result<(), MissingPart> {
    use crate::report::verdict::Failure;
    let model = parts.model;
    let not_among =
        |name: &String, among, names| Err(MissingPart::NotAmong { name: name.clone(), among, listed: listed(names) });
    let needs = |name, needs| Err(MissingPart::Needs { name, needs });
    match failure {
        Failure::Check(q) if !parts.checks.iter().any(|c| &c.quantity == q) => {
            not_among(q, "this scenario's checks", parts.checks.iter().map(|c| c.quantity.as_str()).collect())
        }
        Failure::Prediction(p) if !model.is_some_and(|m| m.predictions.iter().any(|x| &x.name == p)) => not_among(
            p,
            "this scenario's [[predictions]]",
            model.map_or(vec![], |m| m.predictions.iter().map(|x| x.name.as_str()).collect()),
        ),
        Failure::Equation(q) if !model.is_some_and(|m| m.equations.iter().any(|x| &x.name == q)) => not_among(
            q,
            "this scenario's [[equations]]",
            model.map_or(vec![], |m| m.equations.iter().map(|x| x.name.as_str()).collect()),
        ),
        Failure::Frequency(q) if !frequency_names(parts).contains(&q.as_str()) => {
            not_among(q, "this scenario's [[energy.frequencies]] and [[motion.frequencies]]", frequency_names(parts))
        }
        Failure::Trajectory(q) if !trajectory_coordinates(parts).contains(&q.as_str()) => {
            not_among(q, "the coordinates compared by [energy.trajectory]", trajectory_coordinates(parts))
        }
        Failure::Energy if model.is_none_or(|m| m.energy.is_none()) => {
            needs("energy", "an [energy] section in this scenario")
        }
        Failure::Probe if !parts.probe => needs("probe", "a [probe] section that compares (expected and tolerance)"),
        Failure::Prestress if !parts.prestress => {
            needs("prestress", "cables whose tension is judged ([prestress], or a custom structure with cables)")
        }
        _ => Ok(()),
    }
}

/// `[expect]`: `verdict = "pass"`, or `"fail"` with the parts that must fail (`failing`), each
/// a part this scenario has (a `check:` names one of its `[[checks]]`, a `prediction:` or
/// `equation:` one of its model's entries).
pub(super) fn expectation(
    ctx: &Ctx,
    raw: &Spanned<RawExpect>,
    parts: &Parts,
) -> Result<crate::report::verdict::Expectation, ScenarioError> {
    use crate::report::verdict::{Expectation, Failure, UnknownFailure};
    let e = raw.get_ref();
    let mut failing = Vec::new();
    for f in &e.failing {
        let failure: Failure = f.get_ref().parse().map_err(|e: UnknownFailure| ctx.err(f, e.to_string()))?;
        has_part(parts, &failure).map_err(|e| ctx.err(f, e.to_string()))?;
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
