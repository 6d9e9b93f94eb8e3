//! `mechanism` and `[structure]`: a built-in mechanism by name, or the file's own structure.

use super::error::{finite, Ctx, ScenarioError};
use super::number::{param_start, param_values, resolve_structure, ParamMap};
use super::params::params_at;
use super::raw::{RawActuation, RawScenario};
use super::structure::structure_from_file;
use super::Actuation;
use crate::file_model::params::ParamTable;
use crate::mechanisms::custom::{Custom, FileParam};
use crate::mechanisms::{self, Mechanism, Values};
use toml::Spanned;

/// `mechanism = "custom"`: the mechanism built from the `[structure]` table, with each check's
/// expected value (required: there is no analytic model). A built-in mechanism: `None`, and
/// neither a `[structure]` nor a check's value may be given.
pub(super) fn custom(ctx: &Ctx, raw: &RawScenario) -> Result<Option<Custom>, ScenarioError> {
    match (raw.mechanism.get_ref().as_str(), &raw.structure) {
        ("custom", Some(st)) => {
            let params = param_values(ctx, &raw.params)?;
            let mut st = st.clone();
            resolve_structure(ctx, st.get_mut(), &params)?;
            let mut structure = structure_from_file(ctx, &st)?;
            super::prestress::set_self_stress(ctx, raw, &mut structure, &params)?;
            let mut expected = Values::new();
            for c in &raw.checks {
                let v = c.value.as_ref().ok_or_else(|| {
                    ctx.err(
                        &c.quantity,
                        "a custom structure has no analytic model: give the expected value (value = ...)",
                    )
                })?;
                expected.insert(c.quantity.get_ref().clone(), finite(ctx, v, "value")?);
            }
            Ok(Some(Custom::new(structure, expected).with_params(param_specs(&raw.params, &params))))
        }
        ("custom", None) => Err(ctx.err(
            &raw.mechanism,
            "mechanism = \"custom\" needs a [structure] table (bodies, struts, springs, cables, joints, actuators)",
        )),
        (_, Some(st)) => Err(ctx.err(st, "a [structure] table goes with mechanism = \"custom\" only")),
        _ => match raw.checks.iter().find_map(|c| c.value.as_ref()) {
            Some(v) => Err(ctx.err(
                v,
                "value is for custom structures; a built-in mechanism's checks compare with its analytic model",
            )),
            None => Ok(None),
        },
    }
}

/// Largest number of distinct parameter sets a sweep over parameters may ask for (each is a
/// structure of its own, built and checked at read).
pub const MAX_PARAMETER_SETS: usize = 10_000;

/// The distinct sets of parameters the actuation's points ask for, in their order (the
/// scenario's own set when no point sets a parameter); more than [`MAX_PARAMETER_SETS`] is an
/// error at `[actuation]`, found as the sets are gathered (each set is looked up in a hash of
/// its bits, so a million points take one pass).
pub(super) fn parameter_sets(
    ctx: &Ctx,
    raw: &RawScenario,
    table: &ParamTable,
    params: &Values,
    actuation: &Actuation,
) -> Result<Vec<Values>, ScenarioError> {
    let points = actuation.all_inputs();
    let bits = |set: &Values| set.values().map(|x| x.to_bits()).collect::<Vec<u64>>();
    let (mut sets, mut seen) = (Vec::new(), std::collections::HashSet::new());
    for p in points {
        let set = params_at(table, params, p);
        if let Some((k, x)) = set.iter().find(|(_, x)| !x.is_finite()) {
            let at = raw
                .params
                .iter()
                .find(|(n, _)| n.get_ref() == k)
                .map_or(raw.actuation.span().start, |(_, d)| param_start(d));
            return Err(
                ctx.err_at(at, format!("parameter '{k}' is {x} at the point {p:?}: a parameter is a finite number"))
            );
        }
        if seen.insert(bits(&set)) {
            if sets.len() == MAX_PARAMETER_SETS {
                return Err(too_many_sets(ctx, &raw.actuation, &format!("more than {MAX_PARAMETER_SETS}")));
            }
            sets.push(set);
        }
    }
    Ok(sets)
}

/// The error for more than [`MAX_PARAMETER_SETS`] sets of parameters (`count`: how many).
pub(super) fn too_many_sets(ctx: &Ctx, actuation: &Spanned<RawActuation>, count: &str) -> ScenarioError {
    ctx.err(
        actuation,
        format!("the actuation asks for {count} sets of parameters; at most {MAX_PARAMETER_SETS} (each is a structure built and checked at read)"),
    )
}

/// The custom structure at every set of parameters in `sets` besides the file's own, each
/// resolved and read as the file's own is (an error names the set).
pub(super) fn with_variants(
    ctx: &Ctx,
    raw: &RawScenario,
    custom: Custom,
    params: &Values,
    sets: &[Values],
) -> Result<Custom, ScenarioError> {
    let variants = variants(ctx, raw, sets.iter().filter(|set| *set != params))?;
    Ok(custom.with_variants(variants))
}

/// The file's structure resolved and read at each of `sets` (every parameter's value), as
/// the file's own is (an error names the set); none without a `[structure]`.
pub(super) fn variants<'a>(
    ctx: &Ctx,
    raw: &RawScenario,
    sets: impl Iterator<Item = &'a Values>,
) -> Result<Vec<(Values, crate::structure::Structure)>, ScenarioError> {
    let Some(st) = &raw.structure else { return Ok(Vec::new()) };
    let mut variants = Vec::new();
    for set in sets {
        let mut st = st.clone();
        let at_set =
            |e: ScenarioError| ScenarioError { message: format!("{} (with the parameters {set:?})", e.message), ..e };
        resolve_structure(ctx, st.get_mut(), set).map_err(at_set)?;
        let mut structure = structure_from_file(ctx, &st).map_err(at_set)?;
        super::prestress::set_self_stress(ctx, raw, &mut structure, set).map_err(at_set)?;
        variants.push((set.clone(), structure));
    }
    Ok(variants)
}

/// The built-in mechanism `raw.mechanism` names (a scenario without its own structure).
pub(super) fn builtin(ctx: &Ctx, raw: &RawScenario) -> Result<Box<dyn Mechanism>, ScenarioError> {
    mechanisms::find(raw.mechanism.get_ref()).ok_or_else(|| {
        let known: Vec<_> = mechanisms::registry().iter().map(|m| m.name()).collect();
        ctx.err(
            &raw.mechanism,
            format!("unknown mechanism '{}' (expected one of: {}, custom)", raw.mechanism.get_ref(), known.join(", ")),
        )
    })
}

/// The scenario's mechanism: its custom one, else its built-in one (one of the two is there).
pub(super) fn of<'a>(custom: Option<&'a Custom>, builtin: Option<&'a dyn Mechanism>) -> &'a dyn Mechanism {
    match custom {
        Some(c) => c,
        None => builtin.expect("a scenario has a custom or a built-in mechanism"),
    }
}

/// The parameters a custom file declares: each with its value, unit and description.
fn param_specs(raw: &ParamMap, values: &Values) -> Vec<FileParam> {
    raw.iter()
        .map(|(k, p)| {
            let p = p.get_ref();
            FileParam {
                symbol: k.get_ref().clone(),
                value: values.get(k.get_ref()).copied().unwrap_or(f64::NAN),
                unit: p.unit.clone().unwrap_or_else(|| "-".into()),
                description: p.description.clone().unwrap_or_else(|| match &p.value {
                    super::number::Num::Expr(e) => format!("= {e}"),
                    super::number::Num::Value(_) => "from the file".into(),
                }),
            }
        })
        .collect()
}
