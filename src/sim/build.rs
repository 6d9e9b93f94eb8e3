//! Structure -> rapier sets.

use super::data::Data;
use super::joint_data::{generic_joint, link_damping, locked_joint, set_link_damping, v};
use super::model::Tree;
use super::model::{LinkRef, Model, SimError};
use crate::settings::SimSettings;
use crate::structure::{ActuatorTarget, BodyKind, CableLaw, Joint, JointKind, Law, MemberKind, Structure, Vec3};
use rapier3d_f64::prelude::*;

/// The model and the data of `s`: the model is complete when this returns, and nothing
/// writes it after. The commands are not yet applied (`Simulation::new` applies them).
pub(super) fn build(s: &Structure, settings: &SimSettings) -> Result<(Model, Data), SimError> {
    check_settings(settings)?;
    let n = s.bodies.len();
    let actuated = actuated_joints(s)?;
    let (mut bodies, handles) = insert_bodies(s, settings);
    let joints = insert_joints(s, &mut bodies, &handles, &actuated, settings_body_damping(settings))?;
    let Joints { mut impulse_joints, multibody_joints, joint_links, joint_impulse, hidden_links } = joints;
    let ropes = insert_ropes(s, &mut impulse_joints, &handles)?;
    let mut model = Model {
        structure: s.clone(),
        settings: settings.clone(),
        handles,
        actuated,
        joint_links,
        hidden_links,
        joint_impulse,
        internal_closures: Vec::new(),
        projected_groups: Vec::new(),
        ropes,
        has_friction: s.members.iter().any(|m| m.has_friction()),
        external_loads: external_loads(s),
        node_loads: s
            .node_loads
            .iter()
            .filter(|l| s.bodies[s.nodes[l.node].body].kind == crate::structure::BodyKind::Free)
            .map(|l| (l.node, nalgebra::Vector3::from(l.force_n)))
            .collect(),
        length_scale_m: crate::structure::structure_size(s),
        tree: Tree::default(),
        fit_tree: Tree::default(),
        relaxation_applies: super::relaxation::applies(s),
        point_masses: crate::structure::lumped::point_masses(s),
        held_translations: s.held_translations(),
    };
    let mut data = Data {
        pipeline: PhysicsPipeline::new(),
        params: integration_parameters(settings),
        islands: IslandManager::new(),
        broad_phase: BroadPhaseBvh::new(),
        narrow_phase: NarrowPhase::new(),
        bodies,
        colliders: ColliderSet::new(),
        impulse_joints,
        multibody_joints,
        soft_bodies: SoftBodySet::new(),
        ccd: CCDSolver::new(),
        rest_lengths: s.members.iter().map(|m| m.rest_length_m().unwrap_or(0.0)).collect(),
        material: s.members.iter().map(|m| super::capstan::initial_material(m, |n| s.nodes[n].position)).collect(),
        at_bound: s.members.iter().map(|m| vec![false; m.friction.len()]).collect(),
        commands: s.initial_commands(),
        probe_loads: vec![([0.0; 3], [0.0; 3]); n],
        tick: 0,
        locked_coordinates: vec![0.0; s.joints.len()],
        constraint_inputs: 0,
        kept_momenta: vec![None; n],
    };
    data.settle_multibody_roots(&model);
    model.tree = data.link_tree(&model);
    model.internal_closures = data.find_internal_closures(&model);
    model.projected_groups = data.find_projected_groups(&model);
    check_supports(&model)?;
    model.fit_tree = data.fit_tree(&model);
    Ok((model, data))
}

/// A support in some directions holds a body that rapier steps alone: not a multibody link and
/// not in a projected group, whose projection moves its coordinates freely.
fn check_supports(m: &Model) -> Result<(), SimError> {
    let s = &m.structure;
    for support in &s.supports {
        let b = s.nodes[support.node].body;
        if m.tree.hang[b].is_some() || m.projected_groups.iter().any(|g| g.bodies.contains(&b)) {
            return Err(SimError::Build(format!(
                "the support at node '{}' holds a body that a joint or an inextensible cable holds too; a support in some directions takes a point mass held by elastic members",
                s.nodes[support.node].name
            )));
        }
    }
    Ok(())
}

impl Data {
    /// rapier counts a fixed root's six degrees of freedom until the multibody's first forward
    /// kinematics: every multibody's root is settled here, so that the degree-of-freedom
    /// indices read before the first step (the loops' projection at the drawn configuration)
    /// stay valid through it. Without it an unactuated looped multibody (a four-bar hung from
    /// the base) panicked at its first projection.
    fn settle_multibody_roots(&mut self, m: &Model) {
        let mut settled = Vec::new();
        for (j, link) in m.joint_links.iter().enumerate() {
            let Some(link) = link else { continue };
            let child = m.handles[m.structure.joints[j].child];
            let Some(index) = self.multibody_joints.rigid_body_link(child).map(|l| l.multibody) else { continue };
            if settled.contains(&index) {
                continue;
            }
            settled.push(index);
            if let Some((mb, _)) = self.multibody_joints.get_mut(link.multibody_joint) {
                mb.forward_kinematics(&self.bodies, true);
            }
        }
    }
}

fn check_settings(settings: &SimSettings) -> Result<(), SimError> {
    if !(settings.dt_s > 0.0 && settings.dt_s.is_finite()) {
        return Err(SimError::Build(format!("time step must be > 0 s, got {}", settings.dt_s)));
    }
    if settings.substeps == 0 || settings.pgs_iterations == 0 {
        return Err(SimError::Build("substeps and PGS iterations must be at least 1".into()));
    }
    Ok(())
}

/// For each joint: whether an actuator drives it (position-controlled, a kinematic degree of
/// freedom of a multibody; a servo's joint stays free). Two actuators on one joint are an error.
fn actuated_joints(s: &Structure) -> Result<Vec<bool>, SimError> {
    let mut actuated = vec![false; s.joints.len()];
    for a in &s.actuators {
        if let ActuatorTarget::Joint(j) = a.target {
            if actuated[j] {
                return Err(SimError::Build(format!("joint '{}' is driven by two actuators", s.joints[j].name)));
            }
            actuated[j] = true;
        }
    }
    for (j, a) in actuated.iter_mut().enumerate() {
        *a &= s.servo_of(j).is_none();
    }
    Ok(actuated)
}

/// One rapier body per structure body (free bodies never sleep, with explicit mass
/// properties), and their handles in structure order.
fn insert_bodies(s: &Structure, settings: &SimSettings) -> (RigidBodySet, Vec<RigidBodyHandle>) {
    let mut bodies = RigidBodySet::new();
    let mut handles = Vec::with_capacity(s.bodies.len());
    for (b, held) in s.bodies.iter().zip(s.held_translations()) {
        let builder = if b.kind == BodyKind::Fixed {
            RigidBodyBuilder::fixed()
        } else {
            let inertia = b.inertia.expect("validated: free bodies have inertia");
            RigidBodyBuilder::dynamic()
                .can_sleep(false)
                .additional_mass_properties(MassProperties::new(
                    v(inertia.com),
                    inertia.mass_kg,
                    v(inertia.principal_kg_m2),
                ))
                .linear_damping(settings_body_damping(settings))
                .angular_damping(settings_body_damping(settings))
                .enabled_translations(!held[0], !held[1], !held[2])
        };
        handles.push(bodies.insert(builder.build()));
    }
    (bodies, handles)
}

/// The rapier joints of a structure: multibody links along the planned forest, impulse joints
/// for the rest.
struct Joints {
    impulse_joints: ImpulseJointSet,
    multibody_joints: MultibodyJointSet,
    joint_links: Vec<Option<LinkRef>>,
    joint_impulse: Vec<Option<ImpulseJointHandle>>,
    hidden_links: Vec<LinkRef>,
}

fn insert_joints(
    s: &Structure,
    bodies: &mut RigidBodySet,
    handles: &[RigidBodyHandle],
    actuated: &[bool],
    body_damping_per_s: f64,
) -> Result<Joints, SimError> {
    let mut out = Joints {
        impulse_joints: ImpulseJointSet::new(),
        multibody_joints: MultibodyJointSet::new(),
        joint_links: vec![None; s.joints.len()],
        joint_impulse: vec![None; s.joints.len()],
        hidden_links: Vec::new(),
    };
    let mut fixed_roots: std::collections::BTreeMap<usize, RigidBodyHandle> = std::collections::BTreeMap::new();
    // Bodies held by inextensible cables stay plain rigid bodies, joined by impulse joints:
    // the configuration measured to 1e-13 on mohr2011.
    let mut roped = vec![false; s.bodies.len()];
    for c in s.members.iter().filter(|c| c.is_inextensible_cable()) {
        for &n in &c.path {
            roped[s.nodes[n].body] = true;
        }
    }
    let tree = plan_tree(s, &roped, actuated)?;
    for (j, joint) in s.joints.iter().enumerate() {
        let (mut h1, h2) = (handles[joint.parent], handles[joint.child]);
        if !tree[j] {
            // An actuated joint off the tree is locked at its command (the drawn configuration
            // until a command moves it).
            let data = if actuated[j] { locked_joint(s, joint, 0.0) } else { generic_joint(s, joint) };
            out.joint_impulse[j] = Some(out.impulse_joints.insert(h1, h2, data, true));
            continue;
        }
        // A multibody hung from a fixed body gets its own fixed root: impulse joints (cables)
        // attached to a fixed body that is also a multibody root had no effect in rapier 0.36
        // (measured: six rope joints from the base let the end-effector fly away).
        if s.bodies[joint.parent].kind == BodyKind::Fixed {
            let root =
                *fixed_roots.entry(joint.parent).or_insert_with(|| bodies.insert(RigidBodyBuilder::fixed().build()));
            h1 = root;
        }
        let mb = &mut out.multibody_joints;
        let link = match &joint.kind {
            JointKind::Universal { axis1, axis2 } => {
                let (link, first) = insert_universal(s, joint, [*axis1, *axis2], bodies, mb, h1, h2);
                out.hidden_links.push(first);
                link
            }
            // An ideal position actuator: a kinematic degree of freedom, set by the command.
            _ if actuated[j] => mb.insert_kinematic(h1, h2, generic_joint(s, joint), true).expect("checked: no loop"),
            _ => mb.insert(h1, h2, generic_joint(s, joint), true).expect("checked: no loop"),
        };
        set_link_damping(mb, link, link_damping(s, j, body_damping_per_s));
        out.joint_links[j] = Some(LinkRef { multibody_joint: link });
    }
    Ok(out)
}

/// rapier's 2-DoF multibody joints are `todo!()`: a universal joint becomes two revolute links
/// through a hidden body that sits at the anchor. The hidden body has no mass: the child turns
/// with it about the first axis, so the multibody's mass matrix stays the child's (positive
/// definite wherever the child's is) and the joint's dynamics are exactly the child's. Returns
/// the second link (the joint's own) and the first (hidden) one.
fn insert_universal(
    s: &Structure,
    joint: &Joint,
    axes: [Vec3; 2],
    bodies: &mut RigidBodySet,
    multibody_joints: &mut MultibodyJointSet,
    h1: RigidBodyHandle,
    h2: RigidBodyHandle,
) -> (MultibodyJointHandle, LinkRef) {
    let anchor = v(s.nodes[joint.anchor].position);
    let hidden = bodies.insert(RigidBodyBuilder::dynamic().can_sleep(false).gravity_scale(0.0).build());
    let revolute =
        |axis: Vec3| RevoluteJointBuilder::new(v(axis).normalize()).local_anchor1(anchor).local_anchor2(anchor).build();
    let h_first = multibody_joints.insert(h1, hidden, revolute(axes[0]), true).expect("checked: no loop");
    set_link_damping(multibody_joints, h_first, joint.damping);
    let second = multibody_joints.insert(hidden, h2, revolute(axes[1]), true).expect("checked: no loop");
    (second, LinkRef { multibody_joint: h_first })
}

/// One rope joint per inextensible cable, member order (None for every other member: springs
/// and elastic cables are explicit forces). An inextensible cable is straight (validated).
fn insert_ropes(
    s: &Structure,
    impulse_joints: &mut ImpulseJointSet,
    handles: &[RigidBodyHandle],
) -> Result<Vec<Option<ImpulseJointHandle>>, SimError> {
    let mut ropes = vec![None; s.members.len()];
    for (c, cable) in s.members_of(MemberKind::Cable) {
        if let Law::Cable { law: CableLaw::Inextensible, length_m } = cable.law {
            let (a, b) = cable.ends();
            let (na, nb) = (&s.nodes[a], &s.nodes[b]);
            if na.body == nb.body {
                return Err(SimError::Build(format!("cable '{}' joins two nodes of the same body", cable.name)));
            }
            let rope =
                RopeJointBuilder::new(length_m).local_anchor1(v(na.position)).local_anchor2(v(nb.position)).build();
            ropes[c] = Some(impulse_joints.insert(handles[na.body], handles[nb.body], rope, true));
        }
    }
    Ok(ropes)
}

fn integration_parameters(settings: &SimSettings) -> IntegrationParameters {
    IntegrationParameters {
        dt: settings.dt_s,
        num_solver_iterations: settings.substeps,
        num_internal_pgs_iterations: settings.pgs_iterations,
        // rapier caps body speeds at 400 m/s by default: a numerical blow-up would then look
        // like a bounded oscillation. Uncapped, it shows as divergence (energy, bounding box, NaN).
        normalized_max_linear_velocity: Real::MAX,
        ..IntegrationParameters::default()
    }
}

/// The structure's constant external forces, summed per body [N].
fn external_loads(s: &Structure) -> Vec<[f64; 3]> {
    let mut l = vec![[0.0; 3]; s.bodies.len()];
    for load in &s.loads {
        for (sum, f) in l[load.body].iter_mut().zip(load.force_n) {
            *sum += f;
        }
    }
    l
}

/// Chooses which joints are multibody links (the rest become impulse joints). A joint is a
/// link when its child is free, not held by an inextensible cable, has no link yet, and its
/// parent hangs (through links) from a fixed body: a spanning forest rooted at the ground, in
/// joint order. Measured on furet2018 (`scenarios/furet2018/FINDINGS.md`): multibodies
/// rooted at a free body let the impulse joints on their links drift (gaps of 0.1 m); a loop
/// closed between two links of one multibody holds at the velocity level but its position
/// error is not corrected (exact for a configuration built in place and held, a gap after an
/// actuator jump). A loop-closing joint
/// whose two bodies would sit in the same multibody is a problem: rapier did not correct the
/// position error of such a joint (measured on furet2018: a 3.7e-5 m gap at D1 that stayed), so
/// the forest is cut on that loop, at the first non-actuated link above the closure's child,
/// and the closure then joins two different multibodies.
fn plan_tree(s: &Structure, roped: &[bool], actuated: &[bool]) -> Result<Vec<bool>, SimError> {
    // Cutting a link can leave bodies above it hanging from a free body: plan again without the
    // cut links until no loop needs a cut.
    let mut banned = vec![false; s.joints.len()];
    loop {
        let (mut is_link, cuts) = plan_forest(s, roped, actuated, &banned)?;
        if cuts.is_empty() {
            unlink_long_looped_multibodies(s, &mut is_link);
            return Ok(is_link);
        }
        for c in cuts {
            banned[c] = true;
        }
    }
}

/// Multibodies with loops closed inside them (planar pins) and more links than this are cut
/// into plain bodies held by impulse joints (the actuated ones locked at their commands), all
/// closed by the position projection with sparse factorizations. rapier's multibody step
/// assembles and factorizes a dense mass matrix over every link (its cost grows as the cube of
/// the links); the plain bodies' step and the sparse projection grow linearly. Measured on
/// furet2018's X chains (three links an X; BENCHMARKS.md, "X chains at scale"), a settle with
/// the multibody against cut, once a rigid cut chain goes back to its closed configuration at
/// rest without solves (`projection.rs`): 2 X 0.29 against 1.48 ms (its 36 coordinates take the
/// dense projection), 3 X 0.44 against 0.37, 4 X 0.67 against 0.51.
pub const LOOPED_MULTIBODY_MAX_LINKS: usize = 8;

/// Turns every link of a multibody (the links hung from one fixed body) into an impulse joint
/// when a planar pin closes a loop inside it and it has more than
/// [`LOOPED_MULTIBODY_MAX_LINKS`] links.
fn unlink_long_looped_multibodies(s: &Structure, is_link: &mut [bool]) {
    let mut parent_joint: Vec<Option<usize>> = vec![None; s.bodies.len()];
    for (j, joint) in s.joints.iter().enumerate().filter(|(j, _)| is_link[*j]) {
        parent_joint[joint.child] = Some(j);
    }
    let roots = forest_roots(s, &parent_joint, is_link);
    let root = |b: usize| roots[b];
    let mut links_of_root = vec![0_usize; s.bodies.len()];
    for joint in s.joints.iter().enumerate().filter(|(j, _)| is_link[*j]).map(|(_, joint)| joint) {
        links_of_root[root(joint.child)] += 1;
    }
    let mut cut_root = vec![false; s.bodies.len()];
    for joint in s.joints.iter().filter(|j| matches!(j.kind, JointKind::PlanarPin { .. })) {
        let r = root(joint.child);
        cut_root[r] |= r == root(joint.parent) && links_of_root[r] > LOOPED_MULTIBODY_MAX_LINKS;
    }
    let roots: Vec<usize> = s.joints.iter().map(|joint| root(joint.child)).collect();
    for (j, r) in roots.into_iter().enumerate() {
        if is_link[j] && cut_root[r] {
            is_link[j] = false;
        }
    }
}

/// One planning pass: the forest of links (joints not `banned`), then the links to cut so that
/// no closure joins two bodies of one multibody.
fn plan_forest(
    s: &Structure,
    roped: &[bool],
    actuated: &[bool],
    banned: &[bool],
) -> Result<(Vec<bool>, Vec<usize>), SimError> {
    let (parent_joint, mut is_link) = link_forest(s, roped, banned);
    let mut cuts = Vec::new();
    for (j, joint) in s.joints.iter().enumerate() {
        if is_link[j] {
            continue;
        }
        let (u, v) = (joint.parent, joint.child);
        if forest_root(s, &parent_joint, &is_link, u) != forest_root(s, &parent_joint, &is_link, v) {
            continue;
        }
        // A planar pin closes a planar loop inside its multibody: cutting there would leave the
        // rest of the mechanism hanging from a free body (worse, measured on furet2018).
        if matches!(joint.kind, JointKind::PlanarPin { .. }) {
            continue;
        }
        match loop_cut(s, &parent_joint, &is_link, actuated, (u, v)) {
            Some(pj) => {
                is_link[pj] = false;
                cuts.push(pj);
            }
            None => {
                return Err(SimError::Build(format!(
                    "joint '{}' closes a loop made only of actuated joints",
                    joint.name
                )))
            }
        }
    }
    Ok((is_link, cuts))
}

/// The body at the root of `b`'s branch of the forest (following link joints to parents).
fn forest_root(s: &Structure, parent_joint: &[Option<usize>], is_link: &[bool], mut b: usize) -> usize {
    while let Some(j) = parent_joint[b] {
        if !is_link[j] {
            break;
        }
        b = s.joints[j].parent;
    }
    b
}

/// Every body's [`forest_root`], each branch walked once (walking up from every body grew with
/// the square of a chain's length: a fifth of building a 100-X furet2018 chain).
fn forest_roots(s: &Structure, parent_joint: &[Option<usize>], is_link: &[bool]) -> Vec<usize> {
    let mut root: Vec<Option<usize>> = vec![None; s.bodies.len()];
    let mut below = Vec::new();
    for b in 0..s.bodies.len() {
        let mut x = b;
        let r = loop {
            if let Some(r) = root[x] {
                break r;
            }
            match parent_joint[x].filter(|&j| is_link[j]) {
                Some(j) => {
                    below.push(x);
                    x = s.joints[j].parent;
                }
                None => break x,
            }
        };
        root[x] = Some(r);
        for y in below.drain(..) {
            root[y] = Some(r);
        }
    }
    root.into_iter().map(|r| r.expect("every body walked")).collect()
}

/// The forest of links: each free body (not roped) hangs by at most one joint (not banned,
/// not a planar pin) from a branch rooted in a fixed body. Each body's parent joint, and which
/// joints are links. The branches' roots are kept in a union-find whose representatives are
/// the roots: a body that hangs from nothing yet is its branch's root.
fn link_forest(s: &Structure, roped: &[bool], banned: &[bool]) -> (Vec<Option<usize>>, Vec<bool>) {
    let mut parent_joint: Vec<Option<usize>> = vec![None; s.bodies.len()];
    let mut is_link = vec![false; s.joints.len()];
    let mut up: Vec<usize> = (0..s.bodies.len()).collect();
    for (j, joint) in s.joints.iter().enumerate() {
        let free = s.bodies[joint.child].kind == BodyKind::Free
            && !roped[joint.child]
            && !banned[j]
            && !matches!(joint.kind, JointKind::PlanarPin { .. });
        if !free || parent_joint[joint.child].is_some() {
            continue;
        }
        let parent_root = super::projection::find_root(&mut up, joint.parent);
        if s.bodies[parent_root].kind == BodyKind::Fixed && parent_root != joint.child {
            parent_joint[joint.child] = Some(j);
            is_link[j] = true;
            up[joint.child] = parent_root;
        }
    }
    (parent_joint, is_link)
}

/// The link to cut where a joint from body `u` to body `v` closes a loop in the forest: the
/// first unactuated link on `v`'s path up to where it meets `u`'s, else on `u`'s path; None
/// when the loop is made only of actuated joints.
fn loop_cut(
    s: &Structure,
    parent_joint: &[Option<usize>],
    is_link: &[bool],
    actuated: &[bool],
    (u, v): (usize, usize),
) -> Option<usize> {
    // Ancestors of u (bodies), to find where v's path meets u's.
    let mut above_u = vec![u];
    let mut b = u;
    while let Some(pj) = parent_joint[b].filter(|pj| is_link[*pj]) {
        b = s.joints[pj].parent;
        above_u.push(b);
    }
    let mut b = v;
    while !above_u.contains(&b) {
        let Some(pj) = parent_joint[b].filter(|pj| is_link[*pj]) else { break };
        if !actuated[pj] {
            return Some(pj);
        }
        b = s.joints[pj].parent;
    }
    // Try u's side of the loop.
    let mut b = u;
    while let Some(pj) = parent_joint[b].filter(|pj| is_link[*pj]) {
        if !actuated[pj] {
            return Some(pj);
        }
        b = s.joints[pj].parent;
    }
    None
}

/// Linear and angular damping of free bodies [1/s]; zero: joint damping does the work.
fn settings_body_damping(settings: &SimSettings) -> f64 {
    settings.body_damping_per_s
}

#[cfg(test)]
mod tests {
    use crate::settings::SimSettings;
    use crate::sim::joint_coordinates::tests::four_bar_chain;
    use crate::sim::Simulation;

    /// Steps of the test run.
    const STEPS: usize = 20;

    /// Each body's root, walked once per branch, is the one walking up from it finds, on the
    /// link forests of four-bar chains of 1 to 12 modules (three links a module, up to 36
    /// deep).
    #[test]
    fn the_roots_walked_once_are_the_roots_walked_from_every_body() {
        for modules in 1..=12 {
            let s = four_bar_chain(modules);
            let none = vec![false; s.joints.len()];
            let (parent_joint, is_link) = super::link_forest(&s, &vec![false; s.bodies.len()], &none);
            assert!(is_link.iter().filter(|l| **l).count() >= 3 * modules, "{modules} modules: a link a bar");
            let roots = super::forest_roots(&s, &parent_joint, &is_link);
            for (b, root) in roots.into_iter().enumerate() {
                assert_eq!(root, super::forest_root(&s, &parent_joint, &is_link, b), "{modules} modules, body {b}");
            }
        }
    }

    /// A two-module four-bar chain with no actuator (a looped multibody of six links, hung from
    /// the base, whose roots rapier settles only at a forward kinematics) builds, and under
    /// gravity its loops stay closed by the projection: every joint's gap is at most 1e-12 m
    /// after each of 20 steps. It panicked at its first projection before the roots were
    /// settled at build.
    #[test]
    fn an_unactuated_looped_multibody_builds_and_keeps_its_loops_closed() {
        let mut s = four_bar_chain(2);
        s.gravity = [0.0, -9.81, 0.0];
        let mut sim = Simulation::new(&s, &SimSettings::default()).expect("builds");
        assert!(!sim.model.internal_closures.is_empty(), "its pins close loops inside one multibody");
        for _ in 0..STEPS {
            sim.step().expect("steps");
            let gap = (0..s.joints.len()).map(|j| sim.joint_gap_m(j)).fold(0.0, f64::max);
            assert!(gap <= 1e-12, "largest joint gap {gap:.2e} m");
        }
    }
}
