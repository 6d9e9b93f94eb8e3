//! A mechanism with some of its idealizations relaxed (`structure/fidelity.rs`): the paper's
//! mechanism in every respect (its analytic model, inputs, quantities, findings), except that
//! each structure it builds is rewritten with the relaxations, and each snapshot is read as the
//! ideal structure's members carry it (a heavy cable at the node its path ends on).

use super::{Finding, Mechanism, MechanismSpec, ModelError, Prediction, Solution, StiffnessProbe, Values};
use crate::snapshot::Snapshot;
use crate::structure::fidelity::{self, Relaxation};
use crate::structure::Structure;

pub struct Relaxed {
    inner: Box<dyn Mechanism>,
    set: Vec<Relaxation>,
}

impl Relaxed {
    pub fn new(inner: Box<dyn Mechanism>, set: Vec<Relaxation>) -> Relaxed {
        Relaxed { inner, set }
    }
}

impl Mechanism for Relaxed {
    fn spec(&self) -> &MechanismSpec {
        self.inner.spec()
    }
    fn quantities(&self) -> &'static [super::QuantitySpec] {
        self.inner.quantities()
    }
    fn start_flags(&self) -> &'static [&'static str] {
        self.inner.start_flags()
    }
    fn start_exclusive(&self) -> &'static [(&'static str, &'static str)] {
        self.inner.start_exclusive()
    }
    fn validate_params(&self, params: &Values) -> Result<(), ModelError> {
        self.inner.validate_params(params)
    }
    fn convert_inputs(&self, params: &Values, given: &Values) -> Result<Values, ModelError> {
        self.inner.convert_inputs(params, given)
    }
    fn validate_inputs(&self, params: &Values, inputs: &Values) -> Result<(), ModelError> {
        self.inner.validate_inputs(params, inputs)
    }
    fn solve(&self, query: &str, params: &Values, inputs: &Values) -> Result<Vec<Solution>, ModelError> {
        self.inner.solve(query, params, inputs)
    }
    /// The inner mechanism's structure with the relaxations applied.
    fn build(&self, params: &Values, inputs: &Values, start: &Values) -> Result<Structure, ModelError> {
        let mut s = self.inner.build(params, inputs, start)?;
        let set: Vec<&Relaxation> = self.set.iter().collect();
        fidelity::relax(&mut s, &set, &self.inner.commands(params, inputs))
            .map_err(|e| ModelError::no_solution(e.to_string()))?;
        Ok(s)
    }
    fn commands(&self, params: &Values, inputs: &Values) -> Values {
        self.inner.commands(params, inputs)
    }
    fn starts_on_unstable_branch(&self, start: &Values) -> bool {
        self.inner.starts_on_unstable_branch(start)
    }
    fn predict(&self, params: &Values, inputs: &Values) -> Result<Prediction, ModelError> {
        self.inner.predict(params, inputs)
    }
    /// The inner mechanism's reading of the snapshot with the ideal members' forces
    /// ([`fidelity::ideal_forces`]), and each heavy cable's `NAME.force` under its ideal name.
    fn observe(&self, params: &Values, s: &Structure, snap: &Snapshot) -> Values {
        let mut view = snap.clone();
        view.forces.force_n = fidelity::ideal_forces(s, &snap.forces.force_n);
        match fidelity::ideal_names(s) {
            Some(named) => self.inner.observe(params, &named, &view),
            None => self.inner.observe(params, s, &view),
        }
    }
    fn length_scale(&self, params: &Values) -> f64 {
        self.inner.length_scale(params)
    }
    fn paper_values(&self, params: &Values, inputs: &Values) -> Option<(String, Values)> {
        self.inner.paper_values(params, inputs)
    }
    fn analytic_nodes(&self, params: &Values, inputs: &Values) -> Option<Vec<[f64; 3]>> {
        self.inner.analytic_nodes(params, inputs)
    }
    fn stiffness_probe(&self) -> Option<StiffnessProbe> {
        self.inner.stiffness_probe()
    }
    fn findings(&self, params: &Values) -> Vec<Finding> {
        self.inner.findings(params)
    }
}
