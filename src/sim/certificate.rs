//! The settled state as equilibrium equations for a proof (`crate::certify::Problem`): each
//! free body's centre of mass and the arms of its nodes, the rotation directions that move a
//! node, each elastic member's law at its current rest length, and the constant forces. A
//! structure outside the proof's domain is refused by name: joints, supports, inextensible and
//! clustered cables (`CertifyError`).

use super::data::Data;
use super::model::Model;
use crate::certify::{Block, Node, Problem, Spring};
use crate::structure::{CableLaw, Law};
use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// A rotation direction whose nodes' second moment about it is below this fraction of the
/// structure's size squared moves no node (a strut's spin, a point mass's turns): it is left
/// out.
const NODELESS_TURN_RATIO: f64 = 1e-12;

/// Why a settled state has no equilibrium equations to prove.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CertifyError {
    #[error("joint '{0}': certificates are built for free bodies on springs and elastic cables; jointed structures are not certified yet")]
    Joint(String),
    #[error("node '{0}' has a support: structures with supports are not certified yet")]
    Support(String),
    #[error(
        "cable '{0}' is inextensible: its length is a constraint, which the certificate's equations do not hold yet"
    )]
    Inextensible(String),
    #[error("cable '{0}' runs over pulleys (a clustered cable): not certified yet")]
    Clustered(String),
    #[error("no free body: nothing moves")]
    NoFreeBody,
}

impl Data {
    /// The equilibrium equations of the current state (module docs).
    pub(super) fn equilibrium_problem(&self, m: &Model) -> Result<Problem, CertifyError> {
        let s = &m.structure;
        if let Some(j) = s.joints.first() {
            return Err(CertifyError::Joint(j.name.clone()));
        }
        if let Some(support) = s.supports.first() {
            return Err(CertifyError::Support(s.nodes[support.node].name.clone()));
        }
        let members = self.certified_members(m)?;
        let (mut blocks, mut forces, mut block_of) = (Vec::new(), Vec::new(), vec![None; s.bodies.len()]);
        let mut first = 0;
        for (b, body) in s.bodies.iter().enumerate().filter(|(b, _)| m.is_free(*b)) {
            let com = self.world_com(m, b);
            let arms: Vec<Vector3<f64>> = (0..s.nodes.len())
                .filter(|&n| s.nodes[n].body == b)
                .map(|n| Vector3::from(self.node_position(m, n)) - Vector3::new(com.x, com.y, com.z))
                .collect();
            let rotations = moving_turns(&arms, m.length_scale_m);
            let mass = body.inertia.map_or(0.0, |i| i.mass_kg);
            let f: [f64; 3] = std::array::from_fn(|k| s.gravity[k] * mass + m.external_loads[b][k]);
            block_of[b] = Some(blocks.len());
            let count = 3 + rotations.len();
            blocks.push(Block { name: body.name.clone(), com: [com.x, com.y, com.z], rotations, first });
            forces.push(f);
            first += count;
        }
        if blocks.is_empty() {
            return Err(CertifyError::NoFreeBody);
        }
        let nodes = (0..s.nodes.len())
            .map(|n| {
                let p = self.node_position(m, n);
                match block_of[s.nodes[n].body] {
                    Some(block) => {
                        let c = blocks[block].com;
                        Node::OnBlock { block, arm: [p[0] - c[0], p[1] - c[1], p[2] - c[2]] }
                    }
                    None => Node::Fixed(p),
                }
            })
            .collect();
        Ok(with_turn_axis(Problem {
            length_m: m.length_scale_m,
            blocks,
            nodes,
            node_names: s.nodes.iter().map(|n| n.name.clone()).collect(),
            members,
            forces,
            node_loads: m.node_loads.iter().map(|(n, f)| (*n, [f.x, f.y, f.z])).collect(),
            turn_axis: None,
        }))
    }

    /// Each elastic member's law at its current rest length; rigid struts carry none.
    fn certified_members(&self, m: &Model) -> Result<Vec<Spring>, CertifyError> {
        let mut out = Vec::new();
        for (i, member) in m.structure.members.iter().enumerate() {
            match member.law {
                Law::Strut => continue,
                Law::Cable { law: CableLaw::Inextensible, .. } => {
                    return Err(CertifyError::Inextensible(member.name.clone()))
                }
                _ if member.is_clustered() => return Err(CertifyError::Clustered(member.name.clone())),
                _ => {}
            }
            let Some(law) = self.elastic_law(m, i) else { continue };
            out.push(Spring {
                name: member.name.clone(),
                a: member.path[0],
                b: member.path[1],
                stiffness_n_per_m: law.stiffness_n_per_m,
                rest_m: law.rest_length_m,
                tension_only: law.tension_only,
            });
        }
        Ok(out)
    }
}

/// The orthonormal rotation directions that move a node of arms `arms` (the eigenvectors of
/// their second moment sum |rho|^2 1 - rho rho^T above [`NODELESS_TURN_RATIO`] L^2).
fn moving_turns(arms: &[Vector3<f64>], length_m: f64) -> Vec<[f64; 3]> {
    let moment =
        arms.iter().fold(Matrix3::zeros(), |acc, r| acc + Matrix3::identity() * r.norm_squared() - r * r.transpose());
    let eigen = SymmetricEigen::new(moment);
    (0..3)
        .filter(|&k| eigen.eigenvalues[k] > NODELESS_TURN_RATIO * length_m * length_m)
        .map(|k| {
            let e = eigen.eigenvectors.column(k);
            [e[0], e[1], e[2]]
        })
        .collect()
}

/// Collinear within this fraction of the structure's size, parallel within this fraction of
/// a force: the free turn of [`Problem::turn_axis`] is taken as exact.
const AXIS_RATIO: f64 = 1e-12;

/// `problem` with its free turn, where every anchor (a fixed node that a member holds) lies on
/// one line and every constant force is along it.
fn with_turn_axis(mut problem: Problem) -> Problem {
    let anchors: Vec<Vector3<f64>> = problem
        .members
        .iter()
        .flat_map(|m| [m.a, m.b])
        .filter_map(|n| match problem.nodes[n] {
            Node::Fixed(p) => Some(Vector3::from(p)),
            Node::OnBlock { .. } => None,
        })
        .collect();
    let Some(a) = anchors.first().copied() else { return problem };
    let Some(far) = anchors.iter().max_by(|p, q| (*p - a).norm().total_cmp(&(*q - a).norm())) else { return problem };
    let l = problem.length_m;
    if (far - a).norm() <= AXIS_RATIO * l {
        return problem;
    }
    let u = (far - a).normalize();
    let on_line = anchors.iter().all(|p| (p - a).cross(&u).norm() <= AXIS_RATIO * l);
    let along = |f: &[f64; 3]| Vector3::from(*f).cross(&u).norm() <= AXIS_RATIO * Vector3::from(*f).norm();
    if on_line && problem.forces.iter().all(along) && problem.node_loads.iter().all(|(_, f)| along(f)) {
        problem.turn_axis = Some(([a.x, a.y, a.z], [u.x, u.y, u.z]));
    }
    problem
}
