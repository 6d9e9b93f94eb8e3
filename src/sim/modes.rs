//! The structure's own modal analysis at its current (settled) state: the generalized
//! symmetric eigenproblem H v = omega^2 M v of the tangent stiffness H that the static
//! relaxation assembles (the exact Hessian of the potential energy over six coordinates per
//! free body: translation of the centre of mass, small rotation about it, world frame;
//! `relaxation/assemble.rs`) and the mass matrix M = diag(m 1, R I R^T) per body (the
//! kinetic energy m v^2 / 2 + w^T I_world w / 2, I_world the principal moments turned by the
//! body's current rotation R). Structures of free bodies held by springs and elastic cables
//! (no inextensible cables: the relaxation's own domain); jointed ones are reduced to their
//! joints' coordinates (`joint_modes.rs`); others are refused, by name. Modes with |omega^2| below [`ZERO_MODE_RATIO`] of the largest are rigid-body modes
//! (a free turn or translation, a strut's spin about its axis): reported as ~0 and counted.
//! Above [`DENSE_MODAL_MAX_FREE_BODIES`] free bodies (free bodies alone) the eigenproblem is
//! sparse: the lowest [`SPARSE_MODAL_COUNT`] modes beyond the rigid ones, by shift-invert
//! subspace iteration (`relaxation/lowest_modes.rs`).

pub(crate) use super::constrained_modes::{least_squares, null_space, zero_floor};
pub use super::constrained_modes::{Constraints, ModalCoordinate, NULL_SPACE_RATIO};
use super::data::Data;
use super::model::Model;
use crate::eigen::EigenError;
use crate::snapshot::{BodyPose, ModalProjector};
use crate::structure::BodyKind;
use crate::structure::{DENSE_MODAL_MAX_FREE_BODIES, MAX_SPARSE_MODAL_COUNT, SPARSE_MODAL_COUNT};
use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, Quaternion, UnitQuaternion, Vector3};
use std::sync::atomic::AtomicBool;

/// A mode whose |omega^2| is below this fraction of the largest is a rigid-body (zero) mode.
pub const ZERO_MODE_RATIO: f64 = 1e-9;
/// Nodes listed per mode as the largest-moving.
pub const NODES_LISTED: usize = 3;

/// One natural mode of the structure.
#[derive(Clone, Debug)]
pub struct StructureMode {
    /// Eigenvalue of H v = omega^2 M v [rad^2/s^2] (negative: an unstable direction).
    pub omega_squared: f64,
    /// A rigid-body mode (|omega^2| below [`ZERO_MODE_RATIO`] of the largest).
    pub rigid: bool,
    /// Six coordinates per free body (m, rad), mass-normalised (v^T M v = 1).
    pub shape: Vec<f64>,
    /// Every node's displacement in this mode, in structure node order [m per unit of the
    /// mass-normalised amplitude]; zero on fixed bodies.
    pub node_motion: Vec<[f64; 3]>,
    /// A jointed structure's mode in its joints' coordinates (rad or m, mass-normalised; in
    /// the order of [`StructureModes::joints`]); empty for free bodies.
    pub joint_shape: Vec<f64>,
}

impl StructureMode {
    /// omega [rad/s] (minus sqrt(-omega^2) where omega^2 < 0).
    pub fn omega(&self) -> f64 {
        self.omega_squared.signum() * self.omega_squared.abs().sqrt()
    }

    /// The nodes that move most in this mode: (node index, |displacement| relative to the
    /// largest), at most `n`, largest first.
    pub fn largest_moving(&self, n: usize) -> Vec<(usize, f64)> {
        let norm = |d: &[f64; 3]| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let mut by: Vec<(usize, f64)> = self.node_motion.iter().map(norm).enumerate().collect();
        by.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        let top = by.first().map_or(0.0, |x| x.1);
        by.into_iter().take(n).map(|(i, d)| (i, if top > 0.0 { d / top } else { 0.0 })).collect()
    }
}

/// The modal analysis of a structure at one state.
#[derive(Clone, Debug)]
pub struct StructureModes {
    /// The structure body of each block of six coordinates.
    pub bodies: Vec<usize>,
    /// A jointed structure's coordinates: its free joints (`joint_modes.rs`); empty for free
    /// bodies, whose coordinates are the bodies' six each.
    pub joints: Vec<usize>,
    /// Each free body's pose at the state analysed.
    pub poses: Vec<BodyPose>,
    /// The mass matrix there: its 6x6 block per free body (it is block diagonal).
    pub mass: Vec<Matrix6<f64>>,
    /// Ascending omega^2.
    pub modes: Vec<StructureMode>,
    /// How many are rigid-body modes.
    pub rigid: usize,
    /// A structure held by loops or inextensible cables: the constraints it was reduced by
    /// (`constrained_modes.rs`; each mode's `joint_shape` is then in their coordinates).
    pub constraints: Option<Constraints>,
    /// `Some(total)` where `modes` are the lowest of the structure's `total` (the sparse
    /// solver's); `None` where they are all of them.
    pub lowest_of: Option<usize>,
    /// The free bodies' coordinates left out of the analysis: the point masses' turns, three
    /// each (`turning_coordinates` in `sim/modes.rs`; their shapes are zero there).
    pub left_out: usize,
}

/// Why a structure's modes are not computed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ModesError {
    #[error("joint '{0}' closes a loop with a kind of joint that has no constraint rows (spherical, revolute, universal and planar pins have)")]
    Loop(String),
    #[error("free body '{0}' hangs on no joint: the sensitivities of free bodies beside joint trees are not computed (their modes are: tensegrity modes)")]
    Unjointed(String),
    #[error("joint '{0}' has more than one coordinate: modes are reduced to revolute and prismatic joints")]
    JointKind(String),
    #[error("no free body: nothing moves")]
    NoFreeBody,
    #[error("cable '{0}' has friction at a node: its force depends on the path, not on the state alone, so it has no stiffness to linearise")]
    Friction(String),
    /// More free bodies than the dense eigenproblem is solved for.
    #[error("{bodies} free bodies: the modes are a dense eigenproblem, solved for at most {MAX_MODAL_FREE_BODIES} free bodies ({} coordinates; 300 had taken 20 s, 1000 more than 2 GiB)", 6 * MAX_MODAL_FREE_BODIES)]
    TooLarge { bodies: usize },
    /// More free bodies (on springs and elastic cables) than the sparse solver is run for.
    #[error("{bodies} free bodies: the lowest modes of free bodies on springs and elastic cables are computed for at most {MAX_SPARSE_MODAL_FREE_BODIES} free bodies (each rigid mode reported, about one a body, holds a shape and a motion per node: the report grows with the square of the count)")]
    TooLargeSparse { bodies: usize },
    /// More point masses (elastic struts' ends, heavy cables' beads) than the sparse solver is
    /// run for.
    #[error("{points} point masses (elastic struts' ends, heavy cables' beads): the lowest modes are computed for at most {MAX_SPARSE_MODAL_POINT_MASSES}")]
    TooManyPointMasses { points: usize },
    /// More non-rigid modes asked of the sparse solver than it computes.
    #[error("the lowest {wanted} modes beyond the structure's {rigid} rigid ones were asked for (through mode {through}); the sparse solver computes at most {MAX_SPARSE_MODAL_COUNT}")]
    TooManyWanted { wanted: usize, rigid: usize, through: usize },
    /// A motion asks for a mode past those the sparse solver computed.
    #[error("mode {mode} was not computed: the structure's lowest {computed} modes are (from 1), of {total}")]
    NotComputed { mode: usize, computed: usize, total: usize },
    /// A motion asks for a mode (from 1) along which the structure moves without deforming.
    #[error("mode {mode} is a rigid-body mode (omega^2 = {omega_squared:e} rad^2/s^2, one of the structure's {rigid} that move it without deforming it): there is no vibration along it to start or to fit; choose a mode from {}", rigid + 1)]
    RigidMode { mode: usize, omega_squared: f64, rigid: usize },
    /// A support in some directions: the equilibrium's sensitivities over free bodies' poses
    /// do not take its held coordinates out yet.
    #[error("node '{0}' has a support in some directions: sensitivities and fits of a structure with such supports are not computed yet (its modes are: tensegrity modes)")]
    Supported(String),
    #[error(transparent)]
    Eigen(#[from] EigenError),
}

pub use crate::structure::{MAX_MODAL_FREE_BODIES, MAX_SPARSE_MODAL_FREE_BODIES, MAX_SPARSE_MODAL_POINT_MASSES};

/// The structure's size for its modes: an error past [`MAX_MODAL_FREE_BODIES`] free bodies, or
/// [`MAX_SPARSE_MODAL_FREE_BODIES`] for free bodies on springs and elastic cables.
pub fn check_modal_size(s: &crate::structure::Structure) -> Result<(), ModesError> {
    let (free, points) = crate::structure::modal_bodies(s);
    if points > MAX_SPARSE_MODAL_POINT_MASSES {
        return Err(ModesError::TooManyPointMasses { points });
    }
    let bodies = free - points;
    if bodies > crate::structure::modal_free_body_bound(s) {
        return Err(if crate::structure::modes_of_free_bodies(s) {
            ModesError::TooLargeSparse { bodies }
        } else {
            ModesError::TooLarge { bodies }
        });
    }
    Ok(())
}

/// How many modes the sparse solver of large structures computes: the lowest `count` beyond
/// the rigid ones, and at least through mode `through` (from 0: a motion along it). The dense
/// eigenproblem gives every mode whatever it asks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lowest {
    pub count: usize,
    pub through: Option<usize>,
}

impl Default for Lowest {
    fn default() -> Self {
        Lowest { count: SPARSE_MODAL_COUNT, through: None }
    }
}

/// Which eigensolver gives the modes of free bodies on springs and elastic cables.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Solver {
    /// Dense up to [`DENSE_MODAL_MAX_FREE_BODIES`] free bodies, sparse above (as many as asked).
    BySize(Lowest),
    /// Dense at any size (every mode).
    Dense,
}

impl Data {
    /// The structure's natural modes at its current state: over six coordinates per free body,
    /// or reduced to the joints' coordinates where there are joints (`joint_modes.rs`).
    pub(super) fn modes(
        &mut self,
        m: &Model,
        cancel: Option<&AtomicBool>,
        solver: Solver,
    ) -> Result<StructureModes, ModesError> {
        let s = &m.structure;
        if !s.bodies.iter().any(|b| b.kind == BodyKind::Free) {
            return Err(ModesError::NoFreeBody);
        }
        check_modal_size(s)?;
        if let Some(c) = s.members.iter().find(|c| c.has_friction()) {
            return Err(ModesError::Friction(c.name.clone()));
        }
        // Free bodies beside joint trees (beads on the members of a jointed structure): the
        // constrained analysis's coordinates, the trees' joints and six per such body, with no
        // constraint (F5 of issue 60: they had been refused).
        if m.is_constrained() || (!s.joints.is_empty() && !s.unjointed_free_bodies().is_empty()) {
            return self.constrained_modes(m, cancel);
        }
        if !s.joints.is_empty() {
            return self.joint_modes(m, cancel);
        }
        let (bodies, com) = self.free_blocks(m);
        let mass = self.mass_blocks(m, &bodies);
        let sparse = match solver {
            Solver::BySize(wanted) if bodies.len() > DENSE_MODAL_MAX_FREE_BODIES => Some(wanted),
            _ => None,
        };
        let turning = turning_coordinates(s, &bodies);
        let held = held_coordinates(m, &bodies);
        let kept: Vec<usize> = (0..turning.len()).filter(|&c| !turning[c] && !held[c]).collect();
        let (eigen, largest, lowest_of) = if let Some(wanted) = sparse {
            let lowest = self.lowest_modes(m, &mass, &turning, wanted, cancel)?;
            (without_held(lowest.modes, &held, &mass), lowest.largest, Some(kept.len()))
        } else {
            let hessian = self.tangent_stiffness(m).hessian;
            let (k, mm) = (hessian.select_rows(&kept), block_diagonal(&mass).select_rows(&kept));
            let eigen = crate::eigen::modes_until(&k.select_columns(&kept), &mm.select_columns(&kept), cancel)?;
            let largest = eigen.iter().fold(0.0f64, |l, e| l.max(e.omega_squared.abs()));
            let full = |shape: DVector<f64>| {
                let mut x = DVector::zeros(turning.len());
                for (j, &c) in kept.iter().enumerate() {
                    x[c] = shape[j];
                }
                x
            };
            (eigen.into_iter().map(|e| (e.omega_squared, full(e.shape))).collect(), largest, None)
        };
        let modes: Vec<StructureMode> = eigen
            .into_iter()
            .map(|(omega_squared, shape)| StructureMode {
                omega_squared,
                rigid: omega_squared.abs() <= ZERO_MODE_RATIO * largest,
                node_motion: self.node_motion(m, &bodies, &com, shape.as_slice()),
                shape: shape.iter().copied().collect(),
                joint_shape: vec![],
            })
            .collect();
        let rigid = modes.iter().filter(|mode| mode.rigid).count();
        let poses = bodies.iter().map(|b| self.body_pose(m, *b)).collect();
        let left_out = turning.len() - kept.len();
        Ok(StructureModes { bodies, joints: vec![], poses, mass, modes, rigid, constraints: None, lowest_of, left_out })
    }

    /// Displaces the structure along mode `index` (from 0) of `analysis` (made at the current
    /// state) so that its largest node displacement is `amplitude_m`; returns the modal
    /// coordinate reached (the mass-normalised amplitude). Linear in the shape: a rotation of
    /// dtheta about each centre of mass, exact for a rigid body.
    pub(super) fn displace_along_mode(
        &mut self,
        m: &Model,
        analysis: &StructureModes,
        index: usize,
        amplitude_m: f64,
    ) -> f64 {
        let mode = &analysis.modes[index];
        let largest = mode.node_motion.iter().map(|d| Vector3::from(*d).norm()).fold(0.0, f64::max);
        let eta = if largest > 0.0 { amplitude_m / largest } else { 0.0 };
        if let Some(c) = &analysis.constraints {
            let dq: Vec<f64> = mode.joint_shape.iter().map(|v| eta * v).collect();
            self.displace_constrained(m, c, &dq);
        } else if analysis.joints.is_empty() {
            self.displace_free_bodies(m, &(DVector::from_column_slice(&mode.shape) * eta));
        } else {
            for (&j, v) in analysis.joints.iter().zip(&mode.joint_shape) {
                self.displace_joint(m, j, eta * v);
            }
        }
        eta
    }

    /// The mass matrix of the free bodies' blocks: m 1 for the translation, R diag(I) R^T for
    /// the rotation (the principal moments about the centre of mass, turned with the body).
    pub(super) fn mass_matrix(&self, m: &Model, bodies: &[usize]) -> DMatrix<f64> {
        block_diagonal(&self.mass_blocks(m, bodies))
    }

    /// The 6x6 blocks of [`Data::mass_matrix`], one per body.
    pub(super) fn mass_blocks(&self, m: &Model, bodies: &[usize]) -> Vec<Matrix6<f64>> {
        let block = |&b: &usize| {
            let inertia = m.structure.bodies[b].inertia.expect("free bodies have inertia");
            let q = self.body_pose(m, b).rotation_xyzw;
            let r = UnitQuaternion::from_quaternion(Quaternion::new(q[3], q[0], q[1], q[2])).to_rotation_matrix();
            let world =
                r.matrix() * Matrix3::from_diagonal(&Vector3::from(inertia.principal_kg_m2)) * r.matrix().transpose();
            let mut mass = Matrix6::zeros();
            mass.fixed_view_mut::<3, 3>(0, 0).copy_from(&(Matrix3::identity() * inertia.mass_kg));
            mass.fixed_view_mut::<3, 3>(3, 3).copy_from(&(0.5 * (world + world.transpose())));
            mass
        };
        bodies.iter().map(block).collect()
    }

    /// Each node's displacement for the coordinates `shape`: dx + dtheta x rho.
    pub(super) fn node_motion(
        &self,
        m: &Model,
        bodies: &[usize],
        com: &[Vector3<f64>],
        shape: &[f64],
    ) -> Vec<[f64; 3]> {
        let s = &m.structure;
        let mut block = vec![None; s.bodies.len()];
        for (i, &b) in bodies.iter().enumerate() {
            block[b] = block[b].or(Some(i));
        }
        (0..s.nodes.len())
            .map(|n| {
                let Some(i) = block[s.nodes[n].body] else { return [0.0; 3] };
                let rho = Vector3::from(self.node_position(m, n)) - com[i];
                let dx = Vector3::from_column_slice(&shape[6 * i..6 * i + 3]);
                let dtheta = Vector3::from_column_slice(&shape[6 * i + 3..6 * i + 6]);
                let d = dx + dtheta.cross(&rho);
                [d.x, d.y, d.z]
            })
            .collect()
    }
}

/// The reader of mode `index` (from 0) of `analysis`'s coordinate off a snapshot (plain data,
/// `snapshot::ModalProjector`).
pub fn modal_projector(s: &crate::structure::Structure, analysis: &StructureModes, index: usize) -> ModalProjector {
    let com_local = analysis.bodies.iter().map(|b| s.bodies[*b].inertia.map_or([0.0; 3], |i| i.com)).collect();
    let shape = &analysis.modes[index].shape;
    let weights = analysis
        .mass
        .iter()
        .enumerate()
        .flat_map(|(i, block)| (block * nalgebra::Vector6::from_column_slice(&shape[6 * i..6 * i + 6])).data.0[0])
        .collect();
    ModalProjector { bodies: analysis.bodies.clone(), start: analysis.poses.clone(), com_local, weights }
}

/// Which of the free bodies' coordinates (six per body of `bodies`, in order) are a point mass's
/// turns (`structure::lumped::is_point_mass`: one node, at the centre of mass). In a structure
/// of free bodies on elastic members nothing turns such a body: its member forces, gravity and
/// loads all act at its centre. Its three turns are zero modes of nothing physical, so the
/// analysis leaves them out (a beaded string of five beads has no rigid mode, not fifteen), and
/// a structure of thousands of beads reports its modes without one rigid mode per bead.
pub(crate) fn turning_coordinates(s: &crate::structure::Structure, bodies: &[usize]) -> Vec<bool> {
    let point = crate::structure::lumped::point_masses(s);
    bodies.iter().flat_map(|&b| [false, false, false, point[b], point[b], point[b]]).collect()
}

/// Which of the free bodies' coordinates (six per body of `bodies`, in order) a support holds
/// (`Structure::supports`): the modes leave them out.
fn held_coordinates(m: &Model, bodies: &[usize]) -> Vec<bool> {
    bodies.iter().flat_map(|&b| m.held_translations[b].into_iter().chain([false; 3])).collect()
}

/// The sparse solver's modes less those of the held coordinates: the relaxation's Hessian
/// gives each held coordinate a stiffness of its own, alone on the diagonal at the top of the
/// spectrum (`relaxation/assemble.rs`), so a mode that moves mostly there (by mass) is that
/// stand-in, not the structure's.
fn without_held(modes: Vec<(f64, DVector<f64>)>, held: &[bool], mass: &[Matrix6<f64>]) -> Vec<(f64, DVector<f64>)> {
    if !held.contains(&true) {
        return modes;
    }
    let share = |x: &DVector<f64>| {
        let (mut part, mut whole) = (0.0, 0.0);
        for (i, block) in mass.iter().enumerate() {
            let all = x.fixed_rows::<6>(6 * i).into_owned();
            let only = nalgebra::Vector6::from_fn(|r, _| if held[6 * i + r] { all[r] } else { 0.0 });
            part += only.dot(&(block * only));
            whole += all.dot(&(block * all));
        }
        part / whole.max(f64::MIN_POSITIVE)
    };
    modes.into_iter().filter(|(_, x)| share(x) <= 0.5).collect()
}

/// The block-diagonal matrix of `blocks`.
pub(super) fn block_diagonal(blocks: &[Matrix6<f64>]) -> DMatrix<f64> {
    let mut out = DMatrix::zeros(6 * blocks.len(), 6 * blocks.len());
    for (i, b) in blocks.iter().enumerate() {
        out.fixed_view_mut::<6, 6>(6 * i, 6 * i).copy_from(b);
    }
    out
}

/// The 6x6 diagonal blocks of a block-diagonal `matrix` (six coordinates per body).
pub(super) fn diagonal_blocks(matrix: &DMatrix<f64>) -> Vec<Matrix6<f64>> {
    (0..matrix.nrows() / 6).map(|i| matrix.fixed_view::<6, 6>(6 * i, 6 * i).into_owned()).collect()
}
