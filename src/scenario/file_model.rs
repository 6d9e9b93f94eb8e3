//! `[[quantities]]`, `[[predictions]]` and `[[equations]]`: the file's own model, compiled into
//! a [`ModelSpec`] against the symbols of the mechanism's structure (node coordinates, member
//! forces and lengths, revolute joints' angles and prismatic joints' slides), its observed
//! quantities, inputs and parameters, and time `t`. An error
//! inside an expression names its `file:LINE:COL` inside the string and the symbols there.

use super::error::{positive_value, Ctx, ScenarioError};
use super::number::expr_error;
use super::raw::{RawEquation, RawPrediction, RawQuantity, RawScenario, RawSensitivity};
use super::Actuation;
use crate::file_model::expr::Expr;
use crate::file_model::spec::{Equation, ErrorClass, ModelSpec, Prediction, Quantity, Sensitivity, Source, Symbol};
use crate::mechanisms::{Mechanism, Values};
use crate::structure::{JointKind, MemberKind};
use toml::Spanned;

/// The compiled model section, or None when the file states none.
pub(super) fn model(
    ctx: &Ctx,
    raw: &RawScenario,
    m: &dyn Mechanism,
    params: &Values,
    start: &Values,
    actuation: &Actuation,
) -> Result<Option<ModelSpec>, ScenarioError> {
    let Some(first) = first_entry(raw) else { return Ok(None) };
    let inputs = match actuation {
        Actuation::Points { points, .. } => &points[0],
        Actuation::Schedule { waypoints } => &waypoints[0].1,
    };
    let structure = m
        .build(params, inputs, start)
        .map_err(|e| ctx.err_at(first, format!("cannot list the structure's symbols: {e}")))?;
    let mut spec = ModelSpec { symbols: state_symbols(&structure, m, params), ..Default::default() };
    for q in &raw.quantities {
        quantity(ctx, &mut spec, q)?;
    }
    for s in &raw.sensitivities {
        sensitivity(ctx, &mut spec, s, params, raw.motion.is_some())?;
    }
    for p in &raw.predictions {
        prediction(ctx, &mut spec, p, raw.motion.is_some())?;
    }
    for e in &raw.equations {
        equation(ctx, &mut spec, e)?;
    }
    if let Some(e) = &raw.energy {
        spec.energy = Some(super::energy::energy(ctx, &spec, e, &structure)?);
        if let (Some(t), None) = (&e.trajectory, &raw.motion) {
            return Err(
                ctx.err(t, "[energy.trajectory] compares a motion with the Lagrangian model: it needs [motion]")
            );
        }
    }
    Ok(Some(spec))
}

/// Where the first model entry starts, if there is one.
fn first_entry(raw: &RawScenario) -> Option<usize> {
    let q = raw.quantities.first().map(|q| q.name.span().start);
    let p = raw.predictions.first().map(|p| p.quantity.span().start);
    let e = raw.equations.first().map(|e| e.name.span().start);
    let u = raw.energy.as_ref().map(|u| u.potential.span().start);
    let s = raw.sensitivities.first().map(|s| s.name.span().start);
    [q, p, e, u, s].into_iter().flatten().min()
}

/// The symbols of the state: nodes, members, observed quantities, inputs, parameters and `t`
/// (a name given twice keeps its first meaning).
fn state_symbols(s: &crate::structure::Structure, m: &dyn Mechanism, params: &Values) -> Vec<Symbol> {
    let mut out: Vec<Symbol> = Vec::new();
    let mut add = |name: String, source: Source| {
        if !out.iter().any(|x| x.name == name) {
            out.push(Symbol { name, source });
        }
    };
    for n in &s.nodes {
        for (axis, c) in ["x", "y", "z"].iter().enumerate() {
            add(format!("{}.{c}", n.name), Source::Node(n.name.clone(), axis));
        }
    }
    let members = s.members_with_law().map(|(_, m)| &m.name);
    for name in members {
        add(format!("{name}.force"), Source::MemberForce(name.clone()));
        add(format!("{name}.length"), Source::MemberLength(name.clone()));
    }
    for (_, c) in s.members_of(MemberKind::Cable).filter(|(_, c)| c.is_clustered()) {
        for k in 1..c.path.len() {
            add(format!("{}.force_{k}", c.name), Source::SegmentForce(c.name.clone(), k - 1));
        }
        for k in 1..=c.friction.len() {
            add(format!("{}.slip_{k}", c.name), Source::Slip(c.name.clone(), k - 1));
        }
    }
    for (_, st) in s.rigid_struts() {
        add(format!("{}.length", st.name), Source::MemberLength(st.name.clone()));
    }
    for j in &s.joints {
        match j.kind {
            JointKind::Revolute { .. } => add(format!("{}.angle", j.name), Source::JointAngle(j.name.clone())),
            JointKind::Prismatic { .. } => add(format!("{}.slide", j.name), Source::JointSlide(j.name.clone())),
            _ => {}
        }
    }
    for q in m.quantities() {
        add(q.symbol.to_string(), Source::Observed(q.symbol.to_string()));
    }
    for i in m.inputs() {
        add(i.symbol.to_string(), Source::Input(i.symbol.to_string()));
    }
    for (k, v) in params {
        add(k.clone(), Source::Param(*v));
    }
    add("t".into(), Source::Time);
    out
}

/// A name not yet taken by a symbol of the structure or the mechanism (the file's own names
/// are checked against each other in `names.rs`).
fn new_name(ctx: &Ctx, spec: &ModelSpec, name: &Spanned<String>, what: &str) -> Result<String, ScenarioError> {
    let n = name.get_ref();
    if spec.symbols.iter().any(|s| &s.name == n) {
        return Err(ctx.err(name, format!("{what} name '{n}' is already a symbol of this scenario")));
    }
    Ok(n.clone())
}

/// An expression compiled against `symbols`, its errors located inside its string.
fn compile(ctx: &Ctx, text: &Spanned<String>, symbols: &[&str], what: &str) -> Result<Expr, ScenarioError> {
    Expr::compile(text.get_ref(), symbols).map_err(|e| expr_error(ctx, text.span().start, &e, what))
}

fn quantity(ctx: &Ctx, spec: &mut ModelSpec, q: &RawQuantity) -> Result<(), ScenarioError> {
    let name = new_name(ctx, spec, &q.name, "quantity")?;
    let expr = compile(ctx, &q.expr, &spec.names(), &format!("quantity '{name}'"))?;
    let closed_form = expr.uses().iter().all(|&u| spec.is_closed_form(u));
    spec.symbols.push(Symbol { name: name.clone(), source: Source::Quantity(spec.quantities.len()) });
    let unit = q.unit.clone().unwrap_or_else(|| "-".into());
    spec.quantities.push(Quantity { name, unit, expr, closed_form });
    Ok(())
}

/// A `[[sensitivities]]` entry: a new symbol, read at each settle point (an observed value
/// there), d(output)/d(parameter) with the output one of the state's (a node coordinate, a
/// member force, a joint coordinate, an observed quantity, a `[[quantities]]` name, or the
/// omega of mode N, `modeN.omega`) and the parameter one of the scenario's. A motion run has no
/// settle point to compute them at: refused.
fn sensitivity(
    ctx: &Ctx,
    spec: &mut ModelSpec,
    s: &RawSensitivity,
    params: &Values,
    motion: bool,
) -> Result<(), ScenarioError> {
    if motion {
        return Err(ctx.err(&s.name, "[[sensitivities]] are computed at settle points: a [motion] run has none"));
    }
    let name = new_name(ctx, spec, &s.name, "sensitivity")?;
    let p = s.parameter.get_ref();
    if !params.contains_key(p) {
        let known: Vec<&str> = params.keys().map(String::as_str).collect();
        return Err(ctx.err(
            &s.parameter,
            format!("'{p}' is not a parameter of this scenario (its parameters: {})", known.join(", ")),
        ));
    }
    let o = s.output.get_ref();
    // A sensitivity is read at the settle point beside the state, not off it: no derivative
    // of it by a parameter is computed (it had passed here and come out NaN at run time).
    if spec.sensitivities.iter().any(|x| &x.name == o) {
        return Err(ctx.err(
            &s.output,
            format!("'{o}' is another [[sensitivities]] entry, not an output of the settled state: a sensitivity of a sensitivity is not computed (its output must be a node coordinate, a member's force, a joint's angle or slide, an observed quantity, a [[quantities]] name, or modeN.omega)"),
        ));
    }
    let output = |x: &Symbol| {
        &x.name == o
            && matches!(
                x.source,
                Source::Node(..)
                    | Source::MemberForce(_)
                    | Source::JointAngle(_)
                    | Source::JointSlide(_)
                    | Source::Observed(_)
                    | Source::Quantity(_)
            )
    };
    let mode = o.strip_prefix("mode").and_then(|m| m.strip_suffix(".omega")).and_then(|n| n.parse::<usize>().ok());
    if !spec.symbols.iter().any(output) && mode.is_none_or(|n| n < 1) {
        return Err(ctx.err(
            &s.output,
            format!("'{o}' is no output of the settled state (a node coordinate such as P.x, a member's force, a joint's angle or slide, an observed quantity, a [[quantities]] name, or modeN.omega)"),
        ));
    }
    spec.symbols.push(Symbol { name: name.clone(), source: Source::Observed(name.clone()) });
    spec.sensitivities.push(Sensitivity { name, output: o.clone(), parameter: p.clone() });
    Ok(())
}

/// A prediction: its compared symbol, its formula (parameters and inputs only; in a motion run
/// time `t` too, counted from the motion's start), class and tolerance (in a motion run also
/// an optional `rms_tolerance`); its name unique among the predictions.
fn prediction(ctx: &Ctx, spec: &mut ModelSpec, p: &RawPrediction, motion: bool) -> Result<(), ScenarioError> {
    let q = p.quantity.get_ref();
    let symbol = spec.symbols.iter().position(|s| &s.name == q).ok_or_else(|| {
        let quantities: Vec<_> = spec.quantities.iter().map(|q| q.name.as_str()).collect();
        ctx.err(
            &p.quantity,
            format!(
                "unknown quantity '{q}' (the [[quantities]] here: {}; or a node coordinate NODE.x, a member's \
                 NAME.force or NAME.length, or a quantity of the mechanism)",
                if quantities.is_empty() { "none".into() } else { quantities.join(", ") }
            ),
        )
    })?;
    let name = p.name.as_ref().map_or(q.clone(), |n| n.get_ref().clone());
    if spec.predictions.iter().any(|x| x.name == name) {
        let at = p.name.as_ref().unwrap_or(&p.quantity);
        return Err(ctx.err(at, format!("two predictions named '{name}': give each a distinct name = \"...\"")));
    }
    // The formula may use parameters, inputs and quantities of those only: every other symbol
    // is hidden from it.
    // Time is offered to every formula so that its misuse outside a motion run gets its own
    // message.
    let is_time = |i: usize| spec.symbols[i].source == Source::Time;
    let closed_form: Vec<&str> = (0..spec.symbols.len())
        .map(|i| if spec.is_closed_form(i) || is_time(i) { spec.symbols[i].name.as_str() } else { "" })
        .collect();
    let what = if motion {
        format!("prediction '{name}' (parameters, inputs, their quantities and t)")
    } else {
        format!("prediction '{name}' (parameters, inputs and their quantities only)")
    };
    let formula = compile(ctx, &p.formula, &closed_form, &what)?;
    if !motion && formula.uses().iter().any(|&u| is_time(u)) {
        let at = word_offset(p.formula.get_ref(), "t").unwrap_or(0);
        return Err(ctx.err_at(
            p.formula.span().start + 1 + at,
            format!(
                "prediction '{name}' uses t, which means nothing at a settle point: time enters a prediction only in a motion run ([motion], t counted from its start)"
            ),
        ));
    }
    let rms_tolerance = match &p.rms_tolerance {
        Some(r) if !motion => {
            return Err(
                ctx.err(r, "rms_tolerance judges a prediction over a motion's ticks: it needs a [motion] section")
            )
        }
        Some(r) => Some(positive_value(ctx, r, "rms_tolerance")?),
        None => None,
    };
    let class = ErrorClass::parse(p.class.get_ref()).ok_or_else(|| {
        ctx.err(
            &p.class,
            format!("unknown class '{}' (expected one of: {})", p.class.get_ref(), ErrorClass::NAMES.join(", ")),
        )
    })?;
    let tolerance = positive_value(ctx, &p.tolerance, "tolerance")?;
    spec.predictions.push(Prediction { name, symbol, formula, class, tolerance, rms_tolerance });
    Ok(())
}

fn equation(ctx: &Ctx, spec: &mut ModelSpec, e: &RawEquation) -> Result<(), ScenarioError> {
    let name = e.name.get_ref().clone();
    if name.trim().is_empty() || spec.equations.iter().any(|x| x.name == name) {
        return Err(ctx.err(&e.name, format!("an equation needs a name of its own, got '{name}'")));
    }
    let residual = compile(ctx, &e.residual, &spec.names(), &format!("equation '{name}'"))?;
    let tolerance = positive_value(ctx, &e.tolerance, "tolerance")?;
    spec.equations.push(Equation { name, residual, tolerance });
    Ok(())
}

/// Every closed form of the model at every settle point of `actuation` (its parameters from
/// `at_point`): a prediction is a finite number (a NaN or an infinity could never be within
/// or outside its tolerance), a frequency finite and > 0. A motion run's predictions depend on
/// t and are judged on its ticks. The error is at the formula, naming the point.
pub(super) fn closed_forms_at_points(
    ctx: &Ctx,
    raw: &RawScenario,
    spec: &ModelSpec,
    at_point: &dyn Fn(&Values) -> Values,
    actuation: &Actuation,
) -> Result<(), ScenarioError> {
    let predictions = if raw.motion.is_some() { &[][..] } else { &spec.predictions[..] };
    let frequencies = spec.energy.iter().flat_map(|e| e.dynamics.iter()).flat_map(|d| &d.frequencies);
    let raw_frequencies = raw.energy.iter().flat_map(|e| &e.frequencies);
    for p in actuation.all_inputs() {
        let values = spec.values(p, &at_point(p), |_| f64::NAN);
        for (pr, r) in predictions.iter().zip(&raw.predictions) {
            let x = pr.formula.eval(&values);
            if !x.is_finite() {
                let what =
                    format!("prediction '{}' is {x} at the point {p:?}: a predicted value is a finite number", pr.name);
                return Err(ctx.err(&r.formula, what));
            }
        }
        // A formula over the solved equilibrium is judged where the model is solved.
        for (f, r) in frequencies.clone().zip(raw_frequencies.clone()).filter(|(f, _)| !f.solved) {
            let w = f.formula.eval(&values);
            if !(w.is_finite() && w > 0.0) {
                let what =
                    format!("frequency '{}' is {w} rad/s at the point {p:?}: a frequency is finite and > 0", f.name);
                return Err(ctx.err(&r.formula, what));
            }
        }
    }
    Ok(())
}

/// The byte offset of `word` standing alone in `text` (not inside a longer name), if it does.
fn word_offset(text: &str, word: &str) -> Option<usize> {
    let name_char = |c: char| c.is_alphanumeric() || c == '_' || c == '.';
    text.match_indices(word).map(|(i, _)| i).find(|&i| {
        let before = text[..i].chars().next_back().is_none_or(|c| !name_char(c));
        let after = text[i + word.len()..].chars().next().is_none_or(|c| !name_char(c));
        before && after
    })
}
