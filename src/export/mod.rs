//! Structures out to other simulators' formats. `mjcf.rs`: MuJoCo's MJCF XML.
//!
//! An export reads a validated scenario's structure (a built-in mechanism built at its first
//! actuation point, or a file's own `[structure]`) and writes text; it steps nothing.

pub mod mjcf;

use crate::mechanisms::ModelError;
use crate::structure::StructureError;

/// An MJCF export's option out of its range, named by its flag.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MjcfOptionError {
    /// `--kp`: the position servos' gain.
    #[error("--kp must be a finite number > 0, got {0}")]
    Kp(f64),
    /// `--cable-damping` [N s/m].
    #[error("--cable-damping must be a finite number >= 0, got {0}")]
    CableDamping(f64),
}

/// Why a scenario's first structure could not be exported.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The mechanism could not build it.
    #[error("{0}")]
    Model(#[from] ModelError),
    /// It was built but is not a valid structure.
    #[error("the structure is not valid: {0}")]
    Invalid(#[from] StructureError),
}

/// Every option of an MJCF export in its range, or the first that is not, named by its flag:
/// the position servos' gain `joint_kp` [N/m or N m/rad] and the cables' damping [N s/m].
pub fn validate_mjcf_options(joint_kp: f64, cable_damping_n_s_per_m: f64) -> Result<(), MjcfOptionError> {
    if !(joint_kp > 0.0 && joint_kp.is_finite()) {
        return Err(MjcfOptionError::Kp(joint_kp));
    }
    if !(cable_damping_n_s_per_m >= 0.0 && cable_damping_n_s_per_m.is_finite()) {
        return Err(MjcfOptionError::CableDamping(cable_damping_n_s_per_m));
    }
    Ok(())
}

/// The MJCF of a scenario's first structure, with the scenario's time step and body damping.
pub fn scenario_mjcf(
    sc: &Scenario,
    actuators: mjcf::ActuatorMode,
    joint_kp: f64,
    cable_damping_n_s_per_m: f64,
) -> Result<mjcf::Mjcf, ExportError> {
    let (s, commands) = first_structure(sc)?;
    let options = mjcf::MjcfOptions {
        model_name: sc.name.clone(),
        timestep_s: sc.sim.dt_s,
        body_damping_per_s: sc.sim.body_damping_per_s,
        actuators,
        joint_kp,
        commands,
        cable_damping_n_s_per_m,
    };
    Ok(mjcf::to_mjcf(&s, &options))
}

use crate::scenario::Scenario;
use crate::structure::Structure;

/// The structure a scenario starts its run with, built at the first point's (or first
/// waypoint's) inputs from the scenario's `[start]` as `run` builds it, and the actuator
/// commands of that point (actuator order, m or rad).
pub fn first_structure(sc: &Scenario) -> Result<(Structure, Vec<f64>), ExportError> {
    let first_inputs = sc.actuation.first_inputs().clone();
    let mech = sc.mechanism();
    let params = sc.params_at(&first_inputs);
    let mut s = mech.build(&params, &first_inputs, &sc.start)?;
    s.validate()?;
    let commands = s.commands_from(&mech.commands(&params, &first_inputs));
    // Moved nodes are exported where their commands place them (MJCF has no such actuator).
    s.displace_fixed_nodes(&commands);
    Ok((s, commands))
}
