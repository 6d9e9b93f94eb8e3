//! A [`Structure`] as MuJoCo MJCF XML (MuJoCo 3 or later; checked with mujoco 4.0.0).
//!
//! What becomes what (the attribute semantics are those of MuJoCo's `doc/XMLreference.rst`):
//!
//! - every body a `<body>` whose frame has the world's axes and, in the drawn configuration,
//!   its origin at the node of the joint it hangs from (free bodies: their centre of mass;
//!   fixed bodies: the world origin), with its mass, centre of mass and principal moments as
//!   `<inertial>`; fixed bodies are children of the world body without joints (welded);
//! - every node a `<site>` of the same name on its body; every strut whose two nodes are on
//!   one body a capsule `<geom>` of its radius (no contacts: `contype = conaffinity = 0`);
//! - the joints: a spanning forest in joint order, rooted at the fixed bodies, as MJCF
//!   joints (revolute `hinge`, prismatic `slide`, spherical `ball`, universal two hinges,
//!   fixed none) with `ref` = the joint's coordinate in the drawn configuration, so `qpos` and
//!   actuator commands are absolute as in the testbed; a torsion spring is the joint's
//!   `stiffness` with `springref` its rest angle; free bodies outside the forest get a free
//!   joint. The other joints close loops as `<equality>` rows: `connect` (spherical, planar
//!   pin; revolute: two connects on its axis), `weld` (fixed);
//! - springs spatial tendons with `stiffness` and `springlength` (pushing and pulling);
//!   elastic cables tendons with the dead band `springlength="0 L"` ("If the tendon length is
//!   between the two values, the force is 0. If it is outside this range, the force behaves
//!   like a regular spring, with the rest-point corresponding to the nearest springlength
//!   value", XMLreference `tendon-spatial-springlength`), i.e. tension k (l - L) beyond L and
//!   none below: the testbed's tension-only law; inextensible cables tendons `limited` to the
//!   range [0, L];
//! - actuators: the testbed's are ideal (a joint's coordinate *is* its command). In
//!   [`ActuatorMode::Mocap`] a body hung from fixed or placed bodies by actuated joints only is
//!   a mocap body at its drawn pose (placed, never integrated: the MuJoCo peer's model of
//!   ji2014's actuator, `benches/peers/mujoco/README.md`), and the bodies it carries hang from it
//!   as usual; an actuated joint whose parent moves is held at its command by a joint
//!   equality (`polycoef` a0 = command - ref: a soft constraint, like the loop closures); in [`ActuatorMode::Position`] every actuated joint is an MJCF joint driven by a
//!   `<position>` actuator of gain `joint_kp` (a servo: it sags by load / kp). A winch on an
//!   elastic cable is a `<position>` actuator on its tendon with kp = the cable's stiffness and
//!   force range [-max, 0]: tension k (l - command) when longer, none when shorter, the cable's
//!   law with the command as its length. A winch on an inextensible cable is its tendon's
//!   range (set `tendon_range` to move it); a servo (an actuated revolute joint with a torsion
//!   spring: the command is its rest angle) is its joint's `stiffness` with `springref` the
//!   exported command, no actuator element;
//! - gravity in `<option>`; constant external loads as `<custom><numeric name="load:BODY">`
//!   (apply them through `xfrc_applied` at the body's centre of mass); the first point's
//!   actuator commands as the keyframe `first_point`.

use crate::structure::{ActuatorTarget, BodyKind, CableLaw, JointKind, Law, MemberKind, Structure, Vec3};
use std::collections::BTreeSet;
use std::fmt::Write;

/// How the testbed's ideal actuators are written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ActuatorMode {
    /// Bodies placed by actuated joints alone are mocap bodies (exact, no actuator element).
    Mocap,
    /// Actuated joints are MJCF joints with `<position>` actuators (servos of finite gain).
    Position,
}

#[derive(Clone, Debug)]
pub struct MjcfOptions {
    /// The `<mujoco model>` name.
    pub model_name: String,
    /// `<option timestep>` \[s\].
    pub timestep_s: f64,
    /// The testbed's free-body damping [1/s]; written as the free joints' damping, times the
    /// body's mass [N s/m] (zero at rest: the equilibrium does not move).
    pub body_damping_per_s: f64,
    pub actuators: ActuatorMode,
    /// Gain of `<position>` actuators on joints [N/m or N m/rad].
    pub joint_kp: f64,
    /// The actuator commands of the exported point, in actuator order (m or rad).
    pub commands: Vec<f64>,
    /// Viscous damping along every cable [N s/m] (the testbed's cables have none; zero at
    /// rest, so the equilibrium does not move, but MuJoCo damps slack cables too): each cable
    /// tendon's `damping`, each winch's `kv`.
    pub cable_damping_n_s_per_m: f64,
}

/// The XML, and what the export could not express (also written as comments in the XML).
#[derive(Clone, Debug)]
pub struct Mjcf {
    pub xml: String,
    pub warnings: Vec<String>,
}

/// Largest pulling force of a winch's `<position>` actuator \[N\]: its lower force bound (no
/// upper one but zero, so it never pushes).
pub const WINCH_MAX_TENSION_N: f64 = 1e12;

/// Site radius as a fraction of the structure's size (drawing only).
const SITE_SIZE_FRACTION: f64 = 0.01;

/// Smallest capsule radius as a fraction of the structure's size (MuJoCo needs > 0).
const MIN_GEOM_RADIUS_FRACTION: f64 = 1e-3;

/// Impedance of the soft equality and tendon-limit rows: MuJoCo's cap (`mjMAXIMP`), the
/// stiffest it allows (the MuJoCo peer's `tuned` setting).
const SOLIMP: &str = "0.9999 0.9999 0.001 0.5 2";

/// Solver tolerance: MuJoCo's default 1e-8 left node speeds near 1e-8 m/s (the peer's
/// measurement on mohr2011).
const SOLVER_TOLERANCE: f64 = 1e-10;

/// `s` and `o` with every servo (`Structure::servo_of`) written as its joint's spring at the
/// exported command: MuJoCo's joint `stiffness` with `springref` the command is the same
/// torque, -k (q - command), at this point; the servo's actuator and command are left out.
fn servos_as_springs(s: &Structure, o: &MjcfOptions) -> (Structure, MjcfOptions) {
    let (mut s2, mut o2) = (s.clone(), o.clone());
    let servos: Vec<(usize, usize)> = (0..s.joints.len()).filter_map(|j| s.servo_of(j).map(|a| (a, j))).collect();
    for &(a, j) in &servos {
        if let (Some(t), Some(command)) = (s2.joints[j].torsion_spring.as_mut(), o.commands.get(a)) {
            t.rest_angle_rad = *command;
        }
    }
    let kept = |i: &usize| !servos.iter().any(|(a, _)| a == i);
    s2.actuators = s.actuators.iter().enumerate().filter(|(i, _)| kept(i)).map(|(_, a)| a.clone()).collect();
    o2.commands = o.commands.iter().enumerate().filter(|(i, _)| kept(i)).map(|(_, c)| *c).collect();
    (s2, o2)
}

/// The body tree the export writes.
struct Plan {
    /// For each body: the joint it hangs from in the forest.
    tree_joint: Vec<Option<usize>>,
    /// For each body: a mocap body (placed by actuated joints from fixed or placed bodies).
    mocap: Vec<bool>,
    /// For each body: held in place (fixed, welded to a held body, or mocap).
    held: Vec<bool>,
    /// For each body: its frame's origin in the drawn configuration (world) [m].
    origin: Vec<Vec3>,
    /// For each joint: driven by an actuator.
    actuated: Vec<bool>,
    /// For each body: the world translations its supports hold (`Structure::supports`; slide
    /// joints along the others).
    supported: Vec<[bool; 3]>,
}

/// Writes `s` as MJCF.
pub fn to_mjcf(s: &Structure, o: &MjcfOptions) -> Mjcf {
    let (servoed, options) = servos_as_springs(s, o);
    let (s, o) = (&servoed, &options);
    let plan = plan(s, o.actuators);
    let size = crate::structure::structure_size(s);
    let mut w = Writer { s, o, plan: &plan, size, xml: String::new(), warnings: Vec::new() };
    w.header();
    w.worldbody();
    w.equalities();
    w.tendons();
    w.actuators();
    w.custom();
    w.xml.push_str("</mujoco>\n");
    let mut xml = w.xml;
    if !w.warnings.is_empty() {
        let notes: String = w.warnings.iter().map(|m| format!("<!-- not exported: {} -->\n", esc(m))).collect();
        xml = xml.replacen("<compiler", &format!("{notes}<compiler"), 1);
    }
    Mjcf { xml, warnings: w.warnings }
}

/// The spanning forest (joint order; planar pins never; no cycles), the held and mocap bodies
/// and each body's frame origin.
fn plan(s: &Structure, mode: ActuatorMode) -> Plan {
    let n = s.bodies.len();
    let mut actuated = vec![false; s.joints.len()];
    for a in &s.actuators {
        if let ActuatorTarget::Joint(j) = a.target {
            actuated[j] = true;
        }
    }
    let mut tree_joint: Vec<Option<usize>> = vec![None; n];
    let is_above = |tree: &Vec<Option<usize>>, upper: usize, mut b: usize| -> bool {
        loop {
            if b == upper {
                return true;
            }
            match tree[b] {
                Some(j) => b = s.joints[j].parent,
                None => return false,
            }
        }
    };
    for (j, joint) in s.joints.iter().enumerate() {
        let c = joint.child;
        if s.bodies[c].kind == BodyKind::Free
            && tree_joint[c].is_none()
            && !matches!(joint.kind, JointKind::PlanarPin { .. })
            && !is_above(&tree_joint, c, joint.parent)
        {
            tree_joint[c] = Some(j);
        }
    }
    // Held and mocap bodies, from the roots down (a forest: n passes reach every depth).
    let mut held: Vec<bool> = s.bodies.iter().map(|b| b.kind == BodyKind::Fixed).collect();
    let mut mocap = vec![false; n];
    for _ in 0..n {
        for b in 0..n {
            if let Some(j) = tree_joint[b] {
                let joint = &s.joints[j];
                let placed = mode == ActuatorMode::Mocap && actuated[j];
                if held[joint.parent] && (placed || joint.kind == JointKind::Fixed) {
                    held[b] = true;
                    mocap[b] = placed;
                }
            }
        }
    }
    let origin = (0..n)
        .map(|b| match (tree_joint[b], s.bodies[b].inertia) {
            (Some(j), _) => s.nodes[s.joints[j].anchor].position,
            (None, Some(i)) if s.bodies[b].kind == BodyKind::Free => i.com,
            _ => [0.0; 3],
        })
        .collect();
    Plan { tree_joint, mocap, held, origin, actuated, supported: s.held_translations() }
}

/// Escapes text for an XML attribute or comment.
fn esc(t: &str) -> String {
    t.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;").replace("--", "- -")
}

/// Numbers at full precision (shortest round-trip form), space separated.
fn nums(v: &[f64]) -> String {
    v.iter().map(|x| format!("{x:?}")).collect::<Vec<_>>().join(" ")
}

fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn unit(a: Vec3) -> Vec3 {
    let n = crate::structure::norm(a);
    [a[0] / n, a[1] / n, a[2] / n]
}

struct Writer<'a> {
    s: &'a Structure,
    o: &'a MjcfOptions,
    plan: &'a Plan,
    size: f64,
    xml: String,
    warnings: Vec<String>,
}

impl Writer<'_> {
    fn header(&mut self) {
        let (o, s) = (self.o, self.s);
        let _ = writeln!(
            self.xml,
            "<mujoco model=\"{}\">\n<!-- written by tensegrity export mjcf: {} bodies, {} nodes, {} struts, {} springs, {} cables, {} joints, {} actuators; SI units -->",
            esc(&o.model_name),
            s.bodies.len(),
            s.nodes.len(),
            s.count_of(MemberKind::Strut),
            s.count_of(MemberKind::Spring),
            s.count_of(MemberKind::Cable),
            s.joints.len(),
            s.actuators.len()
        );
        let _ = writeln!(self.xml, "<compiler angle=\"radian\" autolimits=\"true\"/>");
        let _ = writeln!(
            self.xml,
            "<option timestep=\"{:?}\" integrator=\"implicitfast\" gravity=\"{}\" tolerance=\"{SOLVER_TOLERANCE:?}\"/>",
            o.timestep_s,
            nums(&s.gravity)
        );
        let solref = 2.0 * o.timestep_s;
        let _ = writeln!(
            self.xml,
            "<default>\n  <geom contype=\"0\" conaffinity=\"0\" rgba=\"0.8 0.6 0.4 1\"/>\n  <site size=\"{:?}\"/>\n  <equality solref=\"{solref:?} 1\" solimp=\"{SOLIMP}\"/>\n  <tendon solreflimit=\"{solref:?} 1\" solimplimit=\"{SOLIMP}\" width=\"{:?}\"/>\n</default>",
            SITE_SIZE_FRACTION * self.size,
            0.5 * SITE_SIZE_FRACTION * self.size
        );
    }

    fn worldbody(&mut self) {
        self.xml.push_str("<worldbody>\n");
        for b in 0..self.s.bodies.len() {
            if self.plan.tree_joint[b].is_none() || self.plan.mocap[b] {
                self.body(b, 1);
            }
        }
        self.xml.push_str("</worldbody>\n");
    }

    /// Body `b` and the bodies that hang from it, at indentation `depth`.
    fn body(&mut self, b: usize, depth: usize) {
        let (s, plan) = (self.s, self.plan);
        let pad = "  ".repeat(depth);
        let at_world = plan.tree_joint[b].is_none() || plan.mocap[b];
        let pos = match plan.tree_joint[b] {
            Some(j) if !at_world => sub(plan.origin[b], plan.origin[s.joints[j].parent]),
            _ => plan.origin[b],
        };
        let mocap = if plan.mocap[b] { " mocap=\"true\"" } else { "" };
        let _ = writeln!(self.xml, "{pad}<body name=\"{}\" pos=\"{}\"{mocap}>", esc(&s.bodies[b].name), nums(&pos));
        self.body_joints(b, &pad);
        if let (BodyKind::Free, Some(i)) = (s.bodies[b].kind, s.bodies[b].inertia) {
            let _ = writeln!(
                self.xml,
                "{pad}  <inertial pos=\"{}\" mass=\"{:?}\" diaginertia=\"{}\"/>",
                nums(&sub(i.com, plan.origin[b])),
                i.mass_kg,
                nums(&i.principal_kg_m2)
            );
        }
        self.geoms_and_sites(b, &pad);
        for c in 0..s.bodies.len() {
            if !plan.mocap[c] && plan.tree_joint[c].is_some_and(|j| s.joints[j].parent == b) {
                self.body(c, depth + 1);
            }
        }
        let _ = writeln!(self.xml, "{pad}</body>");
    }

    /// The MJCF joints of body `b`: its forest joint, or a free joint for a free body outside
    /// the forest; none for held bodies.
    fn body_joints(&mut self, b: usize, pad: &str) {
        let (s, plan) = (self.s, self.plan);
        if plan.held[b] {
            return;
        }
        let Some(j) = plan.tree_joint[b] else {
            let mass = s.bodies[b].inertia.map_or(0.0, |i| i.mass_kg);
            let held = plan.supported[b];
            if held.contains(&true) {
                // A support in some directions (on a point mass, which nothing turns): a slide
                // joint along each free axis.
                for (x, axis) in ["x", "y", "z"].iter().enumerate().filter(|(x, _)| !held[*x]) {
                    let direction = ["1 0 0", "0 1 0", "0 0 1"][x];
                    let _ = writeln!(
                        self.xml,
                        "{pad}  <joint name=\"{}:slide_{axis}\" type=\"slide\" axis=\"{direction}\" damping=\"{:?}\"/>",
                        esc(&s.bodies[b].name),
                        self.o.body_damping_per_s * mass
                    );
                }
                return;
            }
            let _ = writeln!(
                self.xml,
                "{pad}  <joint name=\"{}:free\" type=\"free\" damping=\"{:?}\"/>",
                esc(&s.bodies[b].name),
                self.o.body_damping_per_s * mass
            );
            return;
        };
        let joint = &s.joints[j];
        let name = esc(&joint.name);
        let damping = format!("damping=\"{:?}\"", joint.damping);
        let spring = joint.torsion_spring.as_ref().map_or(String::new(), |t| {
            format!(" stiffness=\"{:?}\" springref=\"{:?}\"", t.stiffness_nm_per_rad, t.rest_angle_rad)
        });
        let r = joint.initial_coordinate;
        let line = match &joint.kind {
            JointKind::Revolute { axis } => format!(
                "<joint name=\"{name}\" type=\"hinge\" pos=\"0 0 0\" axis=\"{}\" ref=\"{r:?}\"{spring} {damping}/>",
                nums(&unit(*axis))
            ),
            JointKind::Prismatic { axis } => format!(
                "<joint name=\"{name}\" type=\"slide\" pos=\"0 0 0\" axis=\"{}\" ref=\"{r:?}\" {damping}/>",
                nums(&unit(*axis))
            ),
            JointKind::Spherical => format!("<joint name=\"{name}\" type=\"ball\" pos=\"0 0 0\" {damping}/>"),
            // The first hinge's axis is fixed in the parent, the second turns with it (fixed
            // in the child), as MuJoCo applies a body's joints in order.
            JointKind::Universal { axis1, axis2 } => format!(
                "<joint name=\"{name}:1\" type=\"hinge\" pos=\"0 0 0\" axis=\"{}\" {damping}/>\n{pad}  <joint name=\"{name}:2\" type=\"hinge\" pos=\"0 0 0\" axis=\"{}\" {damping}/>",
                nums(&unit(*axis1)),
                nums(&unit(*axis2))
            ),
            JointKind::Fixed | JointKind::PlanarPin { .. } => return,
        };
        let _ = writeln!(self.xml, "{pad}  {line}");
    }

    /// Capsules of the struts on body `b`, and its nodes as sites.
    fn geoms_and_sites(&mut self, b: usize, pad: &str) {
        let (s, o) = (self.s, self.plan.origin[b]);
        for (_, st) in s.rigid_struts() {
            let (na, nb) = (&s.nodes[st.ends().0], &s.nodes[st.ends().1]);
            if na.body != b {
                continue;
            }
            if nb.body != b {
                let _ = writeln!(
                    self.xml,
                    "{pad}  <!-- strut {} joins two bodies ({} and {}): drawn by neither -->",
                    esc(&st.name),
                    esc(&s.bodies[na.body].name),
                    esc(&s.bodies[nb.body].name)
                );
                continue;
            }
            let (pa, pb) = (sub(na.position, o), sub(nb.position, o));
            let r = st.radius_m.max(MIN_GEOM_RADIUS_FRACTION * self.size);
            let _ = writeln!(
                self.xml,
                "{pad}  <geom name=\"{}\" type=\"capsule\" fromto=\"{} {}\" size=\"{r:?}\"/>",
                esc(&st.name),
                nums(&pa),
                nums(&pb)
            );
        }
        for n in s.nodes.iter().filter(|n| n.body == b) {
            let _ =
                writeln!(self.xml, "{pad}  <site name=\"{}\" pos=\"{}\"/>", esc(&n.name), nums(&sub(n.position, o)));
        }
    }

    /// The joints outside the forest, as equality constraints.
    fn equalities(&mut self) {
        let (s, plan) = (self.s, self.plan);
        let mut rows = String::new();
        for (j, joint) in s.joints.iter().enumerate() {
            if plan.tree_joint[joint.child] == Some(j) {
                continue;
            }
            let (p, c) = (joint.parent, joint.child);
            if plan.held[p] && plan.held[c] {
                let _ =
                    writeln!(rows, "  <!-- joint {}: both bodies are placed; nothing to close -->", esc(&joint.name));
                continue;
            }
            if plan.actuated[j] {
                self.warnings.push(format!(
                    "actuated joint '{}' closes a loop: held at its drawn coordinate, its command is not exported",
                    joint.name
                ));
            }
            let anchor = s.nodes[joint.anchor].position;
            let (b1, b2) = (esc(&s.bodies[p].name), esc(&s.bodies[c].name));
            let connect = |rows: &mut String, name: &str, at: Vec3| {
                let _ = writeln!(
                    rows,
                    "  <connect name=\"{}\" body1=\"{b1}\" body2=\"{b2}\" anchor=\"{}\"/>",
                    esc(name),
                    nums(&sub(at, plan.origin[p]))
                );
            };
            match &joint.kind {
                JointKind::Spherical | JointKind::PlanarPin { .. } => connect(&mut rows, &joint.name, anchor),
                JointKind::Revolute { axis } => {
                    let u = unit(*axis);
                    let far = [0, 1, 2].map(|k| anchor[k] + u[k] * self.size);
                    connect(&mut rows, &format!("{}:a", joint.name), anchor);
                    connect(&mut rows, &format!("{}:b", joint.name), far);
                }
                JointKind::Fixed => {
                    let _ = writeln!(rows, "  <weld name=\"{}\" body1=\"{b1}\" body2=\"{b2}\"/>", esc(&joint.name));
                }
                JointKind::Universal { .. } => {
                    connect(&mut rows, &joint.name, anchor);
                    self.warnings.push(format!(
                        "universal joint '{}' closes a loop: written as a connect (spherical); its twist lock has no MJCF equality",
                        joint.name
                    ));
                }
                JointKind::Prismatic { .. } => self.warnings.push(format!(
                    "prismatic joint '{}' closes a loop: MJCF has no sliding equality; left out",
                    joint.name
                )),
            }
        }
        self.joint_locks(&mut rows);
        if !rows.is_empty() {
            let _ = write!(self.xml, "<equality>\n{rows}</equality>\n");
        }
    }

    /// In [`ActuatorMode::Mocap`], an actuated forest joint whose parent moves cannot be placed
    /// by a mocap body: it is held at its command by a joint equality (y - ref = a0).
    fn joint_locks(&mut self, rows: &mut String) {
        let (s, plan) = (self.s, self.plan);
        if self.o.actuators != ActuatorMode::Mocap {
            return;
        }
        for (i, a) in s.actuators.iter().enumerate() {
            let ActuatorTarget::Joint(j) = a.target else { continue };
            let joint = &s.joints[j];
            if plan.tree_joint[joint.child] == Some(j) && !plan.mocap[joint.child] {
                let offset =
                    self.o.commands.get(i).copied().unwrap_or(joint.initial_coordinate) - joint.initial_coordinate;
                let _ = writeln!(
                    rows,
                    "  <joint name=\"lock:{}\" joint1=\"{}\" polycoef=\"{offset:?} 0 0 0 0\"/>",
                    esc(&joint.name),
                    esc(&joint.name)
                );
            }
        }
    }

    /// For each cable: the actuator that winches it, if any.
    fn winched(&self, c: usize) -> bool {
        self.s.actuators.iter().any(|a| a.target == ActuatorTarget::CableLength(c))
    }

    fn tendons(&mut self) {
        let s = self.s;
        if s.members.iter().all(|m| m.is_rigid_strut()) {
            return;
        }
        let mut names = Unique::default();
        self.xml.push_str("<tendon>\n");
        // An elastic strut pushes and pulls between its two point masses, as a spring does: a
        // tendon spring pushes too.
        let elastic_struts = s.members_of(MemberKind::Strut).filter(|(_, m)| !m.is_rigid_strut());
        for (_, sp) in elastic_struts.chain(s.members_of(MemberKind::Spring)) {
            let (k, rest) = (sp.stiffness_n_per_m().unwrap_or(f64::NAN), sp.rest_length_m().unwrap_or(f64::NAN));
            let law = format!("stiffness=\"{k:?}\" springlength=\"{rest:?}\"");
            self.spatial(&names.get(&sp.name), &law, &sp.path);
        }
        for (c, cable) in s.members_of(MemberKind::Cable) {
            let Law::Cable { law: cable_law, length_m: l } = cable.law.clone() else { continue };
            let mut law = match (cable_law.clone(), self.winched(c)) {
                (CableLaw::Inextensible, _) => format!("limited=\"true\" range=\"0 {l:?}\""),
                (CableLaw::Elastic { .. }, true) => String::new(),
                (CableLaw::Elastic { stiffness_n_per_m }, false) => {
                    format!("stiffness=\"{stiffness_n_per_m:?}\" springlength=\"0 {l:?}\"")
                }
            };
            let damping = self.o.cable_damping_n_s_per_m;
            if damping > 0.0 && !(self.winched(c) && matches!(cable_law, CableLaw::Elastic { .. })) {
                let _ = write!(law, " damping=\"{damping:?}\"");
            }
            if cable.has_friction() {
                let _ = writeln!(
                    self.xml,
                    "  <!-- cable {} has friction {:?} at its inner nodes: MuJoCo's tendon has no capstan, it slides freely here -->",
                    esc(&cable.name),
                    cable.friction
                );
            }
            self.spatial(&names.get(&cable.name), &law, &cable.path);
        }
        self.xml.push_str("</tendon>\n");
    }

    /// A spatial tendon through the sites of `path`: MuJoCo's length is the sum of its
    /// segments', a clustered cable's as the testbed counts it.
    fn spatial(&mut self, name: &str, law: &str, path: &[usize]) {
        let s = self.s;
        let sites: String = path.iter().map(|&n| format!("<site site=\"{}\"/>", esc(&s.nodes[n].name))).collect();
        let _ = writeln!(self.xml, "  <spatial name=\"{}\" {law}>{sites}</spatial>", esc(name));
    }

    /// Position actuators, comments for mocap-placed and range-driven actuators, and the
    /// keyframe of the exported point's commands.
    fn actuators(&mut self) {
        let (s, plan) = (self.s, self.plan);
        let mut rows = String::new();
        let mut ctrl = Vec::new();
        let mut names = Unique::default();
        for (i, a) in s.actuators.iter().enumerate() {
            let command = self.o.commands.get(i).copied().unwrap_or(f64::NAN);
            let name = esc(&names.get(&a.symbol));
            match a.target {
                ActuatorTarget::Joint(j) => {
                    let joint = &s.joints[j];
                    if plan.mocap[joint.child] && plan.tree_joint[joint.child] == Some(j) {
                        let _ = writeln!(
                            rows,
                            "  <!-- {name} = {command:?}: joint {} places mocap body {} (move it with mocap_pos / mocap_quat) -->",
                            esc(&joint.name),
                            esc(&s.bodies[joint.child].name)
                        );
                    } else if plan.tree_joint[joint.child] == Some(j) && self.o.actuators == ActuatorMode::Mocap {
                        let _ = writeln!(
                            rows,
                            "  <!-- {name} = {command:?}: joint {} held by the equality lock:{} (its eq_data[0] = command - ref) -->",
                            esc(&joint.name),
                            esc(&joint.name)
                        );
                    } else if plan.tree_joint[joint.child] == Some(j) {
                        let _ = writeln!(
                            rows,
                            "  <position name=\"{name}\" joint=\"{}\" kp=\"{:?}\"/>",
                            esc(&joint.name),
                            self.o.joint_kp
                        );
                        ctrl.push(command);
                    }
                }
                ActuatorTarget::FixedNode { node, direction } => {
                    let _ = writeln!(
                        rows,
                        "  <!-- {name} = {command:?}: node {} (fixed) displaced by it along {direction:?} (exported in place) -->",
                        esc(&s.nodes[node].name)
                    );
                }
                ActuatorTarget::CableLength(c) => {
                    let cable = &s.members[c];
                    match cable.law {
                        Law::Cable { law: CableLaw::Elastic { stiffness_n_per_m }, .. } => {
                            let _ = writeln!(
                                rows,
                                "  <position name=\"{name}\" tendon=\"{}\" kp=\"{stiffness_n_per_m:?}\" kv=\"{:?}\" forcelimited=\"true\" forcerange=\"{:?} 0\"/>",
                                esc(&cable.name),
                                self.o.cable_damping_n_s_per_m,
                                -WINCH_MAX_TENSION_N
                            );
                            ctrl.push(command);
                        }
                        _ => {
                            let _ = writeln!(
                                rows,
                                "  <!-- {name} = {command:?}: the length of inextensible cable {} (its tendon_range upper bound) -->",
                                esc(&cable.name)
                            );
                        }
                    }
                }
            }
        }
        if !rows.is_empty() {
            let _ = write!(self.xml, "<actuator>\n{rows}</actuator>\n");
        }
        if !ctrl.is_empty() {
            let _ =
                writeln!(self.xml, "<keyframe>\n  <key name=\"first_point\" ctrl=\"{}\"/>\n</keyframe>", nums(&ctrl));
        }
    }

    fn custom(&mut self) {
        let s = self.s;
        if s.loads.is_empty() && s.node_loads.is_empty() {
            return;
        }
        self.xml.push_str(
            "<custom>\n  <!-- constant forces [N] at each body's centre of mass: apply through xfrc_applied -->\n",
        );
        for (i, l) in s.loads.iter().enumerate() {
            let _ = writeln!(
                self.xml,
                "  <numeric name=\"load:{}:{i}\" data=\"{}\"/>",
                esc(&s.bodies[l.body].name),
                nums(&l.force_n)
            );
        }
        if !s.node_loads.is_empty() {
            self.xml.push_str(
                "  <!-- point loads [N] at nodes (the node's site): apply through mj_applyFT at the site's position every step -->\n",
            );
        }
        for (i, l) in s.node_loads.iter().enumerate() {
            let node = &s.nodes[l.node];
            let _ = writeln!(
                self.xml,
                "  <numeric name=\"node_load:{}:{}:{i}\" data=\"{}\"/>",
                esc(&s.bodies[node.body].name),
                esc(&node.name),
                nums(&l.force_n)
            );
        }
        self.xml.push_str("</custom>\n");
    }
}

/// Names unique within one MJCF namespace: a repeat gets "~2", "~3", ...
#[derive(Default)]
struct Unique(BTreeSet<String>);

impl Unique {
    fn get(&mut self, name: &str) -> String {
        let mut candidate = name.to_string();
        let mut k = 2;
        while !self.0.insert(candidate.clone()) {
            candidate = format!("{name}~{k}");
            k += 1;
        }
        candidate
    }
}
