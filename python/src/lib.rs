//! The testbed's own API for Python (`tensegrity_testbed._tensegrity`; the package's
//! `__init__.py` wraps it): a scenario checked and run by the same code as the CLI, the report
//! handed over as its JSON. Runs release the GIL and stop at the next tick on Ctrl-C.

use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tensegrity_testbed::file_model::spec::ErrorClass;
use tensegrity_testbed::observers::external::{External, ExternalModel, ExternalPrediction};
use tensegrity_testbed::run::{self, RunOptions};
use tensegrity_testbed::scenario::{self, Override, Scenario, ScenarioError};

create_exception!(
    _tensegrity,
    TestbedError,
    PyException,
    "A scenario the testbed refuses (args: file, line, col, message)."
);

/// How often a run's waiting thread looks for Ctrl-C [s].
const SIGNAL_POLL_S: f64 = 0.05;

fn scenario_error(e: ScenarioError) -> PyErr {
    TestbedError::new_err((e.file.clone(), e.line, e.col, e.message.clone()))
}

/// The scenario from a path (`text` None) or from TOML text named `path`, with `NAME=VALUE`
/// overrides.
fn load(path: &str, text: Option<&str>, set: &[String]) -> PyResult<Scenario> {
    let overrides: Vec<Override> =
        set.iter().map(|s| Override::parse(s).map_err(PyValueError::new_err)).collect::<PyResult<_>>()?;
    match text {
        Some(t) => scenario::parse_with(Path::new(path), t, &overrides),
        None => scenario::load_with(Path::new(path), &overrides),
    }
    .map_err(scenario_error)
}

/// Checks a scenario: its name, or TestbedError at its file, line and column.
#[pyfunction]
#[pyo3(signature = (path, text=None, set=Vec::new()))]
fn check(path: &str, text: Option<&str>, set: Vec<String>) -> PyResult<String> {
    Ok(load(path, text, &set)?.name)
}

/// Runs `work` on a thread of its own without the GIL, polling for Ctrl-C every
/// [`SIGNAL_POLL_S`]: on one it raises the flag `work` watches (the run stops at its next
/// tick), waits for it and raises KeyboardInterrupt.
fn on_own_thread<T: Send + 'static>(
    py: Python<'_>,
    work: impl FnOnce(&AtomicBool) -> T + Send + 'static,
) -> PyResult<T> {
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&cancel);
    let (done, result) = std::sync::mpsc::channel();
    let worker = std::thread::spawn(move || {
        // The receiver is gone only after an interruption: nothing is waiting for the result.
        let _ = done.send(work(&flag));
    });
    let poll = Duration::from_secs_f64(SIGNAL_POLL_S);
    // Waited on without the GIL, which needs a Sync receiver.
    let result = Mutex::new(result);
    loop {
        match py.detach(|| result.lock().expect("one waiter").recv_timeout(poll)) {
            Ok(value) => {
                let _ = py.detach(|| worker.join());
                return Ok(value);
            }
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                return Err(PyException::new_err("the run panicked"));
            }
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
        }
        if let Err(e) = py.check_signals() {
            cancel.store(true, Ordering::SeqCst);
            let _ = py.detach(|| worker.join());
            return Err(e);
        }
    }
}

/// Sweeps a scenario's grid (or points) in parallel on `jobs` threads (0: every core): the
/// CSV of `tensegrity sweep --out` and the JSON summary of `--json`.
#[pyfunction]
#[pyo3(signature = (path, text=None, set=Vec::new(), jobs=0))]
fn sweep_csv(
    py: Python<'_>,
    path: &str,
    text: Option<&str>,
    set: Vec<String>,
    jobs: usize,
) -> PyResult<(String, String)> {
    let sc = load(path, text, &set)?;
    let jobs = if jobs == 0 { std::thread::available_parallelism().map_or(1, |n| n.get()) } else { jobs };
    let result = on_own_thread(py, move |cancel| {
        let (rows, summary) = tensegrity_testbed::sweep::sweep(&sc, jobs, None, Some(cancel), &|_, _| {})?;
        let fingerprint = tensegrity_testbed::sweep::fingerprint(&sc);
        let csv = tensegrity_testbed::sweep::to_csv(&rows, &|q: &str| sc.is_angle(q), &fingerprint);
        Ok::<_, tensegrity_testbed::sweep::SweepError>((
            csv,
            serde_json::to_string(&summary).expect("a summary serialises"),
        ))
    })?;
    result.map_err(|e| PyValueError::new_err(e.to_string()))
}

/// A Python callable `f(params, inputs, t) -> {name: value}` as the testbed's external model:
/// called with the GIL from the run's thread; its first failure (an exception, a prediction
/// left out, a value that is not a finite float) is kept and raised after the run.
struct PyModel {
    function: Py<PyAny>,
    names: Vec<String>,
    failure: Mutex<Option<PyErr>>,
}

impl PyModel {
    fn call(
        &self,
        py: Python<'_>,
        params: &BTreeMap<String, f64>,
        inputs: &BTreeMap<String, f64>,
        t: Option<f64>,
    ) -> PyResult<BTreeMap<String, f64>> {
        let out: BTreeMap<String, f64> = self.function.call1(py, (params.clone(), inputs.clone(), t))?.extract(py)?;
        for n in &self.names {
            match out.get(n) {
                Some(v) if v.is_finite() => {}
                Some(v) => {
                    return Err(PyValueError::new_err(format!(
                        "the model's prediction '{n}' is {v}, not a finite number"
                    )))
                }
                None => {
                    let got: Vec<&String> = out.keys().collect();
                    return Err(PyValueError::new_err(format!(
                        "the model returned no prediction '{n}' (it returned {got:?})"
                    )));
                }
            }
        }
        Ok(out)
    }
}

impl ExternalModel for PyModel {
    fn predict(
        &self,
        params: &BTreeMap<String, f64>,
        inputs: &BTreeMap<String, f64>,
        time_s: Option<f64>,
    ) -> Result<BTreeMap<String, f64>, String> {
        Python::attach(|py| {
            self.call(py, params, inputs, time_s).map_err(|e| {
                let message = e.to_string();
                let mut failure = self.failure.lock().expect("one lock holder at a time");
                failure.get_or_insert(e);
                message
            })
        })
    }
}

/// (name, quantity, class, tolerance, rms tolerance) as the testbed's predictions.
type PredictionTuple = (String, String, String, f64, Option<f64>);

fn predictions(raw: Vec<PredictionTuple>) -> PyResult<Vec<ExternalPrediction>> {
    raw.into_iter()
        .map(|(name, quantity, class, tolerance, rms_tolerance)| {
            let class = ErrorClass::parse(&class).ok_or_else(|| {
                PyValueError::new_err(format!(
                    "prediction '{name}': class '{class}' (expected one of {:?})",
                    ErrorClass::NAMES
                ))
            })?;
            let positive = |t: f64| t.is_finite() && t > 0.0;
            if !positive(tolerance) || rms_tolerance.is_some_and(|t| !positive(t)) {
                return Err(PyValueError::new_err(format!("prediction '{name}': tolerances are finite and > 0")));
            }
            Ok(ExternalPrediction { name, quantity, class, tolerance, rms_tolerance })
        })
        .collect()
}

/// Runs a scenario; the report as JSON. `table`: also write every tick to this file (`.arrow`
/// or `.csv`). `model` and `predictions`: a Python callable compared as the file's predictions
/// are. The run happens on a thread of its own, without the GIL; Ctrl-C stops it at the next
/// tick and raises KeyboardInterrupt.
#[pyfunction]
#[pyo3(signature = (path, text=None, set=Vec::new(), table=None, model=None, predictions=Vec::new()))]
#[allow(clippy::too_many_arguments)]
fn run_json(
    py: Python<'_>,
    path: &str,
    text: Option<&str>,
    set: Vec<String>,
    table: Option<PathBuf>,
    model: Option<Py<PyAny>>,
    predictions: Vec<PredictionTuple>,
) -> PyResult<String> {
    let sc = load(path, text, &set)?;
    let predictions = self::predictions(predictions)?;
    let names = predictions.iter().map(|p| p.name.clone()).collect();
    let model = model.map(|function| Arc::new(PyModel { function, names, failure: Mutex::new(None) }));
    let external = model.clone().map(|m| External { model: m as Arc<dyn ExternalModel>, predictions });
    let json = on_own_thread(py, move |cancel| {
        let opts = RunOptions { cancel: Some(cancel), table, external, ..Default::default() };
        serde_json::to_string(&run::run(&sc, &opts)).expect("a report serialises")
    })?;
    if let Some(e) = model.and_then(|m| m.failure.lock().expect("the run is over").take()) {
        return Err(e);
    }
    Ok(json)
}

/// A scenario (TOML text) from the node matrix and the connectivity matrices in files (the
/// importer of `tensegrity import matrices`); errors at file, line and column.
#[pyfunction]
fn import_matrices(
    n: PathBuf,
    cb: PathBuf,
    cs: PathBuf,
    bar_mass_kg: f64,
    bar_radius_m: f64,
    string_stiffness_n_per_m: f64,
    string_tension_n: f64,
) -> PyResult<String> {
    use tensegrity_testbed::import::matrices::{import, MatrixOptions};
    let o =
        MatrixOptions { bar_mass_kg, bar_radius_m, string_stiffness_n_per_m, string_tension_n, uniform_tension: false };
    o.validate().map_err(PyValueError::new_err)?;
    let imported = import(&n, &cb, &cs, &o)
        .map_err(|e| TestbedError::new_err((e.file.clone(), e.line, e.col, e.message.clone())))?;
    Ok(imported.toml)
}

/// The MJCF export of a scenario's first structure (`tensegrity export mjcf`): (the XML, what
/// was not exported). `actuators`: "mocap" or "position" (servos of gain `kp`).
#[pyfunction]
#[pyo3(signature = (path, text=None, set=Vec::new(), actuators="mocap", kp=1e6, cable_damping=0.0))]
fn export_mjcf(
    path: &str,
    text: Option<&str>,
    set: Vec<String>,
    actuators: &str,
    kp: f64,
    cable_damping: f64,
) -> PyResult<(String, Vec<String>)> {
    use tensegrity_testbed::export::{mjcf::ActuatorMode, scenario_mjcf, validate_mjcf_options};
    let sc = load(path, text, &set)?;
    validate_mjcf_options(kp, cable_damping).map_err(PyValueError::new_err)?;
    let mode = match actuators {
        "mocap" => ActuatorMode::Mocap,
        "position" => ActuatorMode::Position,
        other => return Err(PyValueError::new_err(format!("actuators '{other}': \"mocap\" or \"position\""))),
    };
    let mjcf = scenario_mjcf(&sc, mode, kp, cable_damping).map_err(PyValueError::new_err)?;
    Ok((mjcf.xml, mjcf.warnings))
}

/// A built-in mechanism by name, its parameters (defaults for those not given, validated) and
/// the remaining values as inputs.
fn mechanism_values(
    name: &str,
    values: BTreeMap<String, f64>,
) -> PyResult<(Box<dyn tensegrity_testbed::mechanisms::Mechanism>, BTreeMap<String, f64>, BTreeMap<String, f64>)> {
    use tensegrity_testbed::mechanisms;
    let m = mechanisms::find_named(name).map_err(PyValueError::new_err)?;
    let (params, inputs): (BTreeMap<_, _>, BTreeMap<_, _>) =
        values.into_iter().partition(|(k, _)| m.params().iter().any(|p| p.symbol == k));
    if let Some((k, v)) = params.iter().chain(&inputs).find(|(_, v)| !v.is_finite()) {
        return Err(PyValueError::new_err(format!("{k} = {v}: values are finite")));
    }
    let params = mechanisms::with_defaults(m.as_ref(), &params);
    m.validate_params(&params).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok((m, params, inputs))
}

/// The analytic model alone (`tensegrity solve`): every solution of `query` as (label, values,
/// stable).
#[pyfunction]
fn solve(
    mechanism: &str,
    query: &str,
    values: BTreeMap<String, f64>,
) -> PyResult<Vec<(String, BTreeMap<String, f64>, Option<bool>)>> {
    let (m, params, inputs) = mechanism_values(mechanism, values)?;
    let q = tensegrity_testbed::mechanisms::query_named(m.as_ref(), query).map_err(PyValueError::new_err)?;
    if let Some(k) = inputs.keys().find(|k| !q.inputs.contains(&k.as_str())) {
        return Err(PyValueError::new_err(format!(
            "'{k}' is neither a parameter of {mechanism} nor an input of '{query}' ({})",
            q.inputs.join(", ")
        )));
    }
    if let Some(i) = q.inputs.iter().find(|i| !inputs.contains_key(**i)) {
        return Err(PyValueError::new_err(format!("query '{query}' needs {i} (inputs: {})", q.inputs.join(", "))));
    }
    let sols = m.solve(query, &params, &inputs).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(sols.into_iter().map(|s| (s.label, s.values, s.stable)).collect())
}

/// Every printed equation of a built-in mechanism's paper checked (`tensegrity findings`):
/// (equation, claim, measured, holds).
#[pyfunction]
fn findings(mechanism: &str, params: BTreeMap<String, f64>) -> PyResult<Vec<(String, String, String, bool)>> {
    let (m, params, inputs) = mechanism_values(mechanism, params)?;
    if let Some(k) = inputs.keys().next() {
        return Err(PyValueError::new_err(format!("'{k}' is not a parameter of {mechanism}")));
    }
    Ok(m.findings(&params)
        .into_iter()
        .map(|f| (f.equation.to_string(), f.claim.to_string(), f.measured, f.holds))
        .collect())
}

#[pymodule]
fn _tensegrity(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(check, m)?)?;
    m.add_function(wrap_pyfunction!(run_json, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_csv, m)?)?;
    m.add_function(wrap_pyfunction!(import_matrices, m)?)?;
    m.add_function(wrap_pyfunction!(export_mjcf, m)?)?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(findings, m)?)?;
    m.add("TestbedError", m.py().get_type::<TestbedError>())?;
    Ok(())
}
