//! The report of `tensegrity sensitivity`: how a settled state's outputs (node positions,
//! joint coordinates, member forces, the mechanism's and the file's quantities, the natural
//! frequencies) move with each parameter (`study::sensitivity`), as a table, JSON and CSV.

use serde::Serialize;

/// Below this elasticity |dy/dp| |p| / |y| a check's error is taken relative to this
/// fraction of |y| / |p| (the output's own scale over the parameter's) rather than to the
/// derivative itself: a difference of settles at steps of 1e-3 of the parameter resolves no
/// less (a settle's own error, about 1e-13 of |y|, over the step).
pub const CHECK_FLOOR_ELASTICITY: f64 = 1e-3;

/// The sensitivities of one scenario's settled state.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct SensitivityReport {
    pub name: String,
    pub file: String,
    /// The settle point analysed (from 0, as a run numbers its points) and its inputs.
    pub point: usize,
    pub inputs: crate::mechanisms::Values,
    /// Whether the settle criteria were met before the analysis.
    pub settled: bool,
    pub settle_steps: u64,
    /// The equilibrium's free coordinates, by name (`BODY.x` .. `BODY.rz`, or joints).
    pub coordinates: Vec<String>,
    /// Every output at the settled state, in the order of each parameter's derivatives.
    pub outputs: Vec<OutputValue>,
    /// One per parameter, in name order: the file's own (or those asked for by name).
    pub parameters: Vec<ParameterSensitivity>,
    /// The derived parameters (expressions of others, which follow them) left out of
    /// `parameters`: each moves with the parameters it is defined from. Asked for by name,
    /// one is differentiated as an input of its own.
    pub derived: Vec<String>,
    /// Wall time of the sensitivities after the settle \[s\].
    pub wall_s: f64,
    /// Wall time of the check by differences of settles (`--check`) \[s\].
    pub check_wall_s: Option<f64>,
}

/// An output and its value at the settled state.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct OutputValue {
    pub name: String,
    pub value: f64,
    /// It moves with a rigid-body mode of the structure (a node's coordinates where the
    /// structure can turn freely): the equilibrium does not fix it, its derivative is the
    /// minimum-norm solution's, and the check leaves it out.
    pub free: bool,
}

/// Every output's derivative with respect to one parameter.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ParameterSensitivity {
    pub name: String,
    pub value: f64,
    /// The parameter's finite-difference step (h; the samples are at +-h and +-2h).
    pub step: f64,
    /// d(coordinate)/d(parameter), one per coordinate of the report.
    pub coordinates: Vec<f64>,
    /// d(output)/d(parameter), one per output of the report (empty with `error`).
    pub derivatives: Vec<f64>,
    /// Each derivative's error estimate (the five-point stencil against the three-point one
    /// over the same samples: an upper bound where truncation rules), one per output.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub estimates: Vec<f64>,
    /// The same by differences of settles (`--check`), one per output.
    pub check: Option<Vec<f64>>,
    /// The largest error of `derivatives` against `check`, relative (see
    /// [`CHECK_FLOOR_ELASTICITY`]).
    pub max_check_error: Option<f64>,
    /// Why this parameter has no derivatives (its structure could not be built at a step).
    pub error: Option<String>,
    /// Why this parameter is a switch here, not differentiated (no derivatives, no error): a
    /// pattern's count, or a value where the model changes (a member's law, a joint's kind,
    /// the structure's counts) between it and its steps.
    pub switch: Option<String>,
    /// Nothing in the file reads this parameter (`Scenario::unread_params`): it gets no steps
    /// and every derivative is 0, which is what its steps would give.
    pub unused: bool,
}

/// A derivative below this (in the output's unit per the parameter's) is zero to the check:
/// a settle's own error over the step.
pub const CHECK_FLOOR_ABSOLUTE: f64 = 1e-6;

/// The error of a derivative `d` against its check `c`, relative to |c|, or to
/// [`CHECK_FLOOR_ELASTICITY`] x |y| / max(|p|, h) + [`CHECK_FLOOR_ABSOLUTE`] where that is
/// larger (an output that barely moves; `h` the parameter's step).
pub fn check_error(d: f64, c: f64, y: f64, p: f64, h: f64) -> f64 {
    let floor = CHECK_FLOOR_ELASTICITY * (y / p.abs().max(h)).abs() + CHECK_FLOOR_ABSOLUTE;
    (d - c).abs() / c.abs().max(floor)
}

impl SensitivityReport {
    /// The table: a header, then per parameter one row per output.
    pub fn to_table(&self) -> String {
        let mut out = format!(
            "== {} [{}] point {}: {} coordinate(s) ({}), {} output(s), {} parameter(s){}\n      {:<28} {:>20} {:>20} {:>10}{}\n",
            self.name,
            self.file,
            self.point,
            self.coordinates.len(),
            self.coordinates.join(", "),
            self.outputs.len(),
            self.parameters.len(),
            if self.settled { String::new() } else { ", NOT SETTLED".into() },
            "output",
            "value",
            "d/dp",
            "estimate",
            if self.check_wall_s.is_some() { format!(" {:>20}", "settles' d/dp") } else { String::new() }
        );
        if !self.derived.is_empty() {
            out.push_str(&format!(
                "   derived, not differentiated (each follows the parameters it is defined from; --param NAME asks for one): {}\n",
                self.derived.join(", ")
            ));
        }
        for p in &self.parameters {
            out.push_str(&format!("   d/d {} (= {}, step {:.3e})", p.name, p.value, p.step));
            if let Some(e) = &p.error {
                out.push_str(&format!(": {e}\n"));
                continue;
            }
            if let Some(why) = &p.switch {
                out.push_str(&format!(": switch, not differentiated ({why})\n"));
                continue;
            }
            if p.unused {
                out.push_str(": unused, not differentiated (nothing in the file reads it: every derivative 0)\n");
                continue;
            }
            match p.max_check_error {
                Some(e) => out.push_str(&format!(", against settles: largest error {e:.2e}\n")),
                None => out.push('\n'),
            }
            let mut zero = 0;
            for (i, (o, d)) in self.outputs.iter().zip(&p.derivatives).enumerate() {
                let c = p.check.as_ref().map(|c| c[i]);
                if *d == 0.0 && c.is_none_or(|c| c == 0.0) {
                    zero += 1;
                    continue;
                }
                let check = c.map_or(String::new(), |c| format!(" {c:>20.12e}"));
                let free = if o.free { "  (free)" } else { "" };
                let estimate = p.estimates.get(i).map_or(String::new(), |e| format!(" +- {e:.1e}"));
                out.push_str(&format!(
                    "      {:<28} {:>20.12e} {:>20.12e}{estimate}{check}{free}\n",
                    o.name, o.value, d
                ));
            }
            if zero > 0 {
                out.push_str(&format!("      ({zero} output(s) with a zero derivative not listed)\n"));
            }
        }
        out
    }

    /// The CSV: one row per parameter and output.
    pub fn to_csv(&self) -> String {
        let mut out =
            String::from("parameter,parameter_value,output,output_value,free,derivative,estimate,check,check_error\n");
        for p in &self.parameters {
            for (i, (o, d)) in self.outputs.iter().zip(&p.derivatives).enumerate() {
                let (c, e) = match &p.check {
                    Some(c) => {
                        (format!("{:e}", c[i]), format!("{:e}", check_error(*d, c[i], o.value, p.value, p.step)))
                    }
                    None => (String::new(), String::new()),
                };
                let estimate = p.estimates.get(i).map_or(String::new(), |x| format!("{x:e}"));
                out.push_str(&format!(
                    "{},{:e},{},{:e},{},{:e},{estimate},{c},{e}\n",
                    p.name, p.value, o.name, o.value, o.free, d
                ));
            }
        }
        out
    }
}
