//! The linear (small-displacement) analysis of a pin-jointed structure: the displacement
//! method of structural analysis about a reference state, as MusclePy's linear method and
//! every structural code state it.
//!
//! About the reference (the structure settled without its point loads, its member tensions
//! t0), the loads f at the free nodes' coordinates move the nodes by d with K d = f, where
//! K = A diag(k) A^T + G is the tangent stiffness at the reference: A the equilibrium matrix
//! (`equilibrium.rs`), k each member's axial stiffness EA / L0 (zero for a cable slack at the
//! reference), and G the geometric (prestress) stiffness, (t0 / l)(1 - e e^T) per segment of
//! length l along e. The members' forces are then t0 - k (A^T d): the elongations to first
//! order are -A^T d, A's columns being minus the members' length gradients. The answer is exact to first order in the loads; the exact one (the settle under
//! the loads) differs at second order, by the change of geometry the linear method ignores.

use super::equilibrium::{displacements_by_node, matrix, row_index, EquilibriumError};
use super::{MemberId, NodeId, NodeLoad, Structure, Vec3};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// Eigenvalues of K below this fraction of the largest count as zero: a mechanism that no
/// member and no prestress stiffens, where the linear analysis has no unique answer.
pub const SINGULAR_RATIO: f64 = 1e-10;

/// The linear analysis's answer.
#[derive(Clone, Debug)]
pub struct LinearAnalysis {
    /// The free nodes, and each one's displacement \[m\] (zero along its held directions).
    pub displacements_m: Vec<(NodeId, Vec3)>,
    /// The members with a free node, and each one's force t0 + k e \[N\], e its elongation.
    pub forces_n: Vec<(MemberId, f64)>,
}

/// The linear analysis of `s` about the reference `positions` \[m\] with member tensions
/// `tension` \[N\] there, under the point `loads` \[N\]. Refused: a rigid strut or an
/// inextensible cable (no EA), a cable with friction (its tension depends on its path), and a
/// K that is singular or indefinite (a mechanism, or an unstable reference).
pub fn linear_analysis(
    s: &Structure,
    positions: &[Vec3],
    tension: &dyn Fn(MemberId) -> f64,
    loads: &[NodeLoad],
) -> Result<LinearAnalysis, EquilibriumError> {
    let ((nodes, rows, members), a) = matrix(s, positions)?;
    let stiffness = axial_stiffnesses(s, positions, &members)?;
    let row = row_index(s, &rows);
    let mut k = &a * DMatrix::from_diagonal(&DVector::from_vec(stiffness.clone())) * a.transpose();
    for &m in &members {
        add_geometric(&mut k, &row, s, positions, m, tension(m));
    }
    let mut f = DVector::zeros(rows.len());
    for load in loads {
        for (x, r) in row[load.node].iter().enumerate() {
            if let Some(r) = r {
                f[*r] += load.force_n[x];
            }
        }
    }
    let d = solve(k, &f)?;
    // A's columns are minus the members' length gradients (a tension pulls a node towards the
    // member's other end), so the elongations are -A^T d.
    let elongation = -(a.transpose() * &d);
    let forces_n = members.iter().enumerate().map(|(c, &m)| (m, tension(m) + stiffness[c] * elongation[c])).collect();
    Ok(LinearAnalysis { displacements_m: displacements_by_node(&nodes, &rows, &d), forces_n })
}

/// Each member's axial stiffness EA / L0 \[N/m\] at the reference (zero for a cable slack
/// there), or the member the linear analysis cannot take.
fn axial_stiffnesses(s: &Structure, positions: &[Vec3], members: &[MemberId]) -> Result<Vec<f64>, EquilibriumError> {
    let refuse = |m: MemberId, why: &str| Err(EquilibriumError(format!("member '{}' {why}", s.members[m].name)));
    let mut out = Vec::with_capacity(members.len());
    for &m in members {
        let member = &s.members[m];
        if member.has_friction() {
            return refuse(m, "has friction at a node: its tension depends on its path, not on the state");
        }
        let (Some(k), Some(rest)) = (member.stiffness_n_per_m(), member.rest_length_m()) else {
            return refuse(m, "has no axial stiffness (a rigid strut or an inextensible cable): give it EA or a stiffness for the linear analysis");
        };
        let engaged = member.elastic_law(rest).is_some_and(|law| law.engaged(member.length_at(|n| positions[n])));
        out.push(if engaged { k } else { 0.0 });
    }
    Ok(out)
}

/// Adds member `m`'s geometric stiffness at tension `t` \[N\]: (t / l)(1 - e e^T) per segment,
/// at its two ends' rows, subtracted across them.
fn add_geometric(k: &mut DMatrix<f64>, row: &[[Option<usize>; 3]], s: &Structure, at: &[Vec3], m: MemberId, t: f64) {
    for (p, q) in s.members[m].segments() {
        let d = Vector3::from(at[q]) - Vector3::from(at[p]);
        let e = d / d.norm();
        let g = (Matrix3::identity() - e * e.transpose()) * (t / d.norm());
        for (i, j, sign) in [(p, p, 1.0), (q, q, 1.0), (p, q, -1.0), (q, p, -1.0)] {
            for (x, y) in (0..3).flat_map(|x| (0..3).map(move |y| (x, y))) {
                if let (Some(r), Some(c)) = (row[i][x], row[j][y]) {
                    k[(r, c)] += sign * g[(x, y)];
                }
            }
        }
    }
}

/// d = K^-1 f, where K is positive definite; otherwise why not.
fn solve(k: DMatrix<f64>, f: &DVector<f64>) -> Result<DVector<f64>, EquilibriumError> {
    let eigen = (0.5 * (&k + k.transpose())).symmetric_eigen();
    let largest = eigen.eigenvalues.amax();
    let lowest = eigen.eigenvalues.min();
    if lowest < -SINGULAR_RATIO * largest {
        return Err(EquilibriumError(format!(
            "the reference state is unstable (its tangent stiffness has an eigenvalue of {lowest:e}): the linear analysis needs a stable one"
        )));
    }
    if lowest <= SINGULAR_RATIO * largest {
        return Err(EquilibriumError(format!(
            "the tangent stiffness is singular (lowest eigenvalue {lowest:e}, largest {largest:e}): a mechanism that neither the members nor the prestress stiffen has no unique linear answer"
        )));
    }
    let modal = eigen.eigenvectors.transpose() * f;
    let scaled = modal.component_div(&eigen.eigenvalues);
    Ok(&eigen.eigenvectors * scaled)
}
