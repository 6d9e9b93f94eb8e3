//! `[energy]`: a potential in named coordinates, compiled with its gradient and
//! Hessian (forward derivatives) into an [`EnergySpec`]; each coordinate with how it is read off the settled state;
//! its kinetic energy and frequency predictions in `kinetic.rs`.

use super::error::{finite, positive_value, Ctx, ScenarioError};
use super::number::expr_error;
use super::raw::{RawCoordinate, RawEnergy, RawRange};
use crate::file_model::energy_model::{Coordinate, EnergySpec};
use crate::file_model::expr::{Expr, ExprError};
use crate::file_model::spec::{ErrorClass, ModelSpec, Source};
use crate::structure::BodyKind;
use toml::Spanned;

/// Largest number of Newton starts the scans may ask for together (the product of their
/// counts across coordinates: two scans of 10,000 had taken 3.4 GB).
const MAX_SCAN: i64 = 10_000;

/// Largest number of coordinates of a potential: its Hessian has their square of
/// derivatives, each evaluated at every Newton step of every start.
const MAX_COORDINATES: usize = 20;

/// The compiled `[energy]` section of a model whose other sections are in `spec`, of the
/// structure `s` (drawn at the first point: whose nodes are on fixed bodies).
pub(super) fn energy(
    ctx: &Ctx,
    spec: &ModelSpec,
    raw: &RawEnergy,
    s: &crate::structure::Structure,
) -> Result<EnergySpec, ScenarioError> {
    if raw.coordinates.is_empty() {
        return Err(
            ctx.err(&raw.potential, "[energy] needs at least one [[energy.coordinates]] (name, measured, class)")
        );
    }
    if let Some(c) = raw.coordinates.get(MAX_COORDINATES) {
        return Err(ctx.err(&c.name, format!("[energy] has at most {MAX_COORDINATES} coordinates")));
    }
    let state = spec.names();
    let mut coordinates = Vec::new();
    let mut starts: i64 = 1;
    for c in &raw.coordinates {
        coordinates.push(coordinate(ctx, &state, c)?);
        if let Some(s) = &c.scan {
            starts = starts.saturating_mul(*s.get_ref().count.get_ref());
            if starts > MAX_SCAN {
                return Err(ctx.err(
                    &s.get_ref().count,
                    format!("the scans ask for {starts} Newton starts together (the product of their counts); at most {MAX_SCAN}"),
                ));
            }
        }
    }
    // The potential sees the closed forms (parameters, inputs, their quantities), the nodes of
    // fixed bodies (which stay where they are drawn) and the coordinates.
    let anchored = |i: usize| match &spec.symbols[i].source {
        Source::Node(n, _) => s.node_id(n).is_some_and(|k| s.bodies[s.nodes[k].body].kind == BodyKind::Fixed),
        _ => false,
    };
    let mut names: Vec<&str> =
        (0..state.len()).map(|i| if spec.is_closed_form(i) || anchored(i) { state[i] } else { "" }).collect();
    names.extend(coordinates.iter().map(|c: &Coordinate| c.name.as_str()));
    let at = raw.potential.span().start;
    let potential = Expr::compile(raw.potential.get_ref(), &names).map_err(|e| {
        let e = on_free_body(e, s);
        expr_error(ctx, at, &e, "energy potential (coordinates, parameters, inputs, their quantities, fixed nodes)")
    })?;
    let first = state.len();
    let derivative =
        |e: &Expr, i: usize| e.derivative(first + i).map_err(|e| expr_error(ctx, at, &e, "energy potential"));
    let n = coordinates.len();
    let gradient: Vec<Expr> = (0..n).map(|i| derivative(&potential, i)).collect::<Result<_, _>>()?;
    let mut hessian = Vec::with_capacity(n * n);
    for g in &gradient {
        for j in 0..n {
            hessian.push(derivative(g, j)?);
        }
    }
    scan_work(ctx, raw, &coordinates, &gradient, &hessian)?;
    let tolerance = positive_value(ctx, &raw.tolerance, "energy.tolerance")?;
    let dynamics = super::kinetic::dynamics(ctx, spec, raw, &coordinates)?;
    Ok(EnergySpec { potential, gradient, hessian, coordinates, first_coordinate: first, tolerance, dynamics })
}

/// An unknown symbol that is a coordinate of a free body's node, said so.
fn on_free_body(mut e: ExprError, s: &crate::structure::Structure) -> ExprError {
    let name = e.message.strip_prefix("unknown symbol '").and_then(|m| m.split('\'').next()).unwrap_or("");
    let node = name.rsplit_once('.').filter(|(_, c)| ["x", "y", "z"].contains(c)).map(|(n, _)| n);
    if let Some(k) = node.and_then(|n| s.node_id(n)) {
        if s.bodies[s.nodes[k].body].kind == BodyKind::Free {
            e.message = format!(
                "node '{}' is on the free body '{}': the potential reads the nodes of fixed bodies only, where they \
                 are drawn (a moving node is a coordinate's job)",
                s.nodes[k].name, s.bodies[s.nodes[k].body].name
            );
        }
    }
    e
}

/// Largest work of the scans at one settle point: the Newton starts times the bytes of the
/// gradient and Hessian that each Newton step evaluates. Measured: 10,000 starts of a
/// two-coordinate potential of 11 squared sines (8,437 bytes: 84 million) took 4.5 s a settle
/// point, which a signal had to wait for; at the bound a point's scans take about 0.5 s.
const MAX_SCAN_WORK: usize = 10_000_000;

/// The scans' work ([`MAX_SCAN_WORK`]), an error at the potential when it is larger.
fn scan_work(
    ctx: &Ctx,
    raw: &RawEnergy,
    coordinates: &[Coordinate],
    gradient: &[Expr],
    hessian: &[Expr],
) -> Result<(), ScenarioError> {
    let starts: usize = coordinates.iter().filter_map(|c| c.scan.map(|(_, _, n)| n)).product();
    let bytes: usize = gradient.iter().chain(hessian).map(Expr::size).sum();
    if coordinates.iter().any(|c| c.scan.is_some()) && starts.saturating_mul(bytes) > MAX_SCAN_WORK {
        return Err(ctx.err(
            &raw.potential,
            format!(
                "the scans' {starts} Newton starts times the {bytes} bytes of the potential's gradient and Hessian \
                 make {} evaluations' worth a settle point; at most {MAX_SCAN_WORK}: scan fewer starts",
                starts * bytes
            ),
        ));
    }
    Ok(())
}

/// One coordinate: a name new among the state's symbols (and the file's names: `names.rs`),
/// its measured expression of the state, its class and scan.
fn coordinate(ctx: &Ctx, state: &[&str], c: &RawCoordinate) -> Result<Coordinate, ScenarioError> {
    let name = c.name.get_ref().clone();
    if state.contains(&name.as_str()) {
        return Err(ctx.err(&c.name, format!("coordinate name '{name}' is already a symbol of this scenario")));
    }
    let measured = Expr::compile(c.measured.get_ref(), state)
        .map_err(|e| expr_error(ctx, c.measured.span().start, &e, &format!("coordinate '{name}' measured")))?;
    let class = match c.class.get_ref().as_str() {
        "angle" => ErrorClass::Angle,
        "length" => ErrorClass::Length,
        other => {
            return Err(ctx.err(&c.class, format!("unknown coordinate class '{other}' (expected angle or length)")))
        }
    };
    let scan = c.scan.as_ref().map(|s| scan(ctx, s)).transpose()?;
    Ok(Coordinate { name, measured, class, scan })
}

/// A scan: from, to (finite) and a count from 1 to [`MAX_SCAN`].
fn scan(ctx: &Ctx, s: &Spanned<RawRange>) -> Result<(f64, f64, usize), ScenarioError> {
    let r = s.get_ref();
    let (from, to) = (finite(ctx, &r.from, "scan.from")?, finite(ctx, &r.to, "scan.to")?);
    let n = *r.count.get_ref();
    if !(1..=MAX_SCAN).contains(&n) {
        return Err(ctx.err(&r.count, format!("scan.count must be a whole number from 1 to {MAX_SCAN}, got {n}")));
    }
    Ok((from, to, n as usize))
}
