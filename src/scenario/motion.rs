//! `[motion]`: a motion run. The physical dynamics for a stated time, with no settle
//! accelerator (no static relaxation, no Newton damping schedule, no kinetic damping; joint
//! damping exactly as the structure states it), from the drawn state or from the settled one
//! (settled with the usual accelerators, which are then switched off for good), optionally
//! displaced along a named joint coordinate and given a rate of it. Its verdict comes from its
//! checks: the `[[predictions]]` judged over every tick of the motion (maximum and rms error),
//! and the natural frequencies measured from it (`[[motion.frequencies]]`). Over several points
//! (`[actuation] points`, a grid, swept parameters) the scenario is split into one motion per
//! point, each validated here with its point's parameters (`scenario/mod.rs`), run one after
//! the other and joined (`run/topologies.rs`), or in parallel by `tensegrity sweep`.
//!
//! ```toml
//! [motion]
//! duration_s = 2.0        # simulated time of the motion [s]
//! start = "drawn"         # or "settled"
//! coordinate = "pin"      # a revolute (angle, rad) or prismatic (slide, m) joint, not actuated
//! displacement = "A"      # added to its coordinate at the start (a number or an expression of the params)
//! rate = 0.0              # its rate at the start [rad/s or m/s]
//! # mode = 4, amplitude = 1e-4  # instead: along the structure's own mode 4 (as `tensegrity
//! #                             # modes` lists them), largest node displacement 1e-4 m
//! undamped = false        # true: every joint's damping released for the motion (a settle to
//!                         # the start keeps it: damped to equilibrium, then free vibration)
//! extrapolate = true      # judge the motion extrapolated over the time step (h, h/2, h/4:
//!                         # fourth order, with its own error estimate); false: rapier's steps
//!                         # (second order; a plain free body's rotation by the implicit
//!                         # midpoint rule, sim/rotation.rs). Default: true
//! target_error = 1e-12    # optional: the judged motion's error target, a fraction of its
//!                         # amplitude (the largest node excursion): the fewest levels (h ...
//!                         # h/4 to h/16: order 4 to 8) whose estimate meets it, chosen by
//!                         # running the levels first. Default: three levels, the report
//!                         # saying whether their estimate met 1e-9 of the amplitude
//! inputs = { x = "A*sin(w*t)" }  # optional: inputs as functions of the parameters and the
//!                         # motion's time t, followed at their real speed (as [actuation]
//!                         # waypoints are): each actuated joint driven through the solver
//!
//! [[motion.frequencies]]  # a natural frequency measured from the motion and predicted
//! name = "omega"
//! coordinate = "pin"      # the joint whose free vibration is fitted (or mode = N: the
//!                         # coordinate of the structure's own mode N; formula then optional,
//!                         # the modal analysis's frequency by default)
//! formula = "sqrt(L*hypot(k1*a, k2*b)/I_pivot)"  # [rad/s]: parameters, inputs, the
//!                         # mechanism's analytic quantities (ji2014's K of Eq. 42, say) and
//!                         # the [energy] model's solved equilibrium at the start (each
//!                         # coordinate there, V_a_b = d2V/da db, M_a_b): with mode = N too,
//!                         # the modal analysis is judged against the formula as well
//! tolerance = 1e-6        # relative, on the frequency corrected for the integrator
//! measure = "cosine"      # or "period": a least-squares cosine fit over every tick (exact
//!                         # for a linear oscillator, biased by the harmonics at large
//!                         # amplitude: 1e-6 relative at 0.3 rad), or the mean period between
//!                         # interpolated zero crossings of the rate (unbiased at any amplitude)
//! at_amplitude = false    # true: the formula holds at the motion's amplitude (an exact
//!                         # large-amplitude period), so the amplitude's own shift is no part
//!                         # of its error bar; by default a small-oscillation prediction
//! ```

use super::error::{finite, positive_value, Ctx, ScenarioError};
use super::number::{expr_error, Num};
use super::raw::RawScenario;
use super::Actuation;
use crate::file_model::expr::Expr;
use crate::mechanisms::{Mechanism, Values};
use crate::settings::{
    Drive, FrequencyMeasure, FrequencyPrediction, FrequencySignal, JointCoordinate, Motion, MotionStart,
};
use crate::structure::ActuatorTarget;
use crate::structure::{JointKind, Structure};
use serde::Deserialize;
use std::collections::BTreeMap;
use toml::Spanned;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMotion {
    /// Simulated time of the motion [s].
    pub(super) duration_s: Spanned<f64>,
    /// "drawn" or "settled".
    pub(super) start: Spanned<String>,
    /// A joint whose coordinate is displaced or given a rate at the start.
    pub(super) coordinate: Option<Spanned<String>>,
    /// [rad or m]: a number or an expression of the parameters.
    pub(super) displacement: Option<Spanned<Num>>,
    /// [rad/s or m/s]: a number or an expression of the parameters.
    pub(super) rate: Option<Spanned<Num>>,
    /// One of the structure's own modes (from 1, as `tensegrity modes` lists them) to displace
    /// the start along, instead of a coordinate.
    pub(super) mode: Option<Spanned<i64>>,
    /// The largest node displacement of the displacement along `mode` [m].
    pub(super) amplitude: Option<Spanned<Num>>,
    #[serde(default)]
    pub(super) frequencies: Vec<RawFrequency>,
    /// Release every joint's damping for the motion (the settle to its start keeps it).
    #[serde(default)]
    pub(super) undamped: bool,
    /// Inputs as closed forms of the parameters and the motion's time `t` [s], followed at
    /// their real speed (the others held at the single point's values).
    pub(super) inputs: Option<Spanned<BTreeMap<Spanned<String>, Spanned<String>>>>,
    /// A free body without joints started spinning (a torque-free rigid body).
    pub(super) spin: Option<Spanned<RawSpin>>,
    /// Judge the motion extrapolated over the time step (`run/levels.rs`); by default where
    /// every free body moves in joint coordinates.
    pub(super) extrapolate: Option<bool>,
    /// The judged motion's error target, a fraction of its amplitude: the levels of the
    /// extrapolation are chosen to meet it (`run/motion.rs`).
    pub(super) target_error: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSpin {
    pub(super) body: Spanned<String>,
    /// [rad/s], world frame: numbers or expressions of the parameters.
    pub(super) angular_velocity: Spanned<Vec<Spanned<Num>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawFrequency {
    pub(super) name: Spanned<String>,
    /// The joint whose coordinate's free vibration is fitted.
    pub(super) coordinate: Option<Spanned<String>>,
    /// Or the structure's own mode (from 1) whose coordinate is fitted.
    pub(super) mode: Option<Spanned<i64>>,
    /// The predicted angular frequency [rad/s]: a closed form of the parameters, inputs and
    /// analytic quantities; optional with `mode` (then the modal analysis's frequency).
    pub(super) formula: Option<Spanned<String>>,
    /// Relative, on the corrected measured frequency.
    pub(super) tolerance: Spanned<f64>,
    /// "cosine" (the default) or "period": how the frequency is measured from the motion.
    pub(super) measure: Option<Spanned<String>>,
    /// The formula holds at the motion's amplitude (not only as it vanishes): the amplitude's
    /// own shift is no error of it. Default false (a small-oscillation prediction).
    pub(super) at_amplitude: Option<bool>,
}

/// The validated `[motion]` section, or None without one. `first` is the structure at the first
/// point; a motion run holds its single point's inputs. `solved`: the names of the energy
/// model's solved equilibrium that a frequency formula may read (`file_model::dynamics`).
pub(super) fn motion(
    ctx: &Ctx,
    raw: &RawScenario,
    dt_s: f64,
    (mech, first): (&dyn Mechanism, &Structure),
    (params, solved): (&Values, &[String]),
    actuation: &Actuation,
) -> Result<Option<Motion>, ScenarioError> {
    let Some(m) = &raw.motion else { return Ok(None) };
    let section = m.get_ref();
    let drive = drive(ctx, raw, actuation, first, params)?;
    settle_only_sections(ctx, raw)?;
    let duration_s = positive_value(ctx, &section.duration_s, "motion.duration_s")?;
    let steps = (duration_s / dt_s).round();
    if steps.is_nan() || steps > super::MAX_STEPS_PER_SETTLE {
        return Err(ctx.err(
            &section.duration_s,
            format!(
                "motion.duration_s / sim.dt = {duration_s} / {dt_s} s is {steps:e} time steps; at most {:e} (a shorter motion or a longer dt)",
                super::MAX_STEPS_PER_SETTLE
            ),
        ));
    }
    if steps < 1.0 {
        return Err(ctx.err(&section.duration_s, format!("motion.duration_s must be at least sim.dt = {dt_s} s")));
    }
    let start = match section.start.get_ref().as_str() {
        "drawn" => MotionStart::Drawn,
        "settled" => MotionStart::Settled,
        other => {
            return Err(
                ctx.err(&section.start, format!("motion.start must be \"drawn\" or \"settled\", got \"{other}\""))
            )
        }
    };
    let mode = displaced_mode(ctx, m, first, params)?;
    let coordinate = displaced(ctx, m, first, params)?;
    let inputs = actuation.first_inputs();
    let frequencies = section
        .frequencies
        .iter()
        .map(|f| frequency(ctx, f, (mech, first), (params, inputs), solved))
        .collect::<Result<_, _>>()?;
    let undamped = section.undamped;
    let extrapolate = section.extrapolate;
    let target_error = target_error(ctx, section)?;
    let spin = section.spin.as_ref().map(|sp| spin(ctx, sp, (first, params), dt_s)).transpose()?;
    Ok(Some(Motion {
        duration_s,
        steps: steps as u64,
        start,
        coordinate,
        mode,
        frequencies,
        undamped,
        drive,
        spin,
        extrapolate,
        target_error,
    }))
}

/// `target_error`, a fraction in (0, 1) of the motion's amplitude, on an extrapolated motion.
fn target_error(ctx: &Ctx, section: &RawMotion) -> Result<Option<f64>, ScenarioError> {
    let Some(t) = &section.target_error else { return Ok(None) };
    let value = *t.get_ref();
    if !(value > 0.0 && value < 1.0) {
        return Err(ctx.err(
            t,
            format!("motion.target_error is a fraction of the motion's amplitude, above 0 and below 1; got {value}"),
        ));
    }
    if section.extrapolate == Some(false) {
        return Err(ctx
            .err(t, "motion.target_error chooses the levels of an extrapolated motion: not with extrapolate = false"));
    }
    Ok(Some(value))
}

/// What a motion run's inputs do: held at its single point (`points` with one point), or
/// followed in time at their real speed (`waypoints`, or the point with `[motion] inputs`).
fn drive(
    ctx: &Ctx,
    raw: &RawScenario,
    actuation: &Actuation,
    s: &Structure,
    params: &Values,
) -> Result<Option<Drive>, ScenarioError> {
    let functions = raw.motion.as_ref().and_then(|m| m.get_ref().inputs.as_ref());
    let drive = match (actuation, functions) {
        (Actuation::Points { points, .. }, None) if points.len() == 1 => return Ok(None),
        (Actuation::Points { points, .. }, Some(f)) if points.len() == 1 => input_functions(ctx, f, &points[0], params)?,
        (Actuation::Schedule { waypoints }, None) => Drive::Waypoints(waypoints.clone()),
        (Actuation::Schedule { .. }, Some(f)) => {
            return Err(ctx.err(f, "a motion follows [actuation] waypoints or [motion] inputs, not both"))
        }
        _ => {
            return Err(ctx.err(
                &raw.actuation,
                "a motion run ([motion]) holds one set of inputs ([actuation] points = [ { ... } ] with one point) or follows waypoints",
            ))
        }
    };
    let at = functions.map_or(raw.actuation.span(), |f| f.span());
    if let Some(a) = s.actuators.iter().find(|a| matches!(a.target, ActuatorTarget::FixedNode { .. })) {
        return Err(ctx.err_at(
            at.start,
            format!(
                "actuator '{}' moves a fixed node, which a motion cannot follow physically (a fixed body has no velocity to carry its members and joints): drive joints or cable lengths",
                a.symbol
            ),
        ));
    }
    Ok(Some(drive))
}

/// `[motion] inputs = { SYMBOL = "formula of the parameters and t" }`: each an input of the
/// point, compiled and finite at the start.
fn input_functions(
    ctx: &Ctx,
    f: &Spanned<BTreeMap<Spanned<String>, Spanned<String>>>,
    point: &Values,
    params: &Values,
) -> Result<Drive, ScenarioError> {
    let mut symbols: Vec<String> = params.keys().cloned().collect();
    symbols.push("t".into());
    let names: Vec<&str> = symbols.iter().map(String::as_str).collect();
    let mut functions = Vec::new();
    for (name, text) in f.get_ref() {
        if !point.contains_key(name.get_ref()) {
            let known: Vec<&str> = point.keys().map(String::as_str).collect();
            return Err(
                ctx.err(name, format!("unknown input '{}' (the point's inputs: {})", name.get_ref(), known.join(", ")))
            );
        }
        let what = format!("motion input '{}' (parameters and t)", name.get_ref());
        let e = Expr::compile(text.get_ref(), &names).map_err(|e| expr_error(ctx, text.span().start, &e, &what))?;
        let at_start = e.eval(&symbols.iter().map(|s| params.get(s).copied().unwrap_or(0.0)).collect::<Vec<_>>());
        if !at_start.is_finite() {
            return Err(ctx.err(text, format!("{what} is {at_start} at t = 0, not a finite number")));
        }
        functions.push((name.get_ref().clone(), e));
    }
    if functions.is_empty() {
        return Err(ctx.err(f, "motion.inputs names no input: give { SYMBOL = \"formula of t\" } or remove it"));
    }
    Ok(Drive::Functions { held: point.clone(), functions, symbols })
}

/// Sections that judge settle points by perturbing or probing them, or a sweep's agreement:
/// they have no meaning in a motion run.
fn settle_only_sections(ctx: &Ctx, raw: &RawScenario) -> Result<(), ScenarioError> {
    let motion = raw.motion.as_ref().expect("a motion run");
    let at = |what: &str| {
        ctx.err(
            motion,
            format!("[{what}] perturbs, probes or sweeps settled states; a motion run ([motion]) does not: remove one of them"),
        )
    };
    if raw.stability.is_some() {
        return Err(at("stability"));
    }
    if raw.probe.is_some() {
        return Err(at("probe"));
    }
    if raw.workspace.is_some() {
        return Err(at("workspace"));
    }
    Ok(())
}

/// The displaced coordinate of `[motion]`, with its displacement and rate.
fn displaced(
    ctx: &Ctx,
    m: &Spanned<RawMotion>,
    s: &Structure,
    params: &Values,
) -> Result<Option<(JointCoordinate, f64, f64)>, ScenarioError> {
    let section = m.get_ref();
    let Some(name) = &section.coordinate else {
        if let Some(v) = section.displacement.as_ref().or(section.rate.as_ref()) {
            return Err(
                ctx.err(v, "a displacement or a rate needs coordinate = \"JOINT\" (a revolute or prismatic joint)")
            );
        }
        return Ok(None);
    };
    if section.displacement.is_none() && section.rate.is_none() {
        return Err(ctx.err(name, "coordinate needs a displacement (rad or m) or a rate (rad/s or m/s), or both"));
    }
    let joint = joint_coordinate(ctx, name, s)?;
    let number = |v: &Option<Spanned<Num>>, what: &str| match v {
        None => Ok(0.0),
        Some(v) => param_number(ctx, v, params, what),
    };
    let displacement = number(&section.displacement, "motion.displacement")?;
    let rate = number(&section.rate, "motion.rate")?;
    Ok(Some((joint, displacement, rate)))
}

/// The structure's own mode `[motion] mode` (from 1) to displace the start along, and the
/// largest node displacement `amplitude` [m]; not with `coordinate`.
fn displaced_mode(
    ctx: &Ctx,
    m: &Spanned<RawMotion>,
    s: &Structure,
    params: &Values,
) -> Result<Option<(usize, f64)>, ScenarioError> {
    let section = m.get_ref();
    let (mode, amplitude) = match (&section.mode, &section.amplitude) {
        (None, None) => return Ok(None),
        (Some(mode), Some(amplitude)) => (mode, amplitude),
        (Some(mode), None) => return Err(ctx.err(mode, "mode needs an amplitude: the largest node displacement [m]")),
        (None, Some(a)) => {
            return Err(ctx.err(a, "amplitude is the largest node displacement along a mode: it needs mode = N"))
        }
    };
    if let Some(c) = &section.coordinate {
        return Err(ctx.err(c, "a motion starts displaced along a coordinate or along a mode, not both"));
    }
    let index = mode_index(ctx, mode, s)?;
    let amplitude = param_number(ctx, amplitude, params, "motion.amplitude")?;
    Ok(Some((index, amplitude)))
}

/// A mode of the structure's own modal analysis (from 1 in the file, from 0 here): at most six
/// per free body, or one per coordinate of a free (not actuated) joint of a jointed structure
/// (a ball joint's three, a universal joint's two: issue 62 item 1 had counted one per joint).
fn mode_index(ctx: &Ctx, mode: &Spanned<i64>, s: &Structure) -> Result<usize, ScenarioError> {
    // Point masses' turns are no modes, and their bodies count apart (`structure::modal_bodies`).
    let (bodies, points) = crate::structure::modal_bodies(s);
    let count = if s.joints.is_empty() {
        (6 * bodies - 3 * points) as i64
    } else {
        let actuated = |j: usize| s.actuators.iter().any(|a| a.target == crate::structure::ActuatorTarget::Joint(j));
        // Free bodies beside the joint trees add their own six coordinates (a point mass three).
        let point = crate::structure::lumped::point_masses(s);
        let loose: usize = s.unjointed_free_bodies().into_iter().map(|b| if point[b] { 3 } else { 6 }).sum();
        let joints: usize =
            (0..s.joints.len()).filter(|j| !actuated(*j)).map(|j| s.joints[j].kind.coordinate_count()).sum();
        (joints + loose) as i64
    };
    let most_points = crate::structure::MAX_SPARSE_MODAL_POINT_MASSES;
    if points > most_points {
        let message = format!(
            "mode {}: the structure has {points} point masses, and its modes are computed for at most {most_points}",
            mode.get_ref()
        );
        return Err(ctx.err(mode, message));
    }
    let free = bodies - points;
    let most = crate::structure::modal_free_body_bound(s);
    if free > most {
        let what = if crate::structure::modes_of_free_bodies(s) {
            "the lowest modes of free bodies on springs and elastic cables are computed"
        } else {
            "its modes are a dense eigenproblem solved"
        };
        return Err(ctx.err(
            mode,
            format!("mode {}: the structure has {free} free bodies, and {what} for at most {most}", mode.get_ref()),
        ));
    }
    let m = *mode.get_ref();
    if !(1..=count).contains(&m) {
        return Err(ctx.err(mode, format!("mode {m} does not exist: the structure has {count} (from 1)")));
    }
    Ok(m as usize - 1)
}

/// A revolute or prismatic joint of `s`, not driven by an actuator, by name.
fn joint_coordinate(ctx: &Ctx, name: &Spanned<String>, s: &Structure) -> Result<JointCoordinate, ScenarioError> {
    let index = s.joints.iter().position(|j| &j.name == name.get_ref()).ok_or_else(|| {
        let names: Vec<&str> = s
            .joints
            .iter()
            .filter(|j| matches!(j.kind, JointKind::Revolute { .. } | JointKind::Prismatic { .. }))
            .map(|j| j.name.as_str())
            .collect();
        ctx.err(
            name,
            format!(
                "unknown coordinate '{}': a motion coordinate is a revolute or prismatic joint's (the structure's: {})",
                name.get_ref(),
                if names.is_empty() { "none".into() } else { names.join(", ") }
            ),
        )
    })?;
    let prismatic = match s.joints[index].kind {
        JointKind::Revolute { .. } => false,
        JointKind::Prismatic { .. } => true,
        _ => {
            return Err(ctx.err(
                name,
                format!("joint '{}' has no single coordinate: a revolute or prismatic joint is needed", name.get_ref()),
            ))
        }
    };
    if s.actuators.iter().any(|a| a.target == crate::structure::ActuatorTarget::Joint(index)) {
        return Err(
            ctx.err(name, format!("joint '{}' is actuated: its coordinate is commanded, not free", name.get_ref()))
        );
    }
    Ok(JointCoordinate { joint: name.get_ref().clone(), index, prismatic })
}

/// The largest turn of a body in one time step that rapier keeps \[rad\]: it caps every body's
/// angular speed at this over `sim.dt` (`staged_island_solver::worker`'s `MAX_ROTATION`), in
/// silence (spins from 1e10 to 1e154 rad/s had all peaked at one kinetic energy).
pub const MAX_TURN_PER_STEP_RAD: f64 = std::f64::consts::FRAC_PI_4;

/// `[motion] spin`: a free body that no joint holds, by name, and its angular velocity
/// \[rad/s\] (world frame, three finite numbers, at most [`MAX_TURN_PER_STEP_RAD`] / `dt_s`).
fn spin(
    ctx: &Ctx,
    sp: &Spanned<RawSpin>,
    (s, params): (&Structure, &Values),
    dt_s: f64,
) -> Result<(usize, String, [f64; 3]), ScenarioError> {
    let raw = sp.get_ref();
    let name = raw.body.get_ref();
    let b = s.bodies.iter().position(|b| &b.name == name).ok_or_else(|| {
        let names: Vec<&str> = s.bodies.iter().map(|b| b.name.as_str()).collect();
        ctx.err(&raw.body, format!("unknown body '{name}' (the structure's: {})", names.join(", ")))
    })?;
    if s.bodies[b].kind != crate::structure::BodyKind::Free {
        return Err(ctx.err(&raw.body, format!("body '{name}' is fixed: only a free body can spin")));
    }
    if s.joints.iter().any(|j| j.parent == b || j.child == b) {
        return Err(
            ctx.err(&raw.body, format!("body '{name}' is held by a joint: a spin starts a body without joints"))
        );
    }
    let w = raw.angular_velocity.get_ref();
    if w.len() != 3 {
        return Err(ctx.err(
            &raw.angular_velocity,
            format!("angular_velocity is [wx, wy, wz] in rad/s, got {} numbers", w.len()),
        ));
    }
    let mut out = [0.0; 3];
    for (o, c) in out.iter_mut().zip(w) {
        *o = param_number(ctx, c, params, "motion.spin.angular_velocity")?;
    }
    let (speed, most) = (crate::structure::norm(out), MAX_TURN_PER_STEP_RAD / dt_s);
    if speed.is_nan() || speed > most {
        return Err(ctx.err(
            &raw.angular_velocity,
            format!("angular_velocity of magnitude {speed:e} rad/s: the simulator keeps at most pi/4 rad a step, {most:e} rad/s at sim.dt = {dt_s} s (rapier would clamp the spin in silence)"),
        ));
    }
    Ok((b, name.clone(), out))
}

/// A number, or an expression of the parameters evaluated with their values; finite.
fn param_number(ctx: &Ctx, v: &Spanned<Num>, params: &Values, what: &str) -> Result<f64, ScenarioError> {
    match v.get_ref() {
        Num::Value(_) => finite(ctx, v, what),
        Num::Expr(text) => {
            let names: Vec<&str> = params.keys().map(String::as_str).collect();
            let e = Expr::compile(text, &names).map_err(|e| expr_error(ctx, v.span().start, &e, what))?;
            let x = e.eval(&params.values().copied().collect::<Vec<_>>());
            if x.is_finite() {
                Ok(x)
            } else {
                Err(ctx.err(v, format!("{what} = \"{text}\" is {x}, not a finite number")))
            }
        }
    }
}

/// A `[[motion.frequencies]]` entry: its joint or mode, its formula of the parameters, the
/// inputs, the mechanism's analytic quantities and the energy model's solved equilibrium
/// (`solved`; checked finite and positive where the mechanism predicts them at the first
/// point, unless it reads the solved equilibrium; optional for a mode).
fn frequency(
    ctx: &Ctx,
    f: &RawFrequency,
    (mech, s): (&dyn Mechanism, &Structure),
    (params, inputs): (&Values, &Values),
    solved: &[String],
) -> Result<FrequencyPrediction, ScenarioError> {
    let name = f.name.get_ref().clone();
    if name.trim().is_empty() {
        return Err(ctx.err(&f.name, "a frequency needs a name"));
    }
    let signal = match (&f.coordinate, &f.mode) {
        (Some(c), None) => FrequencySignal::Joint(joint_coordinate(ctx, c, s)?),
        (None, Some(m)) => FrequencySignal::Mode(mode_index(ctx, m, s)?),
        _ => {
            return Err(ctx.err(
                &f.name,
                format!("frequency '{name}' is fitted to a coordinate = \"JOINT\" or to a mode = N: one of them"),
            ))
        }
    };
    let mut symbols: Vec<String> = params.keys().chain(inputs.keys()).cloned().collect();
    for q in mech.quantities() {
        if !symbols.iter().any(|s| s == q.symbol) {
            symbols.push(q.symbol.to_string());
        }
    }
    let known = symbols.len();
    symbols.extend(solved.iter().filter(|n| !symbols.contains(n)).cloned().collect::<Vec<_>>());
    let tolerance = positive_value(ctx, &f.tolerance, "tolerance")?;
    let measure = measure(ctx, f.measure.as_ref())?;
    let Some(text) = &f.formula else {
        if let FrequencySignal::Joint(_) = signal {
            return Err(ctx.err(&f.name, format!("frequency '{name}' of a joint needs a formula [rad/s]")));
        }
        let at_amplitude = false;
        return Ok(FrequencyPrediction { name, signal, measure, formula: None, symbols, tolerance, at_amplitude });
    };
    let names: Vec<&str> = symbols.iter().map(String::as_str).collect();
    let what = format!(
        "frequency '{name}' (parameters, inputs, the mechanism's quantities and the [energy] model's solved equilibrium)"
    );
    let formula = Expr::compile(text.get_ref(), &names).map_err(|e| expr_error(ctx, text.span().start, &e, &what))?;
    let reads_solved = formula.uses().iter().any(|&i| i >= known);
    let at_amplitude = f.at_amplitude.unwrap_or(false);
    let p = FrequencyPrediction { name, signal, measure, formula: Some(formula), symbols, tolerance, at_amplitude };
    let Ok(prediction) = mech.predict(params, inputs) else { return Ok(p) };
    if reads_solved {
        return Ok(p); // judged once the energy model is solved at the motion's start
    }
    let w = p.predicted(params, inputs, &prediction.expected, &Values::new()).unwrap_or(f64::NAN);
    if !(w.is_finite() && w > 0.0) {
        return Err(ctx.err(text, format!("frequency '{}' is {w} rad/s here; a frequency is finite and > 0", p.name)));
    }
    Ok(p)
}

/// `measure = "cosine"` (the default without it) or `"period"`.
pub(super) fn measure(ctx: &Ctx, m: Option<&Spanned<String>>) -> Result<FrequencyMeasure, ScenarioError> {
    let Some(m) = m else { return Ok(FrequencyMeasure::default()) };
    match m.get_ref().as_str() {
        "cosine" => Ok(FrequencyMeasure::Cosine),
        "period" => Ok(FrequencyMeasure::Period),
        other => Err(ctx.err(
            m,
            format!("measure must be \"cosine\" (a least-squares cosine fit) or \"period\" (zero crossings of the rate), got \"{other}\""),
        )),
    }
}
