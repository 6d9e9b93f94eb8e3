//! Every tick as one row of a CSV table, at full f64 precision: readable by pandas, polars or
//! any spreadsheet without the rerun SDK (whose recordings store positions as f32).
//!
//! Columns, fixed at the first tick: `tick`, `time_s`, `kinetic_energy_j`, the inputs
//! (`input:SYMBOL`), every node's coordinates (`node:NAME.x`, `.y`, `.z`, m), every spring's
//! force and every cable's tension (`spring:NAME.force_n`, `cable:NAME.tension_n`), every
//! actuator's force (`actuator:SYMBOL@JOINT_OR_CABLE.force`, N or N m), and the mechanism's quantities,
//! simulated (`sim:QUANTITY`) and analytic (`analytic:QUANTITY`, empty where the model has no
//! value). Numbers are written in Rust's shortest round-trip form, so reading them back gives
//! the same f64 bit for bit. The file is written to a temporary file (`output::partial_path`) and renamed when the run
//! is over.

use super::{Observer, Tick};
use crate::report::ScenarioReport;
use crate::structure::ActuatorTarget;
use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};

pub struct Table {
    path: PathBuf,
    partial: PathBuf,
    out: std::io::BufWriter<std::fs::File>,
    /// Input, simulated and analytic keys, fixed at the first tick (None before it).
    keys: Option<(Vec<String>, Vec<String>, Vec<String>)>,
    /// The first write error, reported when the run closes.
    error: Option<String>,
}

/// A CSV field: quoted when it holds a comma, a quote or a line break.
fn field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

impl Table {
    /// Starts the table at `path` (its directory is made if needed).
    pub fn start(path: &Path) -> Result<Self, String> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        }
        crate::output::check_replaceable(path)?;
        let partial = crate::output::partial_path(path);
        let file = std::fs::File::create(&partial).map_err(|e| {
            crate::output::discard(&partial);
            format!("cannot write the table {}: {e}", path.display())
        })?;
        Ok(Table { path: path.to_path_buf(), partial, out: std::io::BufWriter::new(file), keys: None, error: None })
    }

    fn header(&self, t: &Tick, keys: &(Vec<String>, Vec<String>, Vec<String>)) -> String {
        let s = t.structure;
        let mut cols: Vec<String> = vec!["tick".into(), "time_s".into(), "kinetic_energy_j".into()];
        cols.extend(keys.0.iter().map(|k| format!("input:{k}")));
        for n in &s.nodes {
            cols.extend(["x", "y", "z"].map(|c| format!("node:{}.{c}", n.name)));
        }
        cols.extend(s.springs.iter().map(|m| format!("spring:{}.force_n", m.name)));
        cols.extend(s.cables.iter().map(|m| format!("cable:{}.tension_n", m.name)));
        // Several actuators may share a symbol (mohr2011's cable pairs): named by what they drive.
        cols.extend(s.actuators.iter().map(|a| {
            let target = match a.target {
                ActuatorTarget::Joint(j) => &s.joints[j].name,
                ActuatorTarget::CableLength(c) => &s.cables[c].name,
            };
            format!("actuator:{}@{target}.force", a.symbol)
        }));
        cols.extend(keys.1.iter().map(|k| format!("sim:{k}")));
        cols.extend(keys.2.iter().map(|k| format!("analytic:{k}")));
        cols.iter().map(|c| field(c)).collect::<Vec<_>>().join(",")
    }

    fn row(t: &Tick, keys: &(Vec<String>, Vec<String>, Vec<String>)) -> String {
        let snap = t.snapshot;
        let mut r = format!("{},{:?},{:?}", snap.tick, snap.time_s, snap.kinetic_energy_j);
        let mut put = |v: Option<f64>| {
            r.push(',');
            if let Some(x) = v {
                let _ = write!(r, "{x:?}");
            }
        };
        for k in &keys.0 {
            put(t.inputs.get(k).copied());
        }
        for p in &snap.nodes {
            for x in p {
                put(Some(*x));
            }
        }
        let f = &snap.forces;
        for x in f.spring_force_n.iter().chain(&f.cable_tension_n).chain(&f.actuator_force) {
            put(Some(*x));
        }
        for k in &keys.1 {
            put(t.simulated.get(k).copied());
        }
        for k in &keys.2 {
            put(t.prediction.expected.get(k).copied());
        }
        r
    }
}

impl Observer for Table {
    fn tick(&mut self, t: &Tick, _notes: &mut Vec<super::Note>) {
        if self.error.is_some() {
            return;
        }
        let mut text = String::new();
        if self.keys.is_none() {
            let keys = (
                t.inputs.keys().cloned().collect(),
                t.simulated.keys().cloned().collect(),
                t.prediction.expected.keys().cloned().collect(),
            );
            text.push_str(&self.header(t, &keys));
            text.push('\n');
            self.keys = Some(keys);
        }
        let keys = self.keys.as_ref().expect("set above");
        text.push_str(&Self::row(t, keys));
        text.push('\n');
        if let Err(e) = self.out.write_all(text.as_bytes()) {
            self.error = Some(format!("cannot write the table {}: {e}", self.partial.display()));
        }
    }

    fn close(&mut self, _tick: u64, _report: &ScenarioReport) -> Result<(), String> {
        let written = match self.error.take() {
            Some(e) => Err(e),
            None => self
                .out
                .flush()
                .and_then(|_| self.out.get_ref().sync_all())
                .map_err(|e| format!("cannot write the table {}: {e}", self.path.display())),
        };
        match written {
            Ok(()) => crate::output::commit(&self.partial, &self.path),
            Err(e) => {
                crate::output::discard(&self.partial);
                Err(e)
            }
        }
    }
}
