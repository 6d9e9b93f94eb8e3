//! `[energy] kinetic` and `[[energy.frequencies]]`: the file's dynamic model, compiled with the
//! mass matrix d2T/dq'2, dT/dq and d2T/dq'dq (forward derivatives, exact to round-off) into a [`Dynamics`]. Errors, located:
//! a symbol of the simulated state in T, a coordinate whose rate T lacks, a mass matrix that
//! depends on the rates (T not quadratic in them) or, where it is constant, is not positive
//! definite (both probed with the parameters' values); frequencies without a kinetic energy, a mode out of range.

use super::error::{positive_value, Ctx, ScenarioError};
use super::number::expr_error;
use super::raw::{RawEnergy, RawFrequency, RawTrajectory};
use crate::file_model::dynamics::{Dynamics, FrequencyPrediction, TrajectoryCheck, TrajectoryStart, RATE_SUFFIX};
use crate::file_model::energy_model::Coordinate;
use crate::file_model::expr::Expr;
use crate::file_model::spec::ModelSpec;
use toml::Spanned;

/// The compiled dynamic model, or None when `[energy]` states no kinetic energy.
pub(super) fn dynamics(
    ctx: &Ctx,
    spec: &ModelSpec,
    raw: &RawEnergy,
    coordinates: &[Coordinate],
) -> Result<Option<Dynamics>, ScenarioError> {
    let Some(text) = &raw.kinetic else {
        if let Some(f) = raw.frequencies.first() {
            return Err(ctx.err(&f.name, "[[energy.frequencies]] needs a kinetic energy: [energy] kinetic = \"...\""));
        }
        if let Some(t) = &raw.trajectory {
            return Err(ctx.err(t, "[energy.trajectory] needs a kinetic energy: [energy] kinetic = \"...\""));
        }
        return Ok(None);
    };
    let state = spec.names();
    let (first, n) = (state.len(), coordinates.len());
    let rates = rate_names(ctx, spec, raw, coordinates)?;
    let mut names: Vec<&str> = state.clone();
    names.extend(coordinates.iter().map(|c| c.name.as_str()));
    names.extend(rates.iter().map(String::as_str));
    let at = text.span().start;
    let what = "energy kinetic (coordinates, their rates NAME_dot, parameters, inputs and their quantities)";
    let kinetic = Expr::compile(text.get_ref(), &names).map_err(|e| expr_error(ctx, at, &e, what))?;
    if let Some(&u) = kinetic.uses().iter().find(|&&u| u < first && !spec.is_closed_form(u)) {
        return Err(located(ctx, text, state[u], format!("{what}: '{}' is a symbol of the simulated state", state[u])));
    }
    let first_rate = first + n;
    if let Some(i) = (0..n).find(|i| !kinetic.uses().contains(&(first_rate + i))) {
        return Err(ctx.err(
            text,
            format!(
                "energy kinetic has no term in '{}', the rate of coordinate '{}': every coordinate needs one (else \
                 the mass matrix is singular)",
                rates[i], coordinates[i].name
            ),
        ));
    }
    let d = |e: &Expr, s: usize| e.derivative(s).map_err(|e| expr_error(ctx, at, &e, "energy kinetic"));
    let momenta: Vec<Expr> = (0..n).map(|i| d(&kinetic, first_rate + i)).collect::<Result<_, _>>()?;
    let (mut mass, mut mixed) = (Vec::with_capacity(n * n), Vec::with_capacity(n * n));
    for p in &momenta {
        for j in 0..n {
            mass.push(d(p, first_rate + j)?);
            mixed.push(d(p, first + j)?);
        }
    }
    mass_checks(ctx, spec, text, &mass, n)?;
    let kinetic_gradient = (0..n).map(|j| d(&kinetic, first + j)).collect::<Result<_, _>>()?;
    let frequencies = frequencies(ctx, spec, &raw.frequencies, coordinates)?;
    let trajectory = raw.trajectory.as_ref().map(|t| trajectory(ctx, t.get_ref())).transpose()?;
    Ok(Some(Dynamics { kinetic, mass, kinetic_gradient, mixed, first_rate, frequencies, trajectory }))
}

/// `[energy.trajectory]`: its tolerances, positive, and its start (one of
/// [`TrajectoryStart::NAMES`], "samples" when absent).
fn trajectory(ctx: &Ctx, raw: &RawTrajectory) -> Result<TrajectoryCheck, ScenarioError> {
    let tolerance = positive_value(ctx, &raw.tolerance, "energy.trajectory.tolerance")?;
    let rms_tolerance =
        raw.rms_tolerance.as_ref().map(|t| positive_value(ctx, t, "energy.trajectory.rms_tolerance")).transpose()?;
    let start = match &raw.start {
        None => TrajectoryStart::default(),
        Some(s) => TrajectoryStart::parse(s.get_ref()).ok_or_else(|| {
            let expected = TrajectoryStart::NAMES.join(", ");
            ctx.err(s, format!("unknown energy.trajectory.start '{}' (expected one of: {expected})", s.get_ref()))
        })?,
    };
    let measure = super::motion::measure(ctx, raw.measure.as_ref())?;
    Ok(TrajectoryCheck { tolerance, rms_tolerance, start, measure })
}

/// An error at the first place `name` appears as a whole symbol in the expression `text` (not
/// inside a longer name; else at the string's start).
fn located(ctx: &Ctx, text: &Spanned<String>, name: &str, message: String) -> ScenarioError {
    let quote = 1;
    let t = text.get_ref();
    let symbol_char = |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '.');
    let whole = t
        .match_indices(name)
        .map(|(i, _)| i)
        .find(|&i| !symbol_char(t[..i].chars().next_back()) && !symbol_char(t[i + name.len()..].chars().next()));
    match whole {
        Some(i) => ctx.err_at(text.span().start + quote + i, message),
        None => ctx.err(text, message),
    }
}

/// Each coordinate's rate name, `NAME_dot`: new among the scenario's symbols and coordinates.
fn rate_names(
    ctx: &Ctx,
    spec: &ModelSpec,
    raw: &RawEnergy,
    coordinates: &[Coordinate],
) -> Result<Vec<String>, ScenarioError> {
    let mut out = Vec::new();
    for (c, rc) in coordinates.iter().zip(&raw.coordinates) {
        let rate = format!("{}{RATE_SUFFIX}", c.name);
        if spec.symbols.iter().any(|s| s.name == rate) || coordinates.iter().any(|x| x.name == rate) {
            return Err(ctx.err(
                &rc.name,
                format!("the rate of coordinate '{}' would be '{rate}', which is already a symbol here", c.name),
            ));
        }
        out.push(rate);
    }
    Ok(out)
}

/// Two probe states at which the mass matrix is evaluated when the file is read: every
/// coordinate at one of these values [rad or m], every rate at [`PROBE_RATE`] or zero.
const PROBE_COORDINATES: [f64; 2] = [0.3, 0.7];
const PROBE_RATE: f64 = 1.3;
/// Two evaluations of the mass matrix closer than this (relative) are the same.
const SAME_MASS_REL: f64 = 1e-12;

/// The mass matrix evaluated with the parameters (inputs unknown: NaN), the coordinates at
/// `q` and the rates at `v`.
fn mass_at(spec: &ModelSpec, mass: &[Expr], n: usize, q: f64, v: f64) -> nalgebra::DMatrix<f64> {
    let mut values = spec.values(&Default::default(), &Default::default(), |_| f64::NAN);
    values.extend(std::iter::repeat_n(q, n).chain(std::iter::repeat_n(v, n)));
    nalgebra::DMatrix::from_fn(n, n, |i, j| mass[i * n + j].eval(&values))
}

/// The mass matrix d2T/dq'2, probed where the parameters alone define it: it must not depend on
/// the rates (T quadratic in them), and where it is constant it must be positive definite.
/// Elsewhere (it depends on the coordinates or inputs) it is checked at every settle point.
fn mass_checks(
    ctx: &Ctx,
    spec: &ModelSpec,
    text: &Spanned<String>,
    mass: &[Expr],
    n: usize,
) -> Result<(), ScenarioError> {
    let [qa, qb] = PROBE_COORDINATES;
    let (at_rest, moving, elsewhere) =
        (mass_at(spec, mass, n, qa, 0.0), mass_at(spec, mass, n, qa, PROBE_RATE), mass_at(spec, mass, n, qb, 0.0));
    let finite = |m: &nalgebra::DMatrix<f64>| m.iter().all(|x| x.is_finite());
    let same = |a: &nalgebra::DMatrix<f64>, b: &nalgebra::DMatrix<f64>| {
        (a - b).amax() <= SAME_MASS_REL * a.amax().max(b.amax())
    };
    if finite(&at_rest) && finite(&moving) && !same(&at_rest, &moving) {
        return Err(ctx.err(
            text,
            "energy kinetic must be quadratic in the rates (T = q'^T M(q) q' / 2): its second derivative in the \
             rates changes with them",
        ));
    }
    if !(finite(&at_rest) && finite(&elsewhere) && same(&at_rest, &elsewhere)) {
        return Ok(());
    }
    if crate::eigen::is_positive_definite(&at_rest) {
        return Ok(());
    }
    let eigenvalues: Vec<String> =
        nalgebra::SymmetricEigen::new(at_rest).eigenvalues.iter().map(|e| format!("{e:.6e}")).collect();
    Err(ctx.err(
        text,
        format!(
            "energy kinetic is not positive definite: its mass matrix d2T/dq'2 has the eigenvalues [{}] (every one \
             must be > 0)",
            eigenvalues.join(", ")
        ),
    ))
}

/// `[[energy.frequencies]]`: a unique name, a closed form, a mode from 1 to n, a tolerance.
fn frequencies(
    ctx: &Ctx,
    spec: &ModelSpec,
    raw: &[RawFrequency],
    coordinates: &[Coordinate],
) -> Result<Vec<FrequencyPrediction>, ScenarioError> {
    let n = coordinates.len();
    let solved = crate::file_model::dynamics::solved_names(coordinates, true);
    let closed: Vec<&str> = (0..spec.symbols.len())
        .map(|i| if spec.is_closed_form(i) { spec.symbols[i].name.as_str() } else { "" })
        .chain(solved.iter().map(String::as_str))
        .collect();
    let mut out: Vec<FrequencyPrediction> = Vec::new();
    for f in raw {
        let name = f.name.get_ref().clone();
        if name.trim().is_empty() || out.iter().any(|x| x.name == name) {
            return Err(ctx.err(&f.name, format!("a frequency needs a name of its own, got '{name}'")));
        }
        let what = format!(
            "frequency '{name}' (parameters, inputs, their quantities, and the solved equilibrium: the coordinates, V_a_b, M_a_b)"
        );
        let formula = Expr::compile(f.formula.get_ref(), &closed)
            .map_err(|e| expr_error(ctx, f.formula.span().start, &e, &what))?;
        let mode = *f.mode.get_ref();
        if mode < 1 || mode > n as i64 {
            return Err(ctx.err(&f.mode, format!("mode must be from 1 to {n} (the number of coordinates), got {mode}")));
        }
        let tolerance = positive_value(ctx, &f.tolerance, "tolerance")?;
        let solved = formula.uses().iter().any(|&i| i >= spec.symbols.len());
        out.push(FrequencyPrediction { name, formula, solved, mode: mode as usize - 1, tolerance });
    }
    Ok(out)
}
