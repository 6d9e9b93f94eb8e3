//! What the sensitivities of an equilibrium held by constraints (joints that close loops, taut
//! inextensible cables) need of the simulation, in the coordinates and with the Lagrangian of
//! the constrained modal analysis (`constrained_modes.rs`): q, the multibodies' free degrees of
//! freedom and six per plain free body; g(q) = 0 the constraint rows; L = V + lambda . g with
//! the constraint forces lambda of the settled state held.
//!
//! At an equilibrium Q = -dL/dq = 0 and g = 0. Along a parameter p (implicit function theorem
//! on both, K = d2L/dq2 and G = dg/dq):
//!   -K dq/dp + dQ/dp - G^T dlambda/dp = 0,   G dq/dp + dg/dp = 0,
//! with dQ/dp and dg/dp at fixed q and lambda (`run/sensitivity.rs` differences them over
//! structures built again at p +- h, p +- 2 h, put in the settled configuration). Its solution
//! with N a basis of null(G): dq/dp = q_p + N (N^T K N)^-1 N^T (dQ/dp - K q_p), where
//! q_p = -G^+ dg/dp moves the constraints back onto themselves (zero when p does not enter
//! them: a stiffness, an elastic rest length, a mass); then G^T dlambda/dp = dQ/dp - K dq/dp.
//! The frequencies: the reduced problem (N^T K N) v = omega^2 (N^T M N) v has, for any smooth
//! basis N(p), d omega^2/dp = v^T (d(N^T K N)/dp - omega^2 d(N^T M N)/dp) v (Nelson 1976); with
//! N(p) the projection of N onto null(G(p)) it is the derivative of
//! phi_p^T (K - omega^2 M) phi_p, phi_p = (1 - G^+ G) phi, phi = N v.

use super::constrained_modes::{Constraints, ModalCoordinate};
use super::data::Data;
use super::model::{LinkRef, Model};
use nalgebra::{DMatrix, DVector};
use rapier3d_f64::prelude::MultibodyIndex;

impl Data {
    /// Q = -dL/dq = -(grad V + G^T lambda) now, lambda held at `c`'s [N or N m].
    pub(super) fn lagrangian_forces(&mut self, m: &Model, c: &Constraints) -> DVector<f64> {
        let setup = self.constrained_setup(m, &c.coordinates, &c.closures, &c.taut_cables);
        let first = self.first_derivatives_extrapolated(m, &setup);
        let lambda = DVector::from_column_slice(&c.multipliers);
        -(first.gradient + first.jacobian.transpose() * lambda)
    }

    /// G = dg/dq now (extrapolated central differences).
    pub(super) fn constraint_jacobian(&mut self, m: &Model, c: &Constraints) -> DMatrix<f64> {
        let setup = self.constrained_setup(m, &c.coordinates, &c.closures, &c.taut_cables);
        self.first_derivatives_extrapolated(m, &setup).jacobian
    }

    /// g(q) now [m]: each closure's rows, then each taut cable's stretch.
    pub(super) fn constraint_values(&self, m: &Model, c: &Constraints) -> DVector<f64> {
        DVector::from_vec(self.constraint_rows(m, &c.closures, &c.taut_cables))
    }

    /// K = d2L/dq2 now, lambda held at `c`'s (Richardson over h and 2 h), and the size of its
    /// error (the difference between the two steps).
    pub(super) fn lagrangian_stiffness(&mut self, m: &Model, c: &Constraints) -> (DMatrix<f64>, DMatrix<f64>) {
        let setup = self.constrained_setup(m, &c.coordinates, &c.closures, &c.taut_cables);
        let lambda = DVector::from_column_slice(&c.multipliers);
        self.lagrangian_stiffness_and_error(m, &setup, &lambda)
    }

    /// The mass matrix in `c`'s coordinates.
    pub(super) fn constrained_mass(&mut self, m: &Model, c: &Constraints) -> DMatrix<f64> {
        let setup = self.constrained_setup(m, &c.coordinates, &c.closures, &c.taut_cables);
        let bodies: Vec<usize> = (0..m.structure.bodies.len()).filter(|&b| m.is_free(b)).collect();
        self.coordinate_mass(m, &setup, &bodies).0
    }

    /// Puts this structure (the same as `from`'s, built with other parameters) in `from`'s
    /// configuration: each multibody's joint coordinates (about this structure's own joint
    /// frames) and each plain free body's pose.
    pub(super) fn take_constrained_configuration(&mut self, m: &Model, from: &Data, c: &Constraints) {
        let mut multibodies: Vec<MultibodyIndex> = Vec::new();
        for coordinate in &c.coordinates {
            match *coordinate {
                ModalCoordinate::Link { multibody, .. } if !multibodies.contains(&multibody) => {
                    multibodies.push(multibody);
                    let Some(source) = from.multibody_joints.get_multibody(multibody) else { continue };
                    let Some(mb) = self.multibody_joints.get_multibody_mut(multibody) else { continue };
                    for (i, link) in source.links().enumerate() {
                        if let Some(own) = mb.link_mut(i) {
                            // The coordinates are `from`'s, the frames and motors this one's.
                            let mut joint = *link.joint();
                            joint.data = own.joint.data;
                            joint.kinematic = own.joint.kinematic;
                            own.joint = joint;
                        }
                    }
                    mb.forward_kinematics(&self.bodies, false);
                    mb.update_rigid_bodies(&mut self.bodies, true);
                }
                ModalCoordinate::Body { body, axis: 0 } => {
                    let pose = *from.bodies[m.handles[body]].position();
                    self.bodies[m.handles[body]].set_position(pose, true);
                }
                _ => {}
            }
        }
    }

    /// Each coordinate's name: the joint whose link carries it (`JOINT.axis1` and `.axis2` for
    /// the two links of a universal joint), or `BODY.x` .. `BODY.rz`.
    pub(super) fn modal_coordinate_names(&self, m: &Model, coordinates: &[ModalCoordinate]) -> Vec<String> {
        let s = &m.structure;
        let mut links: Vec<(LinkRef, String)> = Vec::new();
        let mut hidden = m.hidden_links.iter();
        for (j, link) in m.joint_links.iter().enumerate() {
            let Some(link) = link else { continue };
            let name = &s.joints[j].name;
            if matches!(s.joints[j].kind, crate::structure::JointKind::Universal { .. }) {
                if let Some(first) = hidden.next() {
                    links.push((*first, format!("{name}.axis1")));
                }
                links.push((*link, format!("{name}.axis2")));
            } else {
                links.push((*link, name.clone()));
            }
        }
        // Each link's multibody and the range of its degrees of freedom there.
        let span = |l: &LinkRef| {
            let (mb, id) = self.multibody_joints.get(l.multibody_joint)?;
            let link = mb.link(id)?;
            let index = self.multibody_joints.rigid_body_link(link.rigid_body_handle())?.multibody;
            Some((index, link.assembly_id()..link.assembly_id() + link.joint().ndofs()))
        };
        let axes = ["x", "y", "z", "rx", "ry", "rz"];
        coordinates
            .iter()
            .map(|q| match *q {
                ModalCoordinate::Body { body, axis } => format!("{}.{}", s.bodies[body].name, axes[axis]),
                ModalCoordinate::Link { multibody, dof, .. } => links
                    .iter()
                    .find(|(l, _)| span(l).is_some_and(|(i, range)| i == multibody && range.contains(&dof)))
                    .map_or_else(|| format!("multibody dof {dof}"), |(_, name)| name.clone()),
            })
            .collect()
    }
}
