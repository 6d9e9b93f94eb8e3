//! `[sim]` and `[settle]`: how the dynamics are stepped, and when a point has settled.

use super::error::{count, finite, positive, Ctx, ScenarioError};
use super::raw::{RawSettle, RawSim};
use crate::settings::{SettleCriteria, SimSettings};

/// `[sim]`: each setting in its range, the defaults for the missing ones; a time step over 1 s
/// is rejected once every setting has been read.
pub(super) fn sim(ctx: &Ctx, raw: &RawSim) -> Result<SimSettings, ScenarioError> {
    let sim = SimSettings {
        dt_s: positive(ctx, &raw.dt, "sim.dt (time step, s)", SimSettings::default().dt_s)?,
        substeps: count(ctx, &raw.substeps, "sim.substeps", 1, 64)?,
        pgs_iterations: count(ctx, &raw.pgs_iterations, "sim.pgs_iterations", 8, 4096)?,
        approach_pgs_iterations: match &raw.approach_pgs_iterations {
            None => None,
            Some(_) => Some(count(ctx, &raw.approach_pgs_iterations, "sim.approach_pgs_iterations", 8, 4096)?),
        },
        newton_damping: raw.newton_damping.as_ref().is_some_and(|b| *b.get_ref()),
        relaxation: raw.relaxation.as_ref().is_none_or(|b| *b.get_ref()),
        body_damping_per_s: match &raw.body_damping {
            None => 0.0,
            Some(s) => {
                let x = finite(ctx, s, "sim.body_damping")?;
                if x < 0.0 {
                    return Err(ctx.err(s, format!("sim.body_damping must be >= 0 1/s, got {x}")));
                }
                x
            }
        },
        bounding_box_m: positive(ctx, &raw.bounding_box, "sim.bounding_box (m)", 1e3)?,
        max_kinetic_energy_j: positive(
            ctx,
            &raw.max_kinetic_energy,
            "sim.max_kinetic_energy (J)",
            crate::settings::DEFAULT_MAX_KINETIC_ENERGY_J,
        )?,
        max_joint_gap_m: match &raw.max_joint_gap {
            None => None,
            Some(_) => Some(positive(ctx, &raw.max_joint_gap, "sim.max_joint_gap (m)", 0.0)?),
        },
    };
    if sim.dt_s > 1.0 {
        let s = raw.dt.as_ref().unwrap();
        return Err(ctx.err(s, format!("sim.dt = {} s is longer than 1 s: use a time step of a few ms", sim.dt_s)));
    }
    Ok(sim)
}

/// `[settle]`: each criterion > 0, the defaults for the missing ones.
pub(super) fn settle(ctx: &Ctx, raw: &RawSettle) -> Result<SettleCriteria, ScenarioError> {
    let d = SettleCriteria::default();
    Ok(SettleCriteria {
        speed_tol_m_per_s: positive(ctx, &raw.speed_tol, "settle.speed_tol (m/s)", d.speed_tol_m_per_s)?,
        window_steps: count(ctx, &raw.window, "settle.window (steps)", d.window_steps as usize, 1_000_000)? as u64,
        residual_force_tol_n: positive(
            ctx,
            &raw.residual_force_tol,
            "settle.residual_force_tol (N)",
            d.residual_force_tol_n,
        )?,
        residual_torque_tol_nm: positive(
            ctx,
            &raw.residual_torque_tol,
            "settle.residual_torque_tol (N m)",
            d.residual_torque_tol_nm,
        )?,
        max_time_s: positive(ctx, &raw.max_time, "settle.max_time (s)", d.max_time_s)?,
    })
}

/// The Newton damping schedule's default: on for a custom structure whose joints form no loop
/// (a tree hung from the ground, where each joint's stiffness with the others held is the
/// step's), off for the built-in mechanisms (their files say what their baselines use) and
/// for closed loops (there the projection closes the loop and settles it).
pub(super) fn default_newton_damping(custom: bool, s: &crate::structure::Structure) -> bool {
    custom && !s.joints.is_empty() && !joints_close_a_loop(s)
}

/// Whether the joints of `s` close a loop (fixed bodies count as one ground).
fn joints_close_a_loop(s: &crate::structure::Structure) -> bool {
    use crate::structure::BodyKind;
    let ground = s.bodies.len();
    let node = |b: usize| if s.bodies[b].kind == BodyKind::Fixed { ground } else { b };
    let mut parent: Vec<usize> = (0..=ground).collect();
    fn root(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    s.joints.iter().any(|j| {
        let (a, b) = (root(&mut parent, node(j.parent)), root(&mut parent, node(j.child)));
        parent[a] = b;
        a == b
    })
}
