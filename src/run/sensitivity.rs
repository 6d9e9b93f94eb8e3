//! A settled state's sensitivities to every parameter (`study::sensitivity` settles a point and
//! calls this; a run's settle point reads a file's `[[sensitivities]]` here), by the
//! implicit function theorem: at the equilibrium the generalized forces Q(q, p) vanish, so
//! dq/dp = K^-1 dQ/dp with K = -dQ/dq the tangent stiffness (`sim::sensitivity`). dQ/dp is
//! the difference of Q over the parameter at a fixed state: the structure built again at
//! p +- h and p +- 2 h (with its commands at the scenario's inputs), put in the settled
//! configuration, Q read there, extrapolated (error O(h^4)); no settle. The outputs' total
//! derivatives dy/dp = dy/dq dq/dp + dy/dp|q are the same samples moved along dq/dp: y at
//! (q + s h dq/dp, p + s h), s = +-1, +-2. The frequencies' from the eigenvectors,
//! d omega^2 / dp = phi^T (dK/dp - omega^2 dM/dp) phi (K and M along the same samples), and
//! d omega / dp = (d omega^2 / dp) / (2 |omega|).

use super::RunError;
use crate::eigen::Mode;
use crate::mechanisms::{Mechanism, Values};
use crate::observers::file_model::ModelObserver;
use crate::report::sensitivity::ParameterSensitivity;
use crate::scenario::Scenario;
use crate::sim::modes::{least_squares, ZERO_MODE_RATIO};
use crate::sim::sensitivity::{
    derivative_and_estimate, derivative_from_samples, EquilibriumCoordinates, SensitivityError,
};
use crate::sim::sparse_sensitivity::SparseLinearization;
use crate::sim::Simulation;
use crate::structure::DENSE_MODAL_MAX_FREE_BODIES;
use nalgebra::{DMatrix, DVector};

/// A parameter's finite-difference step, a fraction of its value (error O(h^4) with the
/// extrapolation: about 1e-12; round-off eps / h: about 1e-13).
pub const STEP_RATIO: f64 = 1e-3;
/// The step of a parameter whose value is 0, in its own unit.
pub const ZERO_PARAMETER_STEP: f64 = 1e-3;
/// The samples of every difference, in steps: -2 h, -h, h, 2 h.
const SAMPLES: [f64; 4] = [-2.0, -1.0, 1.0, 2.0];
/// The move along a rigid-body mode that tells which outputs it moves: its largest
/// coordinate this fraction of the structure's size (m, or rad per m).
const RIGID_PROBE_RATIO: f64 = 1e-5;
/// An output moves with a rigid-body mode when that move (a central difference over +- the
/// move) changes it by more than this fraction of its value (or of the move, for a value near
/// 0): round-off and the move's third order change the others by about 1e-15.
const RIGID_OUTPUT_RATIO: f64 = 1e-9;
/// Natural frequencies reported (the lowest modes that are not rigid-body modes).
pub const FREQUENCIES_LISTED: usize = 6;

/// Why a scenario has no sensitivities.
#[derive(Debug, thiserror::Error)]
pub enum SensitivityRunError {
    /// The settle stopped (divergence, interruption, a model error).
    #[error(transparent)]
    Run(#[from] RunError),
    /// The structure's sensitivities are not computed, by name (bad input).
    #[error(transparent)]
    Refused(SensitivityError),
    /// The scenario has no such point (bad input).
    #[error("the scenario has no point {0} (its points are numbered from 0)")]
    NoPoint(usize),
    /// The structure at a check's sample could not be read.
    #[error("{0}")]
    Check(SampleError),
    /// The eigenproblem at the settled state failed.
    #[error(transparent)]
    Eigen(#[from] crate::eigen::EigenError),
}

/// Why the structure at a step of a parameter could not be made.
#[derive(Debug, thiserror::Error)]
pub enum SampleError {
    /// The scenario does not resolve at the step's parameters.
    #[error(transparent)]
    Scenario(#[from] crate::scenario::ScenarioError),
    /// The mechanism could not build its structure there.
    #[error(transparent)]
    Model(#[from] crate::mechanisms::ModelError),
    /// The simulator could not build it.
    #[error(transparent)]
    Sim(#[from] crate::sim::SimError),
    /// The step switches the model: the structure built there is another than the settled
    /// one's (other bodies, nodes or members, or a member's law or a joint's kind changed).
    #[error("{0}")]
    Switch(String),
}

/// Why a file's `[[sensitivities]]` were not computed at a settle point.
#[derive(Debug, thiserror::Error)]
pub enum FileSensitivityError {
    /// The settled state has no sensitivities.
    #[error("{0}")]
    Analysis(#[from] SensitivityRunError),
    /// One derivative could not be computed (`why`: the parameter's error in the report).
    #[error("d {output}/d {parameter}: {why}")]
    Derivative { output: String, parameter: String, why: String },
}

/// Each sample's parameters and inputs, in the order of [`SAMPLES`].
pub(crate) type Samples = Vec<(Values, Values)>;

/// What an output sample needs of the scenario: its mechanism, inputs and model.
pub(crate) struct Outputs<'a> {
    sc: &'a Scenario,
    mech: Box<dyn Mechanism>,
    pub(crate) inputs: Values,
    model: Option<ModelObserver>,
    pub(crate) coordinates: EquilibriumCoordinates,
    /// Whether each output name asked so far is an angle (`Scenario::is_angle` scans the
    /// quantities: a 300-strut prism's 3,005 outputs at each of its samples had spent most of
    /// its sensitivities' time there).
    angles: std::cell::RefCell<std::collections::HashMap<String, bool>>,
}

/// The analysis of a settled state: what its samples need, its linearization, the listed
/// modes, and every output there.
pub(crate) struct Analysis<'a> {
    pub(crate) out: Outputs<'a>,
    pub(crate) lin: Linearization,
    pub(crate) listed: Vec<usize>,
    pub(crate) base: Vec<(String, f64)>,
}

/// A settled state linearized in its coordinates: K, G (no rows without constraints), the
/// modes K phi = omega^2 M phi on null(G), each phi mass-normalised in the coordinates, and
/// which are rigid-body modes (|omega^2| below [`ZERO_MODE_RATIO`] of the largest, or with
/// constraints below the reduced Hessian's own error, `constrained_modes::zero_floor`).
pub(crate) struct Linearization {
    stiffness: Stiffness,
    jacobian: DMatrix<f64>,
    pub(crate) modes: Vec<Mode>,
    pub(crate) rigid: Vec<bool>,
    /// The point masses' turns among the zero modes (three each, over free bodies), which the
    /// modal analysis leaves out (`sim/modes.rs`) and the modes' names therefore skip.
    left_out: usize,
}

/// K as the linearization holds it: dense, or for a structure of more than
/// [`DENSE_MODAL_MAX_FREE_BODIES`] free bodies (where `tensegrity modes` turns sparse) its
/// lowest modes and the sparse solve of K x = r (`sim/sparse_sensitivity.rs`).
enum Stiffness {
    Dense(DMatrix<f64>),
    Sparse(Box<SparseLinearization>),
}

impl Linearization {
    /// The number of coordinates (each parameter's dq/dp has as many).
    pub(crate) fn size(&self) -> usize {
        match &self.stiffness {
            Stiffness::Dense(k) => k.ncols(),
            Stiffness::Sparse(sparse) => sparse.size(),
        }
    }

    /// The output name of non-rigid mode `i` (from 0) of [`Self::modes`]: `mode{N}.omega`, N
    /// numbered as `tensegrity modes` numbers it. The modes ascend in omega^2: an unstable one
    /// comes before every zero mode, a stable one after them all, the left-out turns among them.
    pub(crate) fn mode_name(&self, i: usize) -> String {
        let before_turns = self.modes[i].omega_squared < 0.0;
        format!("mode{}.omega", if before_turns { i + 1 } else { i + 1 - self.left_out })
    }
}

/// K, M and G of `sim` in `coordinates`, and the modes of the reduced problem
/// (N^T K N) v = omega^2 (N^T M N) v, N a basis of null(G), phi = N v (all coordinates where
/// there is no constraint).
pub(crate) fn linearize(
    sim: &mut Simulation,
    coordinates: &EquilibriumCoordinates,
) -> Result<Linearization, SensitivityRunError> {
    if let EquilibriumCoordinates::Bodies(bodies) = coordinates {
        if bodies.len() > DENSE_MODAL_MAX_FREE_BODIES {
            let refused = |e| SensitivityRunError::Refused(SensitivityError::Modes(e));
            let (modes, rigid, sparse) = sim.sparse_linearization(bodies, FREQUENCIES_LISTED).map_err(refused)?;
            let stiffness = Stiffness::Sparse(Box::new(sparse));
            return Ok(Linearization { stiffness, jacobian: DMatrix::zeros(0, 0), modes, rigid, left_out: 0 });
        }
    }
    let (stiffness, error) = sim.equilibrium_stiffness_and_error(coordinates);
    let mass = sim.equilibrium_mass(coordinates);
    let jacobian = sim.constraint_jacobian(coordinates);
    let (modes, floor) = if coordinates.constraints().is_none() {
        (crate::eigen::modes(&symmetric(&stiffness), &symmetric(&mass))?, 0.0)
    } else {
        let (basis, _) = crate::sim::modes::null_space(&jacobian, stiffness.ncols());
        if basis.ncols() == 0 {
            (Vec::new(), 0.0)
        } else {
            let reduce = |a: &DMatrix<f64>| symmetric(&(basis.transpose() * a * &basis));
            let reduced_mass = reduce(&mass);
            let reduced = crate::eigen::modes(&reduce(&stiffness), &reduced_mass)?;
            let floor = crate::sim::modes::zero_floor(&error, &basis, &reduced_mass);
            (reduced.into_iter().map(|m| Mode { shape: &basis * m.shape, ..m }).collect(), floor)
        }
    };
    let largest = modes.iter().fold(0.0f64, |l, m| l.max(m.omega_squared.abs()));
    let rigid = modes.iter().map(|m| m.omega_squared.abs() <= (ZERO_MODE_RATIO * largest).max(floor)).collect();
    let s = sim.structure();
    let left_out = match coordinates {
        EquilibriumCoordinates::Bodies(bodies) => {
            crate::sim::modes::turning_coordinates(s, bodies).into_iter().filter(|&t| t).count()
        }
        _ => 0,
    };
    Ok(Linearization { stiffness: Stiffness::Dense(stiffness), jacobian, modes, rigid, left_out })
}

/// The analysis of `sim`, settled at `params` and `inputs` of `sc`.
pub(crate) fn analyse<'a>(
    sc: &'a Scenario,
    sim: &mut Simulation,
    params: &Values,
    inputs: Values,
) -> Result<Analysis<'a>, SensitivityRunError> {
    let coordinates = sim.equilibrium_coordinates().map_err(SensitivityRunError::Refused)?;
    let model = sc.model.as_ref().map(|spec| ModelObserver::new(spec, sim.structure(), false, None));
    let out = Outputs { sc, mech: sc.mechanism(), inputs, model, coordinates, angles: Default::default() };
    let lin = linearize(sim, &out.coordinates)?;
    let listed = listed_modes(&lin.rigid);
    let mut base = out.sample(sim, params);
    base.extend(listed.iter().map(|&i| (lin.mode_name(i), lin.modes[i].omega())));
    Ok(Analysis { out, lin, listed, base })
}

/// The file's `[[sensitivities]]` at a settle point of a run (`sim` settled at `params` and
/// `inputs`), by their names: each d(output)/d(parameter), NaN where the output is not one of
/// the state's (a mode it has not), and beside them each one's error estimate; Err where the
/// state has no sensitivities (the reason).
pub(super) fn file_sensitivities(
    sc: &Scenario,
    sim: &mut Simulation,
    params: &Values,
    inputs: &Values,
) -> Result<(Values, Values), FileSensitivityError> {
    let wanted = sc.model.as_ref().map_or(&[][..], |m| &m.sensitivities[..]);
    let a = analyse(sc, sim, params, inputs.clone())?;
    let mut rows: Vec<ParameterSensitivity> = Vec::new();
    let (mut out, mut estimates) = (Values::new(), Values::new());
    for s in wanted {
        if !rows.iter().any(|r| r.name == s.parameter) {
            let value = params.get(&s.parameter).copied().unwrap_or(f64::NAN);
            rows.push(a.out.parameter(sim, params, &s.parameter, value, &a.lin, &a.listed));
        }
        let row = rows.iter().find(|r| r.name == s.parameter).expect("computed above");
        if let Some(e) = row.error.as_ref().or(row.switch.as_ref()) {
            let (output, parameter, why) = (s.output.clone(), s.parameter.clone(), e.clone());
            return Err(FileSensitivityError::Derivative { output, parameter, why });
        }
        let i = a.base.iter().position(|(n, _)| n == &s.output);
        out.insert(s.name.clone(), i.map_or(f64::NAN, |i| row.derivatives[i]));
        estimates.insert(s.name.clone(), i.and_then(|i| row.estimates.get(i).copied()).unwrap_or(f64::NAN));
    }
    Ok((out, estimates))
}

/// How the structure `step` built at a parameter's step is another model than the `settled`
/// one (None: the same, its numbers aside): other counts of bodies, nodes, joints, members or
/// actuators, a member's law (mohr2011's k_cable at its default 0: inextensible cables, elastic
/// ones at any step above), a joint's kind or torsion spring (furet2018's k_servo at 0: ideal
/// actuators, servos above) or an actuator's target. Such a parameter switches the model there
/// and has no derivative.
fn switched(settled: &crate::structure::Structure, step: &crate::structure::Structure) -> Option<String> {
    use crate::structure::{CableLaw, Law};
    let counts = |a: &crate::structure::Structure| {
        (a.bodies.len(), a.nodes.len(), a.joints.len(), a.members.len(), a.actuators.len())
    };
    if counts(settled) != counts(step) {
        return Some("the structure built at the step has other bodies, nodes or members".into());
    }
    let law = |m: &crate::structure::Member| match &m.law {
        Law::Strut => "a rigid strut",
        Law::ElasticStrut { .. } => "an elastic strut",
        Law::Spring { .. } => "a spring",
        Law::Cable { law: CableLaw::Inextensible, .. } => "an inextensible cable",
        Law::Cable { law: CableLaw::Elastic { .. }, .. } => "an elastic cable",
    };
    if let Some((a, b)) = settled.members.iter().zip(&step.members).find(|(a, b)| law(a) != law(b)) {
        return Some(format!("member '{}' is {} at the value and {} at the step", a.name, law(a), law(b)));
    }
    let joint = |j: &crate::structure::Joint| (std::mem::discriminant(&j.kind), j.torsion_spring.is_some());
    if let Some((a, b)) = settled.joints.iter().zip(&step.joints).find(|(a, b)| joint(a) != joint(b)) {
        let spring = |s: bool| if s { "with a torsion spring" } else { "without one" };
        return Some(match joint(a).0 == joint(b).0 {
            true => format!(
                "joint '{}' is {} at the value and {} at the step",
                a.name,
                spring(joint(a).1),
                spring(joint(b).1)
            ),
            false => format!("joint '{}' is of another kind at the step", a.name),
        });
    }
    let target = |a: &crate::structure::Actuator| std::mem::discriminant(&a.target);
    let changed = settled.actuators.iter().zip(&step.actuators).find(|(a, b)| target(a) != target(b));
    changed.map(|(a, _)| format!("actuator '{}' drives another target at the step", a.symbol))
}

/// (K + K^T) / 2: the difference's K is symmetric up to its error and the equilibrium's.
fn symmetric(a: &DMatrix<f64>) -> DMatrix<f64> {
    0.5 * (a + a.transpose())
}

/// The modes whose frequencies are reported: the lowest [`FREQUENCIES_LISTED`] that are not
/// rigid-body modes ([`Linearization`]), by index.
fn listed_modes(rigid: &[bool]) -> Vec<usize> {
    (0..rigid.len()).filter(|&i| !rigid[i]).take(FREQUENCIES_LISTED).collect()
}

/// For each listed mode phi (omega^2) of the settled state, phi_s^T (K - omega^2 M) phi_s in
/// `sim`'s state, phi_s = (1 - G^+ G) phi its projection on the constraints' tangent space
/// there (phi itself without constraints): differenced over the parameter's samples, Nelson's
/// d omega^2 / dp (module docs of sim/constrained_sensitivity.rs).
fn modal_curvatures(
    sim: &mut Simulation,
    c: &EquilibriumCoordinates,
    lin: &Linearization,
    listed: &[usize],
) -> DVector<f64> {
    let modes = &lin.modes;
    if let Stiffness::Sparse(_) = lin.stiffness {
        // From the forces along phi (`sim/sparse_sensitivity.rs`): no K of every coordinate.
        let curvature = |&i: &usize| sim.modal_curvature(c, &modes[i].shape, modes[i].omega_squared);
        return DVector::from_vec(listed.iter().map(curvature).collect());
    }
    let k = sim.equilibrium_stiffness(c);
    let mass = sim.equilibrium_mass(c);
    let g = sim.constraint_jacobian(c);
    DVector::from_iterator(
        listed.len(),
        listed.iter().map(|&i| {
            let (phi, w2) = (&modes[i].shape, modes[i].omega_squared);
            let phi = phi - least_squares(&g, &(&g * phi));
            phi.dot(&(&k * &phi)) - w2 * phi.dot(&(&mass * &phi))
        }),
    )
}

/// K^-1 r over the modes that are not rigid: sum of phi (phi^T r) / omega^2 (phi
/// mass-normalised, so that K^-1 = Phi Lambda^-1 Phi^T); a rigid motion is left where it is.
fn solve(lin: &Linearization, r: &DVector<f64>) -> Result<DVector<f64>, crate::eigen::EigenError> {
    if let Stiffness::Sparse(sparse) = &lin.stiffness {
        return sparse.solve(r);
    }
    let mut x = DVector::zeros(r.len());
    for (m, _) in lin.modes.iter().zip(&lin.rigid).filter(|(_, rigid)| !**rigid) {
        x += &m.shape * (m.shape.dot(r) / m.omega_squared);
    }
    Ok(x)
}

impl Linearization {
    /// dq/dp and the constraint forces' dlambda/dp from dQ/dp and dg/dp: the move that keeps
    /// the constraints (module docs of sim/constrained_sensitivity.rs), then the equilibrium
    /// along null(G).
    fn displacement(
        &self,
        dq_dp: &DVector<f64>,
        dg_dp: &DVector<f64>,
    ) -> Result<(DVector<f64>, DVector<f64>), crate::eigen::EigenError> {
        let Stiffness::Dense(k) = &self.stiffness else {
            return Ok((solve(self, dq_dp)?, DVector::zeros(0)));
        };
        let particular = -least_squares(&self.jacobian, dg_dp);
        let dq = solve(self, &(dq_dp - k * &particular))? + &particular;
        let dlambda = least_squares(&self.jacobian.transpose(), &(dq_dp - k * &dq));
        Ok((dq, dlambda))
    }
}

/// Parameter `name`'s row at `value` before anything is computed: its step, no derivatives.
fn row_of(name: &str, value: f64) -> ParameterSensitivity {
    ParameterSensitivity {
        name: name.to_string(),
        value,
        step: parameter_step(value),
        coordinates: vec![],
        derivatives: vec![],
        estimates: vec![],
        check: None,
        max_check_error: None,
        error: None,
        switch: None,
        unused: false,
    }
}

/// The row of a parameter that nothing in the file reads (`Scenario::unread_params`): no
/// steps are built, and each of the `coordinates` and `outputs` derivatives is 0, which is
/// what the steps would give (every structure the settled one).
pub(crate) fn unused_row(name: &str, value: f64, coordinates: usize, outputs: usize) -> ParameterSensitivity {
    ParameterSensitivity {
        coordinates: vec![0.0; coordinates],
        derivatives: vec![0.0; outputs],
        estimates: vec![0.0; outputs],
        unused: true,
        ..row_of(name, value)
    }
}

/// A parameter's step: [`STEP_RATIO`] of its value, or [`ZERO_PARAMETER_STEP`] at 0.
pub fn parameter_step(value: f64) -> f64 {
    if value == 0.0 {
        ZERO_PARAMETER_STEP
    } else {
        STEP_RATIO * value.abs()
    }
}

impl Outputs<'_> {
    /// Every parameter's value with `name` at `value`, its derived ones following (as
    /// `--set NAME=VALUE` would give them), and the inputs with it where they name it.
    fn moved(&self, params: &Values, name: &str, value: f64) -> (Values, Values) {
        let mut point = self.inputs.clone();
        point.insert(name.to_string(), value);
        let mut moved = params.clone();
        moved.extend(
            self.sc.param_table.evaluate(
                &point.iter().filter(|(k, _)| params.contains_key(*k)).map(|(k, v)| (k.clone(), *v)).collect(),
            ),
        );
        moved.insert(name.to_string(), value);
        let inputs = self.inputs.iter().map(|(k, v)| (k.clone(), if k == name { value } else { *v })).collect();
        (moved, inputs)
    }

    /// The scenario with its structure at parameter `name`'s samples (`scenario`: resolved
    /// there as at a sweep's sets of parameters), and each sample's parameters and inputs.
    pub(crate) fn samples(
        &self,
        params: &Values,
        name: &str,
        value: f64,
        h: f64,
    ) -> Result<(Scenario, Samples), SampleError> {
        let moved: Vec<(Values, Values)> = SAMPLES.iter().map(|s| self.moved(params, name, value + s * h)).collect();
        let sets: Vec<Values> = moved.iter().map(|(p, _)| p.clone()).collect();
        let sc = self.sc.with_parameter_sets(&sets)?;
        Ok((sc, moved))
    }

    /// The structure of `mech` built at `params` and `inputs`, commanded there, in `at`'s
    /// configuration.
    fn rebuilt(
        &self,
        mech: &dyn Mechanism,
        at: &Simulation,
        params: &Values,
        inputs: &Values,
    ) -> Result<Simulation, SampleError> {
        let s = mech.build(params, inputs, &self.sc.start)?;
        if let Some(why) = switched(at.structure(), &s) {
            return Err(SampleError::Switch(why));
        }
        let mut sim = Simulation::new(&s, &self.sc.sim)?;
        let commands = sim.structure().commands_from(&mech.commands(params, inputs));
        sim.set_commands(&commands);
        sim.take_configuration(at, &self.coordinates);
        Ok(sim)
    }

    /// Every output but the frequencies in `sim`'s state at `params`, by name: the mechanism's
    /// observed quantities (a custom structure's node coordinates and member forces), each
    /// joint's coordinate and the file's quantities.
    pub(crate) fn sample(&self, sim: &Simulation, params: &Values) -> Vec<(String, f64)> {
        let s = sim.structure();
        let snap = sim.snapshot_with(false);
        let observed = self.mech.observe(params, s, &snap);
        let mut out: Vec<(String, f64)> = observed.iter().map(|(k, v)| (k.clone(), *v)).collect();
        for (j, joint) in s.joints.iter().enumerate() {
            let kind = match joint.kind {
                crate::structure::JointKind::Prismatic { .. } => "slide",
                _ => "angle",
            };
            if let Some(q) = snap.joint_coordinate(s, j) {
                out.push((format!("{}.{kind}", joint.name), q));
            }
        }
        if let Some(model) = &self.model {
            out.extend(model.quantities_at(&snap, &self.inputs, params, &observed));
        }
        out
    }

    /// Whether each output of `base` moves with a rigid-body mode (a free motion that no
    /// parameter sets: a node's coordinates where the structure may turn): the settled state
    /// moved along each such mode by [`RIGID_PROBE_RATIO`] of the structure's size at its
    /// largest node motion, and back. The frequencies are fixed by the modes.
    pub(crate) fn free_outputs(
        &self,
        sim: &mut Simulation,
        params: &Values,
        lin: &Linearization,
        base: &[(String, f64)],
    ) -> Vec<bool> {
        let mut free = vec![false; base.len()];
        for (m, _) in lin.modes.iter().zip(&lin.rigid).filter(|(_, rigid)| **rigid) {
            let eta = RIGID_PROBE_RATIO * sim.length_scale_m() / m.shape.amax().max(f64::MIN_POSITIVE);
            let mut moved = Vec::new();
            for s in [1.0, -1.0] {
                let step: Vec<f64> = m.shape.iter().map(|v| s * eta * v).collect();
                sim.displace_coordinates(&self.coordinates, &step);
                moved.push(self.offsets(&self.sample(sim, params), base));
                let back: Vec<f64> = step.iter().map(|v| -v).collect();
                sim.displace_coordinates(&self.coordinates, &back);
            }
            // The central difference: the move's second order (small rotations one after the
            // other) cancels.
            let moved = (&moved[0] - &moved[1]) * 0.5;
            for (f, (d, (_, y))) in free.iter_mut().zip(moved.iter().zip(base)) {
                *f |= d.abs() > RIGID_OUTPUT_RATIO * y.abs().max(sim.length_scale_m() * RIGID_PROBE_RATIO);
            }
        }
        free
    }

    /// Whether output `name` is an angle, asked of the scenario once per name.
    fn is_angle(&self, name: &str) -> bool {
        if let Some(&angle) = self.angles.borrow().get(name) {
            return angle;
        }
        let angle = self.sc.is_angle(name);
        self.angles.borrow_mut().insert(name.to_string(), angle);
        angle
    }

    /// The samples' values less the settled state's `base` (as many as the sample has), an
    /// angle's wrapped to (-pi, pi].
    pub(crate) fn offsets(&self, sample: &[(String, f64)], base: &[(String, f64)]) -> DVector<f64> {
        DVector::from_iterator(
            sample.len(),
            base.iter().zip(sample).map(
                |((name, b), (_, v))| {
                    if self.is_angle(name) {
                        crate::mechanisms::wrap_angle(v - b)
                    } else {
                        v - b
                    }
                },
            ),
        )
    }

    /// Every output's derivative with respect to parameter `name` (at `value`) at the settled
    /// state `at` (module docs): outputs first, then the listed modes' omega.
    pub(crate) fn parameter(
        &self,
        at: &Simulation,
        params: &Values,
        name: &str,
        value: f64,
        lin: &Linearization,
        listed: &[usize],
    ) -> ParameterSensitivity {
        let h = parameter_step(value);
        let mut row = row_of(name, value);
        if self.sc.topology_params.iter().any(|t| t == name) {
            row.switch =
                Some(format!("a pattern reads {name}: it sets the structure's counts, which have no derivative"));
            return row;
        }
        let (sc, samples) = match self.samples(params, name, value, h) {
            Ok(s) => s,
            Err(e) => {
                row.error = Some(e.to_string());
                return row;
            }
        };
        let mech = sc.mechanism();
        let mut sims = Vec::new();
        for ((moved, inputs), s) in samples.into_iter().zip(SAMPLES) {
            match self.rebuilt(mech.as_ref(), at, &moved, &inputs) {
                Ok(sim) => sims.push((sim, moved)),
                Err(SampleError::Switch(why)) => {
                    row.switch =
                        Some(format!("the model switches between {name} = {value} and {}: {why}", value + s * h));
                    return row;
                }
                Err(e) => {
                    row.error = Some(format!("at {name} = {}: {e}", value + s * h));
                    return row;
                }
            }
        }
        let q: Vec<DVector<f64>> = sims.iter_mut().map(|(sim, _)| sim.generalized_forces(&self.coordinates)).collect();
        let g: Vec<DVector<f64>> = sims.iter().map(|(sim, _)| sim.constraint_values(&self.coordinates)).collect();
        let dq_dp = derivative_from_samples(q[0].clone(), q[1].clone(), q[2].clone(), q[3].clone(), h);
        let dg_dp = derivative_from_samples(g[0].clone(), g[1].clone(), g[2].clone(), g[3].clone(), h);
        // The move that keeps the constraints (module docs of sim/constrained_sensitivity.rs),
        // then the equilibrium along null(G).
        let (dq, dlambda) = match lin.displacement(&dq_dp, &dg_dp) {
            Ok(d) => d,
            Err(e) => {
                row.error = Some(format!("the static response to {name} was not solved: {e}"));
                return row;
            }
        };
        let lambda = self.coordinates.constraints().map_or(vec![], |c| c.multipliers.clone());
        let base = self.sample(at, params);
        let mut y = Vec::new();
        let mut curvature = Vec::new();
        for ((sim, moved), s) in sims.iter_mut().zip(SAMPLES) {
            let step: Vec<f64> = dq.iter().map(|d| s * h * d).collect();
            sim.displace_coordinates(&self.coordinates, &step);
            y.push(self.offsets(&self.sample(sim, moved), &base));
            let held: Vec<f64> = lambda.iter().zip(dlambda.iter()).map(|(l, d)| l + s * h * d).collect();
            curvature.push(modal_curvatures(sim, &self.coordinates.with_multipliers(&held), lin, listed));
        }
        // Both sample sets are 0 at the settled state itself (offsets from it; the curvature of
        // its own eigenpairs), which the estimate's noise part reads.
        let (dy, dy_estimate) = derivative_and_estimate(&y[0], &y[1], &y[2], &y[3], h);
        let c = &curvature;
        let (dw2, dw2_estimate) = derivative_and_estimate(&c[0], &c[1], &c[2], &c[3], h);
        let omega = |i: usize| 2.0 * lin.modes[i].omega_squared.abs().sqrt();
        row.coordinates = dq.iter().copied().collect();
        row.derivatives = dy.iter().copied().collect();
        row.derivatives.extend(listed.iter().zip(dw2.iter()).map(|(&i, dw2)| dw2 / omega(i)));
        row.estimates = dy_estimate.iter().copied().collect();
        row.estimates.extend(listed.iter().zip(dw2_estimate.iter()).map(|(&i, e)| e / omega(i)));
        row
    }
}
