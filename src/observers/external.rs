//! A model outside the scenario file (a Python callable, say): a function of the parameters,
//! the inputs and a motion's time returning named predictions, each compared with a simulated
//! quantity (the mechanism's, or the file's `[[quantities]]`) exactly as a file's
//! `[[predictions]]` is: at every settle point (the verdict), at every tick (transient errors),
//! over a motion's ticks in a motion run; the same classes, report rows and failure names
//! (`prediction:NAME`). A model that fails (returns an error, or leaves a prediction out) makes
//! its predictions fail with an infinite error; the model itself keeps the reason (the Python
//! package raises it after the run).

use super::file_model::{check_report, Acc, Judged, ModelObserver};
use super::{Made, Note, Observer, SettlePoint, Setup, Tick};
use crate::file_model::spec::ErrorClass;
use crate::mechanisms::Values;
use crate::report::{PointReport, ScenarioReport};
use std::cmp::Ordering;
use std::sync::Arc;

/// A model given as a function: `predict(params, inputs, t)` -> predictions by name; `t` is the
/// time since a motion started \[s\], None outside a motion.
pub trait ExternalModel: Send + Sync {
    fn predict(&self, params: &Values, inputs: &Values, time_s: Option<f64>) -> Result<Values, ExternalError>;
}

/// Why an external model gave no predictions.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ExternalError {
    /// The model raised (its message; the model keeps the error itself, for its caller).
    #[error("the model raised: {0}")]
    Raised(String),
}

/// One prediction of an external model: its name, the simulated quantity it predicts, the
/// error class and the tolerance (and, in a motion run, an optional rms tolerance).
#[derive(Clone, Debug, PartialEq)]
pub struct ExternalPrediction {
    pub name: String,
    pub quantity: String,
    pub class: ErrorClass,
    pub tolerance: f64,
    pub rms_tolerance: Option<f64>,
}

/// An external model and what it predicts, as a run takes them (`RunOptions::external`).
#[derive(Clone)]
pub struct External {
    pub model: Arc<dyn ExternalModel>,
    pub predictions: Vec<ExternalPrediction>,
}

/// The observer of an external model.
pub struct ExternalObserver {
    external: External,
    /// The file's quantities, when it has a model.
    file: Option<ModelObserver>,
    acc: Vec<Acc>,
    motion: bool,
}

impl ExternalObserver {
    pub fn new(external: External, file: Option<ModelObserver>, motion: bool) -> Self {
        let acc = vec![Acc::default(); external.predictions.len()];
        ExternalObserver { external, file, acc, motion }
    }

    /// Each prediction's error with these values (infinite where the model fails).
    fn errors(&self, params: &Values, inputs: &Values, time_s: Option<f64>, simulated: &Values) -> Vec<f64> {
        let predicted = self.external.model.predict(params, inputs, time_s);
        let mut out = Vec::with_capacity(self.external.predictions.len());
        for p in &self.external.predictions {
            let value = predicted.as_ref().ok().and_then(|v| v.get(&p.name).copied());
            let e = match (value, simulated.get(&p.quantity)) {
                (Some(x), Some(s)) => p.class.error(x, *s),
                _ => f64::INFINITY,
            };
            out.push(e);
        }
        out
    }
}

/// A run given a model outside the file (a Python callable) compares it as the file's
/// predictions are (`observers::KINDS`).
pub(super) fn make(setup: &Setup, _warnings: &mut Vec<String>) -> Made {
    let Some(x) = setup.external.clone() else { return Ok(None) };
    let motion = setup.motion.is_some();
    let file = setup.model.map(|spec| ModelObserver::new(spec, setup.structure, false, setup.motion));
    Ok(Some(Box::new(ExternalObserver::new(x, file, motion))))
}

impl Observer for ExternalObserver {
    fn tick(&mut self, t: &Tick, _notes: &mut Vec<Note>) {
        let mut simulated = t.simulated.clone();
        if let Some(f) = &self.file {
            simulated.extend(f.quantities(t.snapshot, t));
        }
        let errors = self.errors(t.params, t.inputs, t.motion_time_s, &simulated);
        for (a, e) in self.acc.iter_mut().zip(errors) {
            a.tick(e);
            if t.motion_time_s.is_some() {
                a.motion_tick(e);
            }
        }
    }

    fn settle_point(&mut self, p: &SettlePoint, point: &mut PointReport, _notes: &mut Vec<Note>) {
        if p.outside_model || self.motion {
            return;
        }
        let errors = self.errors(p.params, &point.inputs, None, &point.simulated);
        for ((a, e), pr) in self.acc.iter_mut().zip(errors).zip(&self.external.predictions) {
            a.point(e, point.settled);
            if point.settled && e.partial_cmp(&pr.tolerance).is_none_or(Ordering::is_gt) {
                point.within_tolerance = false;
            }
        }
    }

    fn finish(&mut self, report: &mut ScenarioReport) {
        for (p, a) in self.external.predictions.iter().zip(&self.acc) {
            let judged = Judged {
                kind: "prediction",
                name: &p.name,
                class: p.class.name(),
                tolerance: p.tolerance,
                rms_tolerance: p.rms_tolerance,
            };
            report.model_checks.push(check_report(&judged, a, self.motion));
        }
    }
}
