//! `tensegrity bench --scale`: families of structures whose equilibrium is known in closed form,
//! each settled from a perturbed start with the structure's default settling, from 3 struts to
//! a thousand. One family per file:
//!
//! - [`prism`](mod@prism): regular n-strut prisms (twist pi/2 + pi/n);
//! - [`icosahedron`]: the 6-strut icosahedron (the expanded octahedron, cable / strut length
//!   sqrt(6)/4);
//! - [`tower`]: stacked towers of 4-strut prisms designed by the force density method;
//! - [`furet`]: furet2018's Snelson X modules in series (n = 1 .. 100), end point against the
//!   direct kinematics of Eq. 2;
//! - [`spine`]: tensegrity spines of stacked tetrahedral vertebrae joined by saddle cables and
//!   vertical springs, whose design is an equilibrium by its symmetry.
//!
//! Each case reports steps, wall time, memory (the process's resident set: `VmRSS` before the
//! case and its peak `VmHWM` during it, after freed heap has been handed back to the system
//! and the peak reset, `reset_memory`),
//! the error against the closed form and the force residual; each family the growth exponent
//! of its cost ([`growth_exponent`]). [`peer`] runs the same structures through MuJoCo.

pub mod furet;
pub mod icosahedron;
pub mod judged;
pub mod motion;
pub mod peer;
pub mod prism;
pub mod spine;
pub mod tower;

pub use prism::{prism, settle_prism};

use super::BenchError;
use crate::run::SettleDetector;
use crate::settings::{SettleCriteria, SimSettings};
use crate::sim::Simulation;
use crate::structure::{MemberKind, Structure, Vec3};
use nalgebra::{Matrix3, Vector3};
use serde::Serialize;
use std::time::Instant;

/// One structure's settle.
#[derive(Clone, Debug, Serialize)]
pub struct ScaleCase {
    pub family: &'static str,
    /// The family's size parameter: struts (prism, icosahedron), stages (tower), X modules
    /// (furet), free vertebrae (spine).
    pub size: usize,
    pub struts: usize,
    pub cables: usize,
    pub springs: usize,
    pub joints: usize,
    pub settled: bool,
    pub steps: u64,
    /// Building the simulation and settling it \[s\] (the structure's design is outside).
    pub wall_s: f64,
    /// Resident set before the case \[KiB\] (None where `/proc/self/status` cannot be read).
    pub rss_before_kib: Option<u64>,
    /// Peak resident set during the case (`VmHWM`, reset before it) \[KiB\].
    pub peak_rss_kib: Option<u64>,
    /// Error against the closed form, in [`ScaleCase::error_unit`]: see [`Measure`].
    pub error: f64,
    pub error_unit: &'static str,
    /// Largest residual force or torque of the settled state [N, N m].
    pub residual: f64,
    /// Why the case stopped without settling (step cap, wall cap), if it did.
    pub note: Option<String>,
    /// The settled positions of the case's target nodes, in target order \[m\].
    #[serde(skip)]
    pub settled_nodes: Vec<Vec3>,
}

/// The caps that keep a case from running for ever: it is reported as not settled.
#[derive(Clone, Copy, Debug)]
pub struct Caps {
    pub max_steps: u64,
    /// Checked between steps (one step is never interrupted) \[s\].
    pub max_wall_s: f64,
}

/// Default caps: 20000 steps, 120 s of wall time per case.
pub const DEFAULT_CAPS: Caps = Caps { max_steps: 20_000, max_wall_s: 120.0 };

/// Speed tolerance per metre of the structure's size [1/s]: at rest, round-off alone moves
/// nodes by a few ulps of their coordinates per step (measured: 4e-12 m/s on 10- to
/// 20-module furet2018 chains at dt 0.005 s, about 10 ulps of a 1 m coordinate per step), so a
/// fixed 1e-12 m/s is out of reach for long structures.
pub const SPEED_TOL_PER_M_PER_S: f64 = 1e-11;

/// The settle criterion of every family: node speeds below [`SPEED_TOL_PER_M_PER_S`] times the
/// structure's size (at least 1 m) for 10 steps, residual below 1e-9 N and N m.
pub fn criteria(s: &Structure, dt_s: f64, caps: &Caps) -> SettleCriteria {
    SettleCriteria {
        speed_tol_m_per_s: SPEED_TOL_PER_M_PER_S * crate::structure::structure_size(s).max(1.0),
        window_steps: 10,
        residual_force_tol_n: 1e-9,
        residual_torque_tol_nm: 1e-9,
        max_time_s: caps.max_steps as f64 * dt_s,
    }
}

/// A structure to settle: its start, settings, actuator commands and what it is compared with.
pub struct Case {
    pub family: &'static str,
    pub size: usize,
    /// The perturbed start.
    pub start: Structure,
    pub settings: SimSettings,
    /// Actuator commands (structure order), if any.
    pub commands: Vec<f64>,
    /// The closed form: node index and its position \[m\].
    pub target: Vec<(usize, Vec3)>,
    pub measure: Measure,
    /// A free body started spinning: its index and angular velocity [rad/s] (world frame).
    pub spin: Option<(usize, Vec3)>,
    /// An actuated slide followed in time (the driven cart of `judged.rs`).
    pub drive: Option<judged::SlideDrive>,
}

/// How a case's settled nodes are compared with the closed form.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Measure {
    /// The largest node distance after the best rigid alignment \[m\] (a structure held by one
    /// strut keeps a free rotation about it).
    Aligned,
    /// The largest node distance as they are \[m\] (furet: the base is fixed).
    Absolute,
    /// The n-strut prism's largest |twist - (pi/2 + pi/n)| \[rad\] (nodes: bottom i at 2 i, top
    /// i at 2 i + 1): its size depends on the drawn strut length, its twist does not.
    Twist,
}

impl Measure {
    pub fn unit(self) -> &'static str {
        match self {
            Measure::Aligned | Measure::Absolute => "m",
            Measure::Twist => "rad",
        }
    }

    /// The error of `settled` against `target` (in target order).
    pub fn error(self, settled: &[Vec3], target: &[Vec3]) -> f64 {
        match self {
            Measure::Aligned => aligned_distance(settled, target),
            Measure::Absolute => max_distance(settled, target),
            Measure::Twist => prism::twist_error(settled, settled.len() / 2),
        }
    }
}

/// What the settle loop measured.
pub struct Settled {
    pub sim: Simulation,
    pub settled: bool,
    pub steps: u64,
    pub wall_s: f64,
    pub residual: f64,
    pub note: Option<String>,
}

/// Reads one `kB` field of `/proc/self/status`.
fn proc_status_kib(field: &str) -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = text.lines().find(|l| l.starts_with(field))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Hands the heap that earlier cases freed back to the system (glibc `malloc_trim`: without it
/// the allocator keeps it and the resident set hides a case's own growth; a counting global
/// allocator was measured instead and cost ji2014's bench about 8 % of its cases per second),
/// then resets the peak resident set (`VmHWM`) to the current one (Linux `clear_refs` 5).
fn reset_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only returns free memory of the allocator's own arenas.
    unsafe {
        libc::malloc_trim(0);
    }
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// Steps `s` as the settle loop does, the relaxation off once the motion has stopped, until
/// settled (speed and residual) or a cap is reached.
pub fn settle(s: &Structure, settings: &SimSettings, commands: &[f64], caps: &Caps) -> Result<Settled, BenchError> {
    let criteria = criteria(s, settings.dt_s, caps);
    let start = Instant::now();
    let mut sim = Simulation::new(s, settings)?;
    if !commands.is_empty() {
        sim.set_commands(commands);
    }
    let mut detector = SettleDetector::new();
    let (mut settled, mut steps, mut residual, mut note) = (false, 0, f64::NAN, None);
    while !settled {
        if steps >= caps.max_steps {
            note = Some(format!("step cap {} reached, speed {:.1e} m/s", caps.max_steps, detector.last_speed));
            break;
        }
        if start.elapsed().as_secs_f64() > caps.max_wall_s {
            note = Some(format!(
                "wall cap {} s reached after {steps} steps, speed {:.1e} m/s",
                caps.max_wall_s, detector.last_speed
            ));
            break;
        }
        sim.step()?;
        steps += 1;
        let quiet = detector.update_nodes(&sim.node_positions(), settings.dt_s, &criteria);
        sim.set_relaxation(settings.relaxation && detector.last_speed > criteria.speed_tol_m_per_s);
        if quiet {
            let snap = sim.snapshot();
            residual = snap.forces.residual.as_ref().map_or(f64::NAN, |r| r.max_force_n.max(r.max_torque_nm));
            settled = SettleDetector::residual_ok(&snap, &criteria);
        }
    }
    Ok(Settled { sim, settled, steps, wall_s: start.elapsed().as_secs_f64(), residual, note })
}

/// A case faster than this is settled again until the settles add up to it, and its wall time
/// is the median \[s\]: one settle of a small structure takes well under a millisecond, where a
/// single timing varied by 10x within a run.
pub const MIN_CASE_WALL_S: f64 = 0.2;

/// The median wall time of a run that took `first` [s] and of its repeats by `again`, run
/// until the runs add up to [`MIN_CASE_WALL_S`].
pub(super) fn median_wall(first: f64, mut again: impl FnMut() -> Result<f64, BenchError>) -> Result<f64, BenchError> {
    let mut walls = vec![first];
    while walls.iter().sum::<f64>() < MIN_CASE_WALL_S {
        walls.push(again()?);
    }
    walls.sort_by(f64::total_cmp);
    Ok(walls[walls.len() / 2])
}

/// Settles `case` and measures it (the memory of the first settle).
pub fn run_case(case: &Case, caps: &Caps) -> Result<ScaleCase, BenchError> {
    reset_memory();
    let rss_before_kib = proc_status_kib("VmRSS:");
    let mut out = settle(&case.start, &case.settings, &case.commands, caps)?;
    let peak_rss_kib = proc_status_kib("VmHWM:");
    out.wall_s = median_wall(out.wall_s, || Ok(settle(&case.start, &case.settings, &case.commands, caps)?.wall_s))?;
    let settled_nodes: Vec<Vec3> = case.target.iter().map(|(i, _)| out.sim.node_position(*i)).collect();
    let target: Vec<Vec3> = case.target.iter().map(|(_, p)| *p).collect();
    let error = case.measure.error(&settled_nodes, &target);
    let s = &case.start;
    Ok(ScaleCase {
        family: case.family,
        size: case.size,
        struts: s.count_of(MemberKind::Strut),
        cables: s.count_of(MemberKind::Cable),
        springs: s.count_of(MemberKind::Spring),
        joints: s.joints.len(),
        settled: out.settled,
        steps: out.steps,
        wall_s: out.wall_s,
        rss_before_kib,
        peak_rss_kib,
        error,
        error_unit: case.measure.unit(),
        residual: out.residual,
        note: out.note,
        settled_nodes,
    })
}

/// Largest distance between corresponding points \[m\].
pub fn max_distance(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(p, q)| crate::structure::distance(*p, *q)).fold(0.0, f64::max)
}

/// Largest distance between corresponding points after the rigid motion that best maps `a`
/// onto `b` (least squares, Kabsch's SVD solution) \[m\].
pub fn aligned_distance(a: &[Vec3], b: &[Vec3]) -> f64 {
    let centroid = |v: &[Vec3]| v.iter().map(|p| Vector3::from(*p)).sum::<Vector3<f64>>() / v.len().max(1) as f64;
    let (ca, cb) = (centroid(a), centroid(b));
    let mut h = Matrix3::zeros();
    for (p, q) in a.iter().zip(b) {
        h += (Vector3::from(*p) - ca) * (Vector3::from(*q) - cb).transpose();
    }
    let svd = h.svd(true, true);
    let (u, v_t) = (svd.u.expect("u requested"), svd.v_t.expect("v_t requested"));
    let d = (v_t.transpose() * u.transpose()).determinant().signum();
    let r = v_t.transpose() * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * u.transpose();
    a.iter().zip(b).map(|(p, q)| (r * (Vector3::from(*p) - ca) + cb - Vector3::from(*q)).norm()).fold(0.0, f64::max)
}

/// Points fitted by [`growth_exponent`]: the largest settled sizes.
pub const EXPONENT_POINTS: usize = 4;

/// The growth exponent of a family's cost: the least-squares slope of ln(wall) against
/// ln(struts) over its [`EXPONENT_POINTS`] largest settled cases (None below 2 sizes).
pub fn growth_exponent(cases: &[ScaleCase]) -> Option<f64> {
    let mut pts: Vec<(f64, f64)> =
        cases.iter().filter(|c| c.settled && c.wall_s > 0.0).map(|c| ((c.struts as f64).ln(), c.wall_s.ln())).collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let pts = &pts[pts.len().saturating_sub(EXPONENT_POINTS)..];
    if pts.len() < 2 || pts.first()?.0 == pts.last()?.0 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    Some(sxy / sxx)
}

/// The families, in table order.
pub const FAMILIES: [&str; 5] = ["prism", "icosahedron", "tower", "furet", "spine"];

/// Every family's cases up to `max_struts` struts (furet: up to its 100 modules).
pub fn cases(family: &str, max_struts: usize) -> Result<Vec<Case>, BenchError> {
    match family {
        "prism" => Ok(prism::SIZES.iter().filter(|&&n| n <= max_struts).map(|&n| prism::case(n)).collect()),
        "icosahedron" => Ok(if max_struts >= 6 { vec![icosahedron::case()] } else { vec![] }),
        "tower" => tower::STAGES
            .iter()
            .filter(|&&m| tower::N * m <= max_struts)
            .map(|&m| tower::case(m).map_err(BenchError::Tower))
            .collect(),
        // n modules: 3 n struts and the base bar.
        "furet" => Ok(furet::MODULES.iter().filter(|&&n| 3 * n < max_struts).map(|&n| furet::case(n)).collect()),
        // m free vertebrae and the held one: four legs each.
        "spine" => {
            Ok(spine::VERTEBRAE.iter().filter(|&&m| 4 * (m + 1) <= max_struts).map(|&m| spine::case(m)).collect())
        }
        _ => Err(BenchError::Case(format!("no scale family '{family}' (families: {})", FAMILIES.join(", ")))),
    }
}

/// One family's table.
#[derive(Clone, Debug, Serialize)]
pub struct FamilyReport {
    pub family: &'static str,
    pub cases: Vec<ScaleCase>,
    /// [`growth_exponent`] of the wall time.
    pub growth_exponent: Option<f64>,
}

/// Settles every case of `family`.
pub fn run_family(family: &'static str, max_struts: usize, caps: &Caps) -> Result<FamilyReport, BenchError> {
    let mut out = Vec::new();
    for case in cases(family, max_struts)? {
        out.push(run_case(&case, caps)?);
    }
    Ok(FamilyReport { family, growth_exponent: growth_exponent(&out), cases: out })
}
