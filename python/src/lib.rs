//! The testbed's own API for Python (`tensegrity_testbed._tensegrity`; the package's
//! `__init__.py` wraps it): a scenario checked and run by the same code as the CLI, the report
//! handed over as its JSON. Runs release the GIL and stop at the next tick on Ctrl-C.

use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;
use tensegrity_testbed::run::{self, RunOptions};
use tensegrity_testbed::scenario::{self, Override, Scenario, ScenarioError};

create_exception!(_tensegrity, TestbedError, PyException, "A scenario the testbed refuses (args: file, line, col, message).");

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

/// Runs a scenario; the report as JSON. `table`: also write every tick to this file (`.arrow`
/// or `.csv`). The run happens on a thread of its own, without the GIL; Ctrl-C stops it at the
/// next tick and raises KeyboardInterrupt.
#[pyfunction]
#[pyo3(signature = (path, text=None, set=Vec::new(), table=None))]
fn run_json(py: Python<'_>, path: &str, text: Option<&str>, set: Vec<String>, table: Option<PathBuf>) -> PyResult<String> {
    let sc = load(path, text, &set)?;
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&cancel);
    let worker = std::thread::spawn(move || {
        let opts = RunOptions { cancel: Some(&flag), table, ..Default::default() };
        serde_json::to_string(&run::run(&sc, &opts)).expect("a report serialises")
    });
    while !worker.is_finished() {
        py.detach(|| std::thread::sleep(Duration::from_secs_f64(SIGNAL_POLL_S)));
        if let Err(e) = py.check_signals() {
            cancel.store(true, Ordering::SeqCst);
            let _ = py.detach(|| worker.join());
            return Err(e);
        }
    }
    py.detach(|| worker.join()).map_err(|_| PyException::new_err("the run panicked"))
}

#[pymodule]
fn _tensegrity(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(check, m)?)?;
    m.add_function(wrap_pyfunction!(run_json, m)?)?;
    m.add("TestbedError", m.py().get_type::<TestbedError>())?;
    Ok(())
}
