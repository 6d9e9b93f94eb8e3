//! A mechanism described in a scenario file (`mechanism = "custom"` and a `[structure]`
//! table): no analytic model, only what the dynamics can check on their own (settling, the
//! force balance, cable slackness, member forces, stability, interference), plus optional
//! expected values given in the file (`[[checks]]` with `value`) and the file's own model
//! (`[params]`, `[[quantities]]`, `[[predictions]]`, `[[equations]]`, `[energy]`: see
//! the `file_model` module, which this one does not import).

use crate::mechanisms::{
    Finding, InputSpec, Mechanism, MechanismSpec, ModelError, Origin, ParamSpec, Prediction, QuantityKind,
    QuantitySpec, Solution, Values,
};
use crate::snapshot::Snapshot;
use crate::structure::{ActuatorTarget, Structure};

/// The mechanism built from a file's `[structure]`.
#[derive(Clone, Debug)]
pub struct Custom {
    pub structure: Structure,
    /// Name, title and the symbols of the file's actuators and checks.
    spec: MechanismSpec,
    /// Expected values from the file's checks, by quantity.
    pub expected: Values,
    /// The parameters `structure` was resolved with.
    params: Values,
    /// The structure at the other sets of parameters a sweep over them settles at (shared: a
    /// sweep clones the mechanism per block, and 4000 copies of 4000 structures had made its
    /// time grow with the square of its points).
    variants: std::sync::Arc<Vec<(Values, Structure)>>,
    /// `structure`'s size [m] ([`crate::structure::structure_size`], up to quadratic in the nodes:
    /// computed once).
    size_m: f64,
}

/// A parameter a custom file declares in `[params]`.
#[derive(Clone, Debug, PartialEq)]
pub struct FileParam {
    pub symbol: String,
    /// Its value in the file (an expression's value once evaluated).
    pub value: f64,
    pub unit: String,
    pub description: String,
}

/// Leaks a string for the `'static` specs of a file-described mechanism (one per file).
fn leak(s: String) -> &'static str {
    Box::leak(s.into_boxed_str())
}

impl Custom {
    pub fn new(structure: Structure, expected: Values) -> Self {
        let mut inputs: Vec<InputSpec> = Vec::new();
        for a in &structure.actuators {
            if inputs.iter().any(|i| i.symbol == a.symbol) {
                continue;
            }
            let (unit, description) = match a.target {
                ActuatorTarget::Joint(j) => match structure.joints[j].kind {
                    crate::structure::JointKind::Revolute { .. } => {
                        ("rad", "joint angle command from the structure file")
                    }
                    _ => ("m", "joint slide command from the structure file"),
                },
                ActuatorTarget::CableLength(_) => ("m", "winch: the cable's rest length, from the structure file"),
                ActuatorTarget::FixedNode { .. } => {
                    ("m", "moved node: its displacement along its direction, from the structure file")
                }
            };
            inputs.push(InputSpec { symbol: leak(a.symbol.clone()), unit, description });
        }
        let mut quantities = Vec::new();
        for n in &structure.nodes {
            for c in ["x", "y", "z"] {
                quantities.push(QuantitySpec {
                    symbol: leak(format!("{}.{c}", n.name)),
                    unit: "m",
                    kind: QuantityKind::Length,
                    description: "node coordinate",
                });
            }
        }
        let size = crate::structure::structure_size(&structure);
        let tensioned = structure.members_with_law();
        let read_struts = structure.rigid_struts().filter(|(_, t)| strut_reading(&structure, t, size).is_some());
        let members = tensioned.chain(read_struts).map(|(_, m)| &m.name);
        for name in members {
            quantities.push(QuantitySpec {
                symbol: leak(format!("{name}.force")),
                unit: "N",
                kind: QuantityKind::Magnitude,
                description: "member force, tension positive (struts: from the balance of an end node without a joint; none for a strut on a fixed body or jointed at both ends)",
            });
        }
        Custom {
            structure,
            size_m: size,
            spec: MechanismSpec {
                name: "custom",
                title: "a structure described in the scenario file (its model, if any, stated there too)",
                params: &[],
                inputs: Box::leak(inputs.into_boxed_slice()),
                quantities: Box::leak(quantities.into_boxed_slice()),
                queries: &[],
                start_keys: &[],
                alternative_inputs: &[],
            },
            expected,
            params: Values::new(),
            variants: std::sync::Arc::default(),
        }
    }

    /// The mechanism with its structure at other sets of parameters (a sweep over them).
    /// The same structure, at every set of parameters, without its point loads (the reference
    /// of a linear analysis).
    pub fn without_point_loads(&self) -> Custom {
        let unloaded = |s: &Structure| Structure { node_loads: Vec::new(), ..s.clone() };
        let variants = self.variants.iter().map(|(p, s)| (p.clone(), unloaded(s))).collect();
        Custom { structure: unloaded(&self.structure), variants: std::sync::Arc::new(variants), ..self.clone() }
    }

    pub fn with_variants(mut self, variants: Vec<(Values, Structure)>) -> Self {
        self.variants = std::sync::Arc::new(variants);
        self
    }

    /// The mechanism with its structure at these sets of parameters too.
    pub fn with_more_variants(mut self, variants: Vec<(Values, Structure)>) -> Self {
        std::sync::Arc::make_mut(&mut self.variants).extend(variants);
        self
    }

    /// The parameters of `swept` that change nothing in the structure: at every other value of
    /// the swept ones, each value gives the same structure (a sweep that only the formulas see).
    pub fn unseen(&self, swept: &[String]) -> Vec<String> {
        let all: Vec<(&Values, &Structure)> =
            std::iter::once((&self.params, &self.structure)).chain(self.variants.iter().map(|(p, s)| (p, s))).collect();
        let value = |p: &Values, k: &str| p.get(k).copied().unwrap_or(f64::NAN).to_bits();
        // Unseen: it varies, and every structure equals the first one found at the same values
        // of the other swept parameters.
        let unseen = |k: &String| {
            let varies = all.iter().any(|(p, _)| value(p, k) != value(all[0].0, k));
            let mut first: std::collections::HashMap<Vec<u64>, &Structure> = std::collections::HashMap::new();
            varies
                && all.iter().all(|(p, s)| {
                    let others: Vec<u64> = swept.iter().filter(|o| *o != k).map(|o| value(p, o)).collect();
                    *first.entry(others).or_insert(s) == *s
                })
        };
        swept.iter().filter(|k| unseen(k)).cloned().collect()
    }

    /// The structure resolved with `params`: the file's own, or one of its variants.
    fn structure_at(&self, params: &Values) -> Result<&Structure, ModelError> {
        if params == &self.params || params.is_empty() {
            return Ok(&self.structure);
        }
        self.variants.iter().find(|(p, _)| p == params).map(|(_, s)| s).ok_or_else(|| {
            ModelError::no_solution(format!("the file's structure was not resolved with the parameters {params:?}"))
        })
    }

    /// The mechanism with the parameters its file declares (their values are the defaults).
    pub fn with_params(mut self, params: Vec<FileParam>) -> Self {
        self.params = params.iter().map(|p| (p.symbol.clone(), p.value)).collect();
        let specs: Vec<ParamSpec> = params
            .into_iter()
            .map(|p| ParamSpec {
                symbol: leak(p.symbol),
                unit: leak(p.unit),
                default: p.value,
                description: leak(p.description),
                origin: Origin::Paper,
            })
            .collect();
        self.spec.params = Box::leak(specs.into_boxed_slice());
        self
    }

    /// Axial force of each strut whose force can be read ([`strut_reading`]), tension positive
    /// [N]: minus the member forces on an end node along the strut, so that it balances them.
    fn strut_forces(&self, snap: &Snapshot) -> Vec<(usize, f64)> {
        let s = &self.structure;
        // The member forces on every node, summed in one pass over the members (in member
        // and segment order, as a sum per node would take them): a pass per strut end had
        // made the observation quadratic in the structure's size.
        let mut node_forces = vec![[0.0; 3]; snap.nodes.len()];
        let mut add = |a: usize, b: usize, t: f64| {
            let (pa, pb) = (snap.nodes[a], snap.nodes[b]);
            let d = [pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]];
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if l > 0.0 {
                for k in 0..3 {
                    node_forces[a][k] += t * d[k] / l;
                }
            }
        };
        for (i, m) in s.members_with_law() {
            for (a, b) in m.segments() {
                add(a, b, snap.forces.force_n[i]);
                if b != a {
                    add(b, a, snap.forces.force_n[i]);
                }
            }
        }
        let node_force = |node: usize| node_forces[node];
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        s.rigid_struts()
            .filter_map(|(k, st)| {
                let reading = strut_reading(s, st, self.size_m)?;
                let (a, b) = st.ends();
                let (pa, pb) = (snap.nodes[a], snap.nodes[b]);
                let d = [pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]];
                let l = dot(d, d).sqrt().max(f64::MIN_POSITIVE);
                let u = [d[0] / l, d[1] / l, d[2] / l];
                // Strut tension t pulls a towards b: t u + fa = 0 at a, -t u + fb = 0 at b.
                let ta = || -dot(node_force(a), u);
                let tb = || dot(node_force(b), u);
                Some((
                    k,
                    match reading {
                        StrutReading::BothEnds => 0.5 * (ta() + tb()),
                        StrutReading::EndA => ta(),
                        StrutReading::EndB => tb(),
                    },
                ))
            })
            .collect()
    }
}

/// Which end nodes carry a strut's axial force alone: an end with a joint also takes the
/// joint's reaction, which the member forces do not show.
#[derive(Clone, Copy, Debug, PartialEq)]
enum StrutReading {
    BothEnds,
    EndA,
    EndB,
}

/// How the axial force of `st` is read, or None when it cannot be: a strut on a fixed body
/// (its force goes into the ground) or with a joint at both ends (the joints' reactions share
/// the axial force in a way the body's balance does not determine). `size`: the structure's
/// ([`crate::structure::structure_size`], computed once by the caller: it can be quadratic in the
/// nodes, and computing it per strut had made checking a 1000-rod model take 10.9 s).
fn strut_reading(s: &Structure, st: &crate::structure::Member, size: f64) -> Option<StrutReading> {
    let fixed = |n: usize| s.bodies[s.nodes[n].body].kind == crate::structure::BodyKind::Fixed;
    let (a, b) = st.ends();
    if fixed(a) || fixed(b) {
        return None;
    }
    let jointed = |n: usize| {
        let node = &s.nodes[n];
        s.joints.iter().any(|j| {
            (j.parent == node.body || j.child == node.body)
                && crate::structure::distance(s.nodes[j.anchor].position, node.position)
                    <= JOINT_AT_NODE_FRACTION * size
        })
    };
    match (jointed(a), jointed(b)) {
        (false, false) => Some(StrutReading::BothEnds),
        (true, false) => Some(StrutReading::EndB),
        (false, true) => Some(StrutReading::EndA),
        (true, true) => None,
    }
}

/// A joint anchored closer than this fraction of the structure's size to a strut's end node
/// acts at that end.
const JOINT_AT_NODE_FRACTION: f64 = 1e-9;

/// The branch a custom structure's settled state lands on: the values its `[[checks]]` state.
pub const EXPECTED_VALUES: &str = "expected values from the file";
/// The label where the file's `[[checks]]` state no values: no branch to land on (the file's
/// own model, `[[predictions]]` and the rest, is judged beside, not as a branch).
pub const NO_EXPECTED_VALUES: &str = "none (the file's [[checks]] state no values)";

impl Mechanism for Custom {
    fn spec(&self) -> &MechanismSpec {
        &self.spec
    }
    fn validate_params(&self, _params: &Values) -> Result<(), ModelError> {
        Ok(())
    }
    fn validate_inputs(&self, _params: &Values, inputs: &Values) -> Result<(), ModelError> {
        for i in self.spec.inputs {
            let x = inputs
                .get(i.symbol)
                .copied()
                .ok_or(ModelError::value(i.symbol, format!("missing input {}", i.symbol)))?;
            if !x.is_finite() {
                return Err(ModelError::value(i.symbol, format!("{} must be finite, got {x}", i.symbol)));
            }
        }
        for a in &self.structure.actuators {
            if let ActuatorTarget::CableLength(_) = a.target {
                if inputs.get(&a.symbol).is_some_and(|l| *l <= 0.0) {
                    return Err(ModelError::value(
                        a.symbol.clone(),
                        format!("cable length {} must be > 0 m", a.symbol),
                    ));
                }
            }
        }
        Ok(())
    }
    fn solve(&self, query: &str, _params: &Values, _inputs: &Values) -> Result<Vec<Solution>, ModelError> {
        Err(ModelError::no_solution(format!("a custom structure has no analytic model (no query '{query}')")))
    }
    fn build(&self, params: &Values, inputs: &Values, _start: &Values) -> Result<Structure, ModelError> {
        let mut s = self.structure_at(params)?.clone();
        for a in &s.actuators {
            if let (ActuatorTarget::CableLength(c), Some(l)) = (&a.target, inputs.get(&a.symbol)) {
                if let crate::structure::Law::Cable { length_m, .. } = &mut s.members[*c].law {
                    *length_m = *l;
                }
            }
        }
        Ok(s)
    }
    /// The one branch: the file's `[[checks]] value`s, if it states any.
    fn predict(&self, _params: &Values, _inputs: &Values) -> Result<Prediction, ModelError> {
        Ok(Prediction {
            expected: self.expected.clone(),
            branches: vec![Solution {
                label: if self.expected.is_empty() { NO_EXPECTED_VALUES } else { EXPECTED_VALUES }.into(),
                values: self.expected.clone(),
                stable: None,
            }],
            expected_slack: None,
        })
    }
    fn observe(&self, _params: &Values, s: &Structure, snap: &Snapshot) -> Values {
        let mut v = Values::new();
        for (i, n) in s.nodes.iter().enumerate() {
            for (k, c) in ["x", "y", "z"].iter().enumerate() {
                v.insert(format!("{}.{c}", n.name), snap.nodes[i][k]);
            }
        }
        for (i, m) in s.members_with_law() {
            v.insert(format!("{}.force", m.name), snap.forces.force_n[i]);
        }
        for (k, f) in self.strut_forces(snap) {
            v.insert(format!("{}.force", s.members[k].name), f);
        }
        v
    }
    fn length_scale(&self, params: &Values) -> f64 {
        crate::structure::structure_size(self.structure_at(params).unwrap_or(&self.structure))
    }
    fn findings(&self, _params: &Values) -> Vec<Finding> {
        Vec::new()
    }
}
