//! The testbed's own API for Python (`tensegrity_testbed._tensegrity`; the package's
//! `__init__.py` wraps it): a scenario checked and run by the same code as the CLI, the report
//! handed over as its JSON, the per-tick table as Arrow record batches in memory
//! (`ArrowTable`, the Arrow PyCapsule interface). Runs release the GIL and stop at the next
//! tick on Ctrl-C.

use arrow_array::ffi_stream::FFI_ArrowArrayStream;
use arrow_array::{RecordBatch, RecordBatchIterator};
use arrow_schema::ffi::FFI_ArrowSchema;
use arrow_schema::{ArrowError, SchemaRef};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyCapsule;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use tensegrity_testbed::file_model::spec::ErrorClass;
use tensegrity_testbed::mechanisms::Values;
use tensegrity_testbed::observers::external::{External, ExternalError, ExternalModel, ExternalPrediction};
use tensegrity_testbed::observers::table::{MemoryTable, TableTarget};
use tensegrity_testbed::run::stoppable::Stoppable;
use tensegrity_testbed::run::{self, RunOptions};
use tensegrity_testbed::scenario::{self, Override, Scenario, ScenarioError};
use tensegrity_testbed::study;

create_exception!(
    _tensegrity,
    TestbedError,
    PyException,
    "A scenario the testbed refuses (args: file, line, col, message)."
);

fn scenario_error(e: ScenarioError) -> PyErr {
    TestbedError::new_err((e.file.clone(), e.line, e.col, e.message.clone()))
}

/// The scenario from a path (`text` None) or from TOML text named `path`, with `NAME=VALUE`
/// overrides.
fn load(path: &str, text: Option<&str>, set: &[String]) -> PyResult<Scenario> {
    if text.is_none() && path == scenario::STDIN {
        // The interpreter's own standard input: reading it would block the caller.
        return Err(PyValueError::new_err(
            "'-' is the command line's standard input: give a file's path, or the TOML as text=",
        ));
    }
    let overrides: Vec<Override> = set
        .iter()
        .map(|s| Override::parse(s).map_err(|e| PyValueError::new_err(e.to_string())))
        .collect::<PyResult<_>>()?;
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

/// The Python thread running a model callable now (its `_thread.get_ident()`), 0 for none:
/// where Ctrl-C sends its KeyboardInterrupt when a callable keeps the run from its next tick.
static CALLABLE_THREAD: AtomicU64 = AtomicU64::new(0);

/// Polls ([`tensegrity_testbed::run::stoppable::POLL_S`] each) that a run is waited for after
/// Ctrl-C before KeyboardInterrupt is raised without it (1 s): a callable blocked in C (a
/// sleep, a read) is then left to return on its own, and the run ends at its next tick.
const STOP_POLLS: usize = 20;

/// Raises KeyboardInterrupt in the thread of a model callable that is running, if one is: a
/// loop in Python stops at its next bytecode, not at the run's next tick.
fn interrupt_callable() {
    let thread = CALLABLE_THREAD.load(Ordering::SeqCst);
    if thread != 0 {
        // SAFETY: called with the GIL held (from `on_own_thread`, between polls); the thread
        // id came from `_thread.get_ident()` in that thread, and an id that has since ended
        // is ignored by CPython (0 threads modified).
        unsafe {
            pyo3::ffi::PyThreadState_SetAsyncExc(thread as std::os::raw::c_long, pyo3::ffi::PyExc_KeyboardInterrupt);
        }
    }
}

/// Runs `work` on a thread of its own (`stoppable`) and waits for it without the GIL, looking
/// for Ctrl-C at every poll: on one it raises the flag `work` watches (the run stops at its
/// next tick) and a KeyboardInterrupt in a running model callable, waits for the run at most
/// [`STOP_POLLS`] polls, and raises KeyboardInterrupt.
fn on_own_thread<T: Send + 'static>(
    py: Python<'_>,
    work: impl FnOnce(&AtomicBool) -> T + Send + 'static,
) -> PyResult<T> {
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&cancel);
    let worker = Stoppable::spawn(None, move || work(&flag))
        .map_err(|e| PyException::new_err(format!("cannot start the run's thread: {e}")))?;
    loop {
        match py.detach(|| worker.poll()) {
            Ok(Some(value)) => {
                py.detach(move || worker.join());
                return Ok(value);
            }
            Err(_) => return Err(PyException::new_err("the run panicked")),
            Ok(None) => {}
        }
        if let Err(e) = py.check_signals() {
            cancel.store(true, Ordering::SeqCst);
            interrupt_callable();
            let stopped = py.detach(|| (0..STOP_POLLS).any(|_| !matches!(worker.poll(), Ok(None))));
            if stopped {
                py.detach(move || worker.join());
            }
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
        let (rows, summary) = tensegrity_testbed::study::sweep::sweep(&sc, jobs, None, Some(cancel), &|_, _| {})?;
        let fingerprint = tensegrity_testbed::study::sweep::fingerprint(&sc);
        let csv = tensegrity_testbed::study::sweep::to_csv(&rows, &|q: &str| sc.is_angle(q), &fingerprint);
        Ok::<_, tensegrity_testbed::study::sweep::SweepError>((
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
        // `_thread`, not `threading`: imported first from this thread, `threading` would take it
        // for the main thread and hold the interpreter's exit for it (measured: a hang).
        let thread: u64 = py.import("_thread")?.call_method0("get_ident")?.extract()?;
        CALLABLE_THREAD.store(thread, Ordering::SeqCst);
        let called = self.function.call1(py, (params.clone(), inputs.clone(), t));
        CALLABLE_THREAD.store(0, Ordering::SeqCst);
        let out: BTreeMap<String, f64> = called?.extract(py)?;
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
    ) -> Result<BTreeMap<String, f64>, ExternalError> {
        Python::attach(|py| {
            self.call(py, params, inputs, time_s).map_err(|e| {
                let raised = ExternalError::Raised(e.to_string());
                let mut failure = self.failure.lock().expect("one lock holder at a time");
                failure.get_or_insert(e);
                raised
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

/// Every tick of a run as Arrow record batches in memory (the columns of `tensegrity run
/// --table FILE.arrow`), exported through the Arrow PyCapsule interface: `pyarrow.table(t)`
/// (or any consumer of `__arrow_c_stream__`) takes the batches without copying them. Can be
/// read any number of times.
#[pyclass(frozen, module = "tensegrity_testbed._tensegrity")]
struct ArrowTable {
    schema: SchemaRef,
    batches: Vec<RecordBatch>,
}

#[pymethods]
impl ArrowTable {
    /// The table as an Arrow C stream (a PyCapsule named "arrow_array_stream"); the
    /// `requested_schema` is not applied (the table has one schema: UInt64 `tick`, Float64
    /// else).
    #[pyo3(signature = (requested_schema=None))]
    fn __arrow_c_stream__<'py>(
        &self,
        py: Python<'py>,
        requested_schema: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyCapsule>> {
        let _ = requested_schema;
        let batches: Vec<Result<RecordBatch, ArrowError>> = self.batches.iter().cloned().map(Ok).collect();
        let reader = RecordBatchIterator::new(batches, self.schema.clone());
        PyCapsule::new(py, FFI_ArrowArrayStream::new(Box::new(reader)), Some(c"arrow_array_stream".to_owned()))
    }

    /// The table's schema as an Arrow C schema (a PyCapsule named "arrow_schema").
    fn __arrow_c_schema__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyCapsule>> {
        let schema =
            FFI_ArrowSchema::try_from(self.schema.as_ref()).map_err(|e| PyValueError::new_err(e.to_string()))?;
        PyCapsule::new(py, schema, Some(c"arrow_schema".to_owned()))
    }

    /// The number of rows (ticks).
    #[getter]
    fn num_rows(&self) -> usize {
        self.batches.iter().map(RecordBatch::num_rows).sum()
    }

    /// The column names: `tick`, then those of `tensegrity run --table`.
    #[getter]
    fn column_names(&self) -> Vec<String> {
        self.schema.fields().iter().map(|f| f.name().clone()).collect()
    }

    fn __len__(&self) -> usize {
        self.num_rows()
    }

    fn __repr__(&self) -> String {
        format!("<ArrowTable: {} rows, {} columns>", self.num_rows(), self.schema.fields().len())
    }
}

/// Runs a scenario: the report as JSON and, with `table`, every tick as an [`ArrowTable`]
/// (None when no tick ran). `model` and `predictions`: a Python callable compared as the file's
/// predictions are. The run happens on a thread of its own, without the GIL; Ctrl-C stops it at
/// the next tick and raises KeyboardInterrupt.
#[pyfunction]
#[pyo3(signature = (path, text=None, set=Vec::new(), table=false, model=None, predictions=Vec::new()))]
// The Python function's keyword arguments, one parameter each (and the GIL token).
#[allow(clippy::too_many_arguments)]
fn run_json(
    py: Python<'_>,
    path: &str,
    text: Option<&str>,
    set: Vec<String>,
    table: bool,
    model: Option<Py<PyAny>>,
    predictions: Vec<PredictionTuple>,
) -> PyResult<(String, Option<ArrowTable>)> {
    let sc = load(path, text, &set)?;
    let predictions = self::predictions(predictions)?;
    let known = sc.quantity_names();
    if let Some(p) = predictions.iter().find(|p| !known.contains(&p.quantity)) {
        return Err(PyValueError::new_err(format!(
            "prediction '{}': the scenario measures no quantity '{}' (it measures {})",
            p.name,
            p.quantity,
            known.join(", ")
        )));
    }
    let names = predictions.iter().map(|p| p.name.clone()).collect();
    let model = model.map(|function| Arc::new(PyModel { function, names, failure: Mutex::new(None) }));
    let external = model.clone().map(|m| External { model: m as Arc<dyn ExternalModel>, predictions });
    let kept = table.then(MemoryTable::default);
    let target = kept.clone().map(TableTarget::Memory);
    let json = on_own_thread(py, move |cancel| {
        let opts = RunOptions { cancel: Some(cancel), table: target, external, ..Default::default() };
        serde_json::to_string(&run::run(&sc, &opts)).expect("a report serialises")
    })?;
    if let Some(e) = model.and_then(|m| m.failure.lock().expect("the run is over").take()) {
        return Err(e);
    }
    let table = kept.and_then(|k| k.take()).map(|(schema, batches)| ArrowTable { schema, batches });
    Ok((json, table))
}

/// An import's error as a ValueError: `FILE[ROW]: message` for the arrays of `from_matrices`
/// (`N`, `Cb`, `Cs`, rows from 0), `FILE: message` for the whole of one, the message alone
/// for the member properties.
fn array_error(e: tensegrity_testbed::import::ImportError) -> PyErr {
    match e.line {
        0 if e.file.is_empty() => PyValueError::new_err(e.message),
        0 => PyValueError::new_err(format!("{}: {}", e.file, e.message)),
        line => PyValueError::new_err(format!("{}[{}]: {}", e.file, line - 1, e.message)),
    }
}

/// A scenario (TOML text) named `name` from N (3 rows), C_b and C_s as rows of numbers and one
/// property per member (`import::matrices::from_arrays`): ValueError on what is wrong.
#[pyfunction]
#[pyo3(signature = (name, n, cb, cs, bar_mass_kg, bar_radius_m, string_stiffness_n_per_m, string_tension_n, string_rest_length_m, tension_only, pins, quantities, clusters=Vec::new()))]
// The Python function's keyword arguments, one parameter each: the arrays and one property per
// member, as `tensegrity import matrices` takes them.
#[allow(clippy::too_many_arguments)]
fn structure_from_arrays(
    name: &str,
    n: Vec<Vec<f64>>,
    cb: Vec<Vec<f64>>,
    cs: Vec<Vec<f64>>,
    bar_mass_kg: Vec<f64>,
    bar_radius_m: Vec<f64>,
    string_stiffness_n_per_m: Vec<f64>,
    string_tension_n: Option<Vec<f64>>,
    string_rest_length_m: Option<Vec<f64>>,
    tension_only: Vec<bool>,
    pins: Vec<(String, Option<[f64; 3]>)>,
    quantities: Vec<(String, String)>,
    clusters: Vec<Vec<f64>>,
) -> PyResult<String> {
    use tensegrity_testbed::import::matrices::{from_arrays, DrawnTension, MemberProperties, StringRest};
    use tensegrity_testbed::import::DEFAULT_LEAST_TENSION_N;
    // Neither given: the drawn structure's self-stress, its least string tension the CLI's
    // default (as `tensegrity import matrices` chooses).
    let (string_rest, prestress) = match (string_tension_n, string_rest_length_m) {
        (Some(_), Some(_)) => {
            return Err(PyValueError::new_err("give string_tension_n or string_rest_length_m, not both"))
        }
        (Some(t), None) => (StringRest::TensionN(t), DrawnTension::AsGiven),
        (None, Some(l)) => (StringRest::LengthM(l), DrawnTension::AsGiven),
        (None, None) => (
            StringRest::TensionN(vec![DEFAULT_LEAST_TENSION_N; cs.len()]),
            DrawnTension::SelfStress { least_n: DEFAULT_LEAST_TENSION_N },
        ),
    };
    let p = MemberProperties {
        bar_mass_kg,
        bar_radius_m,
        string_stiffness_n_per_m,
        string_rest,
        tension_only,
        pins,
        quantities,
        prestress,
        clusters,
    };
    Ok(from_arrays(name, &n, &cb, &cs, &p).map_err(array_error)?.toml)
}

/// A scenario (TOML text) from an NTRT YAML model (`tensegrity import ntrt`), read from `path`
/// or given as `text` named `path` (substructures relative to its directory): (the TOML, what
/// was skipped). Errors at file, line and column.
#[pyfunction]
#[pyo3(signature = (path, text=None, keep_axes=false))]
fn import_ntrt(path: PathBuf, text: Option<&str>, keep_axes: bool) -> PyResult<(String, Vec<String>)> {
    use tensegrity_testbed::import::ntrt::{import, import_text, Axes};
    let axes = if keep_axes { Axes::Keep } else { Axes::ZUp };
    let imported = match text {
        Some(t) => import_text(&path, t, axes),
        None => import(&path, axes),
    }
    .map_err(|e| TestbedError::new_err((e.file.clone(), e.line, e.col, e.message.clone())))?;
    Ok((imported.toml, imported.skipped))
}

/// Writes a scenario's text to `path` as the CLI writes its outputs (`output`): never over one
/// of `inputs` or over anything but a regular file, through a temporary file and a rename.
#[pyfunction]
fn write_scenario(path: PathBuf, text: &str, inputs: Vec<PathBuf>) -> PyResult<()> {
    use tensegrity_testbed::output;
    output::check_outputs(&inputs, &[("the scenario".into(), path.clone())])
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    output::write_atomic(&path, text.as_bytes()).map_err(|e| pyo3::exceptions::PyOSError::new_err(e.to_string()))
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
    validate_mjcf_options(kp, cable_damping).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let mode = match actuators {
        "mocap" => ActuatorMode::Mocap,
        "position" => ActuatorMode::Position,
        other => return Err(PyValueError::new_err(format!("actuators '{other}': \"mocap\" or \"position\""))),
    };
    let mjcf = scenario_mjcf(&sc, mode, kp, cable_damping).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok((mjcf.xml, mjcf.warnings))
}

/// A built-in mechanism, its parameters and its inputs.
type MechanismValues = (Box<dyn tensegrity_testbed::mechanisms::Mechanism>, Values, Values);

/// A built-in mechanism by name, its parameters (defaults for those not given, validated) and
/// the remaining values as inputs.
fn mechanism_values(name: &str, values: Values) -> PyResult<MechanismValues> {
    use tensegrity_testbed::mechanisms;
    let m = mechanisms::find_named(name).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let (params, inputs): (BTreeMap<_, _>, BTreeMap<_, _>) =
        values.into_iter().partition(|(k, _)| m.params().iter().any(|p| p.symbol == k));
    if let Some((k, v)) = params.iter().chain(&inputs).find(|(_, v)| !v.is_finite()) {
        return Err(PyValueError::new_err(format!("{k} = {v}: values are finite")));
    }
    let params = mechanisms::with_defaults(m.as_ref(), &params);
    m.validate_params(&params).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok((m, params, inputs))
}

/// One solution of the analytic model: its label, its values and whether it is stable (None
/// where the model does not say).
type Solution = (String, Values, Option<bool>);

/// The analytic model alone (`tensegrity solve`): every solution of `query` as (label, values,
/// stable).
#[pyfunction]
fn solve(mechanism: &str, query: &str, values: Values) -> PyResult<Vec<Solution>> {
    let (m, params, inputs) = mechanism_values(mechanism, values)?;
    let q = tensegrity_testbed::mechanisms::query_named(m.as_ref(), query)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
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

/// The modal analysis of `tensegrity modes --json`: the same report, as its JSON text, at the
/// scenario's first point settled as `run` settles it. Ctrl-C stops the settle.
#[pyfunction]
#[pyo3(signature = (path, text=None, set=Vec::new(), count=tensegrity_testbed::structure::SPARSE_MODAL_COUNT))]
fn modes_json(py: Python<'_>, path: &str, text: Option<&str>, set: Vec<String>, count: usize) -> PyResult<String> {
    let max = tensegrity_testbed::structure::MAX_SPARSE_MODAL_COUNT;
    if !(1..=max).contains(&count) {
        return Err(PyValueError::new_err(format!(
            "count must be from 1 to {max} (the lowest non-rigid modes the sparse solver computes), got {count}"
        )));
    }
    let sc = load(path, text, &set)?;
    let file = path.to_string();
    let result =
        on_own_thread(py, move |cancel| run::modes(&sc, &file, count, Some(cancel)).map(|(report, ..)| report))?;
    let report = result.map_err(|e| match e {
        run::ModesRunError::Refused(_) => PyValueError::new_err(format!("{path}: {e}")),
        _ => PyException::new_err(format!("{path}: {e}")),
    })?;
    Ok(serde_json::to_string_pretty(&report).expect("a report serialises"))
}

/// The equilibrium matrix's analysis of `tensegrity equilibrium --json`: the same report, as
/// its JSON text, at the scenario's first point settled as `run` settles it. Ctrl-C stops the
/// settle.
#[pyfunction]
#[pyo3(signature = (path, text=None, set=Vec::new()))]
fn equilibrium_json(py: Python<'_>, path: &str, text: Option<&str>, set: Vec<String>) -> PyResult<String> {
    let sc = load(path, text, &set)?;
    let file = path.to_string();
    let result = on_own_thread(py, move |cancel| run::equilibrium(&sc, &file, Some(cancel)).map(|(report, _)| report))?;
    let report = result.map_err(|e| match e {
        run::EquilibriumRunError::Refused(_) => PyValueError::new_err(format!("{path}: {e}")),
        run::EquilibriumRunError::Run(_) => PyException::new_err(format!("{path}: {e}")),
    })?;
    Ok(serde_json::to_string_pretty(&report).expect("a report serialises"))
}

/// The sensitivities of `tensegrity sensitivity --json` (with `--check` when `check`, at
/// `--point point`): the same report, as its JSON text, at that point settled as `run`
/// settles it.
/// Ctrl-C stops the settles.
#[pyfunction]
#[pyo3(signature = (path, text=None, set=Vec::new(), check=false, point=0, params=Vec::new()))]
fn sensitivity_json(
    py: Python<'_>,
    path: &str,
    text: Option<&str>,
    set: Vec<String>,
    check: bool,
    point: usize,
    params: Vec<String>,
) -> PyResult<String> {
    let sc = load(path, text, &set)?;
    if let Some(name) = params.iter().find(|p| !sc.params.contains_key(*p)) {
        return Err(PyValueError::new_err(format!("params: '{name}' is not a parameter of the scenario")));
    }
    let file = path.to_string();
    let result = on_own_thread(py, move |cancel| {
        let only = (!params.is_empty()).then_some(params.as_slice());
        study::sensitivity::sensitivity_to(&sc, &file, (point, only), check, Some(cancel))
    })?;
    let report = result.map_err(|e| match e {
        study::SensitivityRunError::Refused(_) | study::SensitivityRunError::NoPoint(_) => {
            PyValueError::new_err(format!("{path}: {e}"))
        }
        _ => PyException::new_err(format!("{path}: {e}")),
    })?;
    Ok(serde_json::to_string_pretty(&report).expect("a report serialises"))
}

/// The certificate of `tensegrity certify --json` (at `--point point`): the same report, as
/// its JSON text, at that point settled as `run` settles it. Ctrl-C stops the settle.
#[pyfunction]
#[pyo3(signature = (path, text=None, set=Vec::new(), point=0, stiffness=false))]
fn certify_json(
    py: Python<'_>,
    path: &str,
    text: Option<&str>,
    set: Vec<String>,
    point: usize,
    stiffness: bool,
) -> PyResult<String> {
    let sc = load(path, text, &set)?;
    let file = path.to_string();
    let result =
        on_own_thread(py, move |cancel| study::certify::certify_with(&sc, &file, (point, stiffness), Some(cancel)))?;
    let report = result.map_err(|e| match e {
        study::certify::CertifyRunError::Run(_) => PyException::new_err(format!("{path}: {e}")),
        _ => PyValueError::new_err(format!("{path}: {e}")),
    })?;
    Ok(serde_json::to_string_pretty(&report).expect("a report serialises"))
}

/// The attribution of `tensegrity attribute --json` (`study::attribution`, the CLI's own
/// function): the file's checks under the ideal structure, each `[[fidelity]]` relaxation alone
/// and all of them together, as its JSON text. Ctrl-C stops the runs.
#[pyfunction]
#[pyo3(signature = (path, text=None, set=Vec::new()))]
fn attribute_json(py: Python<'_>, path: &str, text: Option<&str>, set: Vec<String>) -> PyResult<String> {
    let sc = load(path, text, &set)?;
    let result = on_own_thread(py, move |cancel| study::attribution::attribute(&sc, Some(cancel)))?;
    let report = result.map_err(|e| match e {
        study::attribution::AttributionError::NoRelaxation | study::attribution::AttributionError::Level { .. } => {
            PyValueError::new_err(format!("{path}: {e}"))
        }
        study::attribution::AttributionError::Cancelled => PyException::new_err(format!("{path}: {e}")),
    })?;
    Ok(serde_json::to_string_pretty(&report).expect("a report serialises"))
}

/// A fitted parameter from Python: (name, low bound, high bound).
type FitBounds = (String, Option<f64>, Option<f64>);
/// A measured row from Python: (where it is, for errors; point; output; value; sigma).
type MeasuredRow = (String, i64, String, f64, Option<f64>, Option<f64>);

/// The fit of `tensegrity fit --json` (`study::fit`, the CLI's own function): the scenario at
/// `path` (or TOML `text` named `path`) with `set`, the parameters `params` within their
/// bounds, the measurements from the CSV at `data_path` (read as `--data` reads it) or as
/// `rows`; the same report as its JSON text. Ctrl-C stops the settles.
#[pyfunction]
#[pyo3(signature = (path, text=None, set=Vec::new(), params=Vec::new(), data_path=None, rows=Vec::new()))]
fn fit_json(
    py: Python<'_>,
    path: &str,
    text: Option<&str>,
    set: Vec<String>,
    params: Vec<FitBounds>,
    data_path: Option<PathBuf>,
    rows: Vec<MeasuredRow>,
) -> PyResult<String> {
    use tensegrity_testbed::study::{FitError, FitParameter, FitProblem, Measurement};
    // The scenario's errors located as every other function's (ScenarioError).
    load(path, text, &set)?;
    let source = match text {
        Some(t) => t.to_string(),
        None => tensegrity_testbed::input::read_text(Path::new(path), scenario::MAX_SCENARIO_BYTES, false)
            .map_err(|e| PyValueError::new_err(format!("{path}: the scenario file: {e}")))?,
    };
    let overrides: Vec<Override> = set
        .iter()
        .map(|s| Override::parse(s).map_err(|e| PyValueError::new_err(e.to_string())))
        .collect::<PyResult<_>>()?;
    let parameters = params.into_iter().map(|(name, low, high)| FitParameter { name, low, high }).collect();
    if rows.len() > study::MAX_DATA_ROWS {
        return Err(PyValueError::new_err(format!("data: {}", study::too_many_rows())));
    }
    let measurements = match data_path {
        Some(d) => study::read_measurements("data", &d, false).map_err(|e| PyValueError::new_err(e.to_string()))?,
        None => rows
            .into_iter()
            .map(|(at, point, output, value, sigma, time_s)| {
                let point = usize::try_from(point).map_err(|_| {
                    PyValueError::new_err(format!("{at}: point {point} is not a point number (from 0)"))
                })?;
                Ok(Measurement { at, point, output, value, sigma, time_s })
            })
            .collect::<PyResult<_>>()?,
    };
    let problem = FitProblem { file: PathBuf::from(path), source, overrides, parameters, measurements };
    let result = on_own_thread(py, move |cancel| study::fit(&problem, Some(cancel)))?;
    let report = result.map_err(|e| match e {
        FitError::Scenario(e) => scenario_error(e),
        e if e.is_bad_input() => PyValueError::new_err(e.to_string()),
        e => PyException::new_err(format!("{path}: {e}")),
    })?;
    Ok(serde_json::to_string_pretty(&report).expect("a report serialises"))
}

/// Scenario sections given as a JSON object (`{"motion": {...}, "energy": {...}}`) as TOML
/// text; a value TOML cannot hold (null, a mixed array) is a ValueError naming it.
#[pyfunction]
fn sections_toml(json: &str) -> PyResult<String> {
    let value: serde_json::Value =
        serde_json::from_str(json).map_err(|e| PyValueError::new_err(format!("sections: {e}")))?;
    let table = toml::Value::try_from(value).map_err(|e| PyValueError::new_err(format!("sections: {e}")))?;
    toml::to_string(&table).map_err(|e| PyValueError::new_err(format!("sections: {e}")))
}

#[pymodule]
fn _tensegrity(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("MAX_DATA_ROWS", study::MAX_DATA_ROWS)?;
    m.add_function(wrap_pyfunction!(check, m)?)?;
    m.add_function(wrap_pyfunction!(run_json, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_csv, m)?)?;
    m.add_function(wrap_pyfunction!(structure_from_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(import_ntrt, m)?)?;
    m.add_function(wrap_pyfunction!(write_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(export_mjcf, m)?)?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(findings, m)?)?;
    m.add_function(wrap_pyfunction!(modes_json, m)?)?;
    m.add_function(wrap_pyfunction!(equilibrium_json, m)?)?;
    m.add_function(wrap_pyfunction!(sensitivity_json, m)?)?;
    m.add_function(wrap_pyfunction!(attribute_json, m)?)?;
    m.add_function(wrap_pyfunction!(certify_json, m)?)?;
    m.add_function(wrap_pyfunction!(fit_json, m)?)?;
    m.add_function(wrap_pyfunction!(sections_toml, m)?)?;
    m.add_class::<ArrowTable>()?;
    m.add("TestbedError", m.py().get_type::<TestbedError>())?;
    Ok(())
}
