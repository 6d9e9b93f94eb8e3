//! A mechanism with some of its idealizations relaxed (`structure/fidelity.rs`): the paper's
//! mechanism in every respect (its analytic model, inputs, quantities, findings), except that
//! each structure it builds is rewritten with the relaxations, and each snapshot is read as the
//! ideal structure's members carry it (a heavy cable at the node its path ends on).

use super::{Finding, Mechanism, MechanismSpec, ModelError, Prediction, Solution, StiffnessProbe, Values};
use crate::snapshot::Snapshot;
use crate::structure::fidelity::{self, IdealView, Relaxation};
use crate::structure::Structure;

pub struct Relaxed {
    inner: Box<dyn Mechanism>,
    set: Vec<Relaxation>,
    /// The ideal view of the structure built last, which every tick's snapshot is read with
    /// (found again for a structure it does not fit).
    view: std::sync::Mutex<Option<IdealView>>,
}

impl Relaxed {
    pub fn new(inner: Box<dyn Mechanism>, set: Vec<Relaxation>) -> Relaxed {
        Relaxed { inner, set, view: std::sync::Mutex::new(None) }
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
        *self.view.lock().unwrap_or_else(|p| p.into_inner()) = Some(IdealView::of(&s));
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
    /// The inner mechanism's reading of the snapshot as the ideal structure's ([`IdealView`]):
    /// each heavy cable under its ideal name, with the force at its last segment.
    fn observe(&self, params: &Values, s: &Structure, snap: &Snapshot) -> Values {
        let mut view = self.view.lock().unwrap_or_else(|p| p.into_inner());
        let view = match view.as_ref() {
            Some(v) if v.fits(s) => v,
            _ => view.insert(IdealView::of(s)),
        };
        let structure = view.structure(s);
        match view.forces(&snap.forces.force_n) {
            Some(force_n) => {
                let mut ideal = snap.clone();
                ideal.forces.force_n = force_n;
                self.inner.observe(params, structure, &ideal)
            }
            None => self.inner.observe(params, structure, snap),
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
