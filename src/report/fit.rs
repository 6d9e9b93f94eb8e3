//! The report of `tensegrity fit`: the fitted parameters with their standard errors and 95 %
//! intervals, the covariance, the residual of each measurement, chi^2, and the combinations
//! of parameters the data cannot identify (`study::fit`), as a table and JSON.

use serde::Serialize;

/// A fit of a scenario's parameters to measured outputs.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct FitReport {
    pub name: String,
    pub file: String,
    /// One per fitted parameter, in the order given.
    pub parameters: Vec<FittedParameter>,
    /// The parameters' covariance (their units squared), (J^T J)^-1 over the identifiable
    /// directions of the weighted Jacobian J; infinite on the rows and columns of the
    /// parameters in an unidentifiable combination.
    pub covariance: Vec<Vec<f64>>,
    /// Whether the covariance was scaled by the reduced chi^2 (chi^2 / (rows - parameters)):
    /// true when no measurement states its sigma (each then weighs 1), false otherwise.
    pub covariance_scaled: bool,
    /// One per measurement, in the data's order.
    pub residuals: Vec<FitResidual>,
    /// Sum of the squared weighted residuals at the optimum.
    pub chi2: f64,
    /// Measurements less fitted parameters.
    pub degrees_of_freedom: usize,
    /// Levenberg-Marquardt iterations taken (each one accepted step).
    pub iterations: usize,
    /// Why the iterations stopped.
    pub stopped: String,
    /// The directions in parameter space the data do not see.
    pub unidentifiable: Vec<Combination>,
    /// The fit's wall time \[s\] (every settle and sensitivity of every step).
    pub wall_s: f64,
}

/// A fitted parameter.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct FittedParameter {
    pub name: String,
    pub initial: f64,
    pub value: f64,
    /// Standard error (infinite when the parameter is in an unidentifiable combination).
    pub sigma: f64,
    /// The 95 % interval, value -+ 1.96 sigma.
    pub low: f64,
    pub high: f64,
}

/// A measurement and the fitted model's value of it.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct FitResidual {
    pub point: usize,
    /// A trajectory row's time since the motion's start \[s\].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_s: Option<f64>,
    pub output: String,
    pub measured: f64,
    pub model: f64,
    pub sigma: f64,
    /// (model - measured) / sigma.
    pub weighted: f64,
}

/// A combination of relative parameter changes the data do not see: sum of
/// weight_j dp_j / |p_j| changes no measured output (to within the ratio of singular values).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Combination {
    /// (parameter, weight) of the right singular vector, its weights above the listing floor.
    pub weights: Vec<(String, f64)>,
    /// Its singular value over the largest.
    pub ratio: f64,
}

impl FitReport {
    /// The report as text: the parameters with their intervals, the unidentifiable
    /// combinations, chi^2 and the residuals.
    pub fn to_table(&self) -> String {
        let mut s = format!("{} ({})\n", self.name, self.file);
        s += &format!(
            "{:<16} {:>14} {:>14} {:>12} {:>30}\n",
            "parameter", "initial", "fitted", "sigma", "95 % interval"
        );
        for p in &self.parameters {
            let interval = format!("[{:.6e}, {:.6e}]", p.low, p.high);
            s += &format!(
                "{:<16} {:>14.6e} {:>14.6e} {:>12.3e} {:>30}\n",
                p.name, p.initial, p.value, p.sigma, interval
            );
        }
        for c in &self.unidentifiable {
            let terms: Vec<String> = c.weights.iter().map(|(n, w)| format!("{w:+.3} d{n}/{n}")).collect();
            s += &format!(
                "unidentifiable: the data do not see {} (singular value {:.1e} of the largest)\n",
                terms.join(" "),
                c.ratio
            );
        }
        let scaled = if self.covariance_scaled { ", covariance scaled by the reduced chi^2 (no sigmas)" } else { "" };
        s += &format!(
            "chi^2 = {:.6e} over {} degrees of freedom{scaled}; {} iterations ({}) in {:.3} s\n",
            self.chi2, self.degrees_of_freedom, self.iterations, self.stopped, self.wall_s
        );
        s += &format!(
            "{:>5} {:>10} {:<20} {:>14} {:>14} {:>10}\n",
            "point", "t [s]", "output", "measured", "model", "weighted"
        );
        for r in &self.residuals {
            // A trajectory row's time since the motion's start; "-" for a settled state's.
            let t = r.time_s.map_or("-".to_string(), |t| format!("{t}"));
            s += &format!(
                "{:>5} {:>10} {:<20} {:>14.6e} {:>14.6e} {:>10.3}\n",
                r.point, t, r.output, r.measured, r.model, r.weighted
            );
        }
        s
    }
}
