//! `tensegrity bench --scale --peer`: the scale families in MuJoCo, side by side in one run.
//!
//! Each case's start is written to MJCF by `export::mjcf` (free bodies with free joints damped
//! at the testbed's body damping times their mass, elastic cables as tendons with the dead band
//! `springlength="0 L"`, springs as tendons, revolute joints as hinges, loop closures as soft
//! `connect` equalities, actuated joints as mocap bodies or joint locks), and the case list
//! goes to the peer (`benches/peers/mujoco/scale_peer.py`): it settles every case by the
//! testbed's criterion and scores it by the testbed's error measure (`scale_peer.py`'s
//! docstring has the protocol and the settings). The testbed settles each case first, in the
//! same process run; rates are 1 / (wall time per case), building the model included on both
//! sides.

use super::{cases, criteria, growth_exponent, run_case, Caps, Case, FamilyReport, Measure, ScaleCase};
use crate::bench::{write_error, BenchError};
use crate::export::mjcf::{to_mjcf, ActuatorMode, MjcfOptions};
use crate::structure::{ActuatorTarget, BodyKind, JointKind};
use serde::Serialize;
use std::path::Path;

/// One case of both sides.
#[derive(Clone, Debug, Serialize)]
pub struct PeerRow {
    pub family: &'static str,
    pub size: usize,
    pub struts: usize,
    pub testbed_settled: bool,
    pub testbed_steps: u64,
    pub testbed_wall_s: f64,
    pub testbed_cases_per_s: f64,
    pub testbed_error: f64,
    /// The unit of both errors (m or rad).
    pub error_unit: &'static str,
    pub peer_settled: bool,
    pub peer_steps: u64,
    pub peer_wall_s: f64,
    pub peer_cases_per_s: f64,
    pub peer_error: f64,
    /// Testbed / peer: above 1 the testbed settles more cases per second.
    pub ratio_cases_per_s: f64,
    /// Testbed / peer: below 1 the testbed is more accurate.
    pub ratio_error: f64,
    /// What the export could not express, and why the peer stopped if it did not settle.
    pub peer_notes: Vec<String>,
    /// The peer's description (simulator, version, settings).
    pub peer: serde_json::Value,
}

/// A mocap body the peer must turn to its actuator's command (MJCF places it at its drawn
/// pose): `angle_rad` about `axis` through the body's frame origin (the joint's anchor).
#[derive(Clone, Debug, Serialize)]
struct MocapTurn {
    body: String,
    axis: [f64; 3],
    angle_rad: f64,
}

#[derive(Clone, Debug, Serialize)]
struct PeerCase {
    family: &'static str,
    size: usize,
    mjcf: String,
    dt_s: f64,
    speed_tol_m_per_s: f64,
    window_steps: u64,
    max_steps: u64,
    max_wall_s: f64,
    /// Sites compared with `target` [m].
    nodes: Vec<String>,
    target: Vec<[f64; 3]>,
    measure: Measure,
    mocap: Vec<MocapTurn>,
    warnings: Vec<String>,
}

/// Actuated revolute joints on fixed parents: the MJCF's mocap bodies, turned by command - q0.
fn mocap_turns(case: &Case) -> Vec<MocapTurn> {
    let s = &case.start;
    s.actuators
        .iter()
        .zip(&case.commands)
        .filter_map(|(a, &command)| {
            let ActuatorTarget::Joint(j) = a.target else { return None };
            let joint = &s.joints[j];
            let JointKind::Revolute { axis } = joint.kind else { return None };
            (s.bodies[joint.parent].kind == BodyKind::Fixed).then(|| MocapTurn {
                body: s.bodies[joint.child].name.clone(),
                axis,
                angle_rad: command - joint.initial_coordinate,
            })
        })
        .collect()
}

/// The case for the peer, its MJCF written to `dir`.
fn peer_case(case: &Case, caps: &Caps, dir: &Path) -> Result<PeerCase, BenchError> {
    let s = &case.start;
    let path = dir.join(format!("{}-{}.xml", case.family, case.size));
    let warnings = write_mjcf(case, case.settings.dt_s, case.settings.body_damping_per_s, &path)?;
    let c = criteria(s, case.settings.dt_s, caps);
    Ok(PeerCase {
        family: case.family,
        size: case.size,
        mjcf: path.display().to_string(),
        dt_s: case.settings.dt_s,
        speed_tol_m_per_s: c.speed_tol_m_per_s,
        window_steps: c.window_steps,
        max_steps: caps.max_steps,
        max_wall_s: caps.max_wall_s,
        nodes: case.target.iter().map(|(i, _)| s.nodes[*i].name.clone()).collect(),
        target: case.target.iter().map(|(_, p)| *p).collect(),
        measure: case.measure,
        mocap: mocap_turns(case),
        warnings,
    })
}

/// Writes `case`'s start to `path` as MJCF at this time step and body damping [1/s], its
/// actuators as mocap bodies; returns what the export could not express.
pub(super) fn write_mjcf(
    case: &Case,
    timestep_s: f64,
    body_damping_per_s: f64,
    path: &Path,
) -> Result<Vec<String>, BenchError> {
    let o = MjcfOptions {
        model_name: case.start.name.clone(),
        timestep_s,
        body_damping_per_s,
        actuators: ActuatorMode::Mocap,
        joint_kp: 0.0,
        commands: case.commands.clone(),
        cable_damping_n_s_per_m: 0.0,
    };
    let m = to_mjcf(&case.start, &o);
    crate::bench::write_whole(path, &m.xml)?;
    Ok(m.warnings)
}

/// One case of both sides: the testbed's `t`, the peer's JSON `p` for the case `pc` it got.
fn row(t: &ScaleCase, p: &serde_json::Value, pc: &PeerCase, about: &serde_json::Value) -> PeerRow {
    let num = |k: &str| p.get(k).and_then(|x| x.as_f64()).unwrap_or(f64::NAN);
    let (peer_wall_s, peer_error) = (num("wall_s"), num("error"));
    let mut notes = pc.warnings.clone();
    if let Some(n) = p.get("note").and_then(|n| n.as_str()) {
        notes.push(n.to_string());
    }
    PeerRow {
        family: t.family,
        size: t.size,
        struts: t.struts,
        testbed_settled: t.settled,
        testbed_steps: t.steps,
        testbed_wall_s: t.wall_s,
        testbed_cases_per_s: 1.0 / t.wall_s,
        testbed_error: t.error,
        error_unit: t.error_unit,
        peer_settled: p.get("settled").and_then(|x| x.as_bool()).unwrap_or(false),
        peer_steps: p.get("steps").and_then(|x| x.as_u64()).unwrap_or(0),
        peer_wall_s,
        peer_cases_per_s: 1.0 / peer_wall_s,
        peer_error,
        ratio_cases_per_s: peer_wall_s / t.wall_s,
        ratio_error: t.error / peer_error,
        peer_notes: notes,
        peer: about.clone(),
    }
}

/// Every case of `families` up to `max_struts`, settled by the testbed and then by the peer:
/// the testbed's family tables and the side-by-side rows. `progress` is told what starts (a
/// line of text, for the command line to show).
pub fn compare(
    families: &[&'static str],
    max_struts: usize,
    caps: &Caps,
    command: &[String],
    dir: &Path,
    progress: &dyn Fn(&str),
) -> Result<(Vec<FamilyReport>, Vec<PeerRow>), BenchError> {
    std::fs::create_dir_all(dir).map_err(write_error(dir))?;
    let (mut ours, mut theirs) = (Vec::new(), Vec::new());
    for family in families {
        for case in cases(family, max_struts)? {
            progress(&format!("{} {}: testbed ...", case.family, case.size));
            ours.push(run_case(&case, caps)?);
            theirs.push(peer_case(&case, caps, dir)?);
        }
    }
    let file = dir.join("scale_cases.json");
    let list = serde_json::json!({ "cases": theirs });
    crate::bench::write_whole(&file, &serde_json::to_string_pretty(&list).expect("case list serialises"))?;
    progress(&format!("{} cases: peer ...", theirs.len()));
    let v = crate::bench::run_peer(command, &file, &[])?;
    let peer_cases = v
        .get("cases")
        .and_then(|c| c.as_array())
        .ok_or_else(|| BenchError::Peer("the peer's JSON has no 'cases' list".into()))?;
    if peer_cases.len() != ours.len() {
        return Err(BenchError::Peer(format!("the peer settled {} cases of {}", peer_cases.len(), ours.len())));
    }
    let about = serde_json::json!({
        "simulator": v.get("simulator"), "mujoco_version": v.get("mujoco_version"), "settings": v.get("settings"),
    });
    let rows = ours.iter().zip(peer_cases).zip(&theirs).map(|((t, p), pc)| row(t, p, pc, &about)).collect();
    let reports = families
        .iter()
        .map(|f| {
            let cases: Vec<ScaleCase> = ours.iter().filter(|c| c.family == *f).cloned().collect();
            FamilyReport { family: f, growth_exponent: growth_exponent(&cases), cases }
        })
        .collect();
    Ok((reports, rows))
}
