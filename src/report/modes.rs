//! The report of `tensegrity modes`: a structure's natural frequencies and mode shapes at its
//! settled state (`sim::modes`), as a table and as JSON.

use serde::Serialize;

/// The modal analysis of one scenario's structure.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ModesReport {
    pub name: String,
    pub file: String,
    /// Whether the settle criteria were met before the analysis.
    pub settled: bool,
    pub settle_steps: u64,
    pub free_bodies: usize,
    /// Six per free body, or one per free joint of a jointed structure.
    pub coordinates: usize,
    /// A jointed structure's coordinates: its free joints, by name (empty for free bodies).
    pub joint_coordinates: Vec<String>,
    /// A structure held by constraints (loops, taut inextensible cables): what the coordinates
    /// were reduced by; None for free bodies on springs and for joint trees.
    pub constraints: Option<ConstraintsReport>,
    /// Modes with |omega^2| below `zero_mode_ratio` of the largest (free rigid motions).
    pub rigid_modes: usize,
    pub zero_mode_ratio: f64,
    /// Ascending omega^2.
    pub modes: Vec<ModeReport>,
    /// Where `modes` are the lowest of the structure's modes (the sparse solver's, above
    /// `structure::DENSE_MODAL_MAX_FREE_BODIES` free bodies): how many it has in all (its
    /// coordinates); absent where every mode is listed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lowest_of: Option<usize>,
    /// Wall time of the analysis after the settle \[s\].
    pub wall_s: f64,
}

/// The constraints a structure's modes were reduced by (`sim::constrained_modes`).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ConstraintsReport {
    /// Constraint rows: each loop-closing joint's, then one per taut inextensible cable.
    pub rows: usize,
    /// The rank of their Jacobian.
    pub rank: usize,
    /// Coordinates less the rank: the dimension of the modal problem.
    pub degrees_of_freedom: usize,
    /// The joints that close loops, by name.
    pub loop_closures: Vec<String>,
    /// The taut inextensible cables with their tension from the equilibrium \[N\].
    pub taut_cables: Vec<(String, f64)>,
    /// The inextensible cables left out as slack.
    pub slack_cables: Vec<String>,
    /// The reduced Hessian's own error as an omega^2 (its second differences at h and 2 h
    /// apart): a mode below it, or below `zero_mode_ratio` of the largest, is rigid.
    pub zero_floor_rad2_per_s2: f64,
}

/// One mode.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ModeReport {
    /// From 1, ascending omega^2.
    pub index: usize,
    /// [rad^2/s^2]; negative: an unstable direction.
    pub omega_squared: f64,
    /// [rad/s] (minus sqrt(-omega^2) where omega^2 < 0).
    pub omega_rad_per_s: f64,
    /// omega / (2 pi) \[Hz\].
    pub frequency_hz: f64,
    pub rigid: bool,
    /// A mechanism stiffened by the prestress: not rigid, and less than half of its stiffness
    /// omega^2 is the members' stretching (the rest is the tensions' geometric stiffness and the
    /// loads'); judged for structures of free bodies on members (no joints).
    pub mechanism: bool,
    /// The nodes that move most, with their motion relative to the largest.
    pub largest_moving: Vec<(String, f64)>,
    /// The mode's shape: every node's displacement, world frame, for the mass-normalised
    /// amplitude (v^T M v = 1) \[m per unit\], by node name; empty for a rigid-body mode.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub node_displacements_m: Vec<(String, [f64; 3])>,
}

impl ModesReport {
    /// The table: a header, then one row per mode.
    pub fn to_table(&self) -> String {
        let mut out = format!(
            "== {} [{}]: {} free bodies, {} coordinates{}, {} rigid-body mode(s) (|omega^2| < {:.0e} of the largest){}\n",
            self.name,
            self.file,
            self.free_bodies,
            self.coordinates,
            if self.joint_coordinates.is_empty() {
                String::new()
            } else {
                format!(" (joints {})", self.joint_coordinates.join(", "))
            },
            self.rigid_modes,
            self.zero_mode_ratio,
            if self.settled { String::new() } else { ", NOT SETTLED".into() }
        );
        if let Some(c) = &self.constraints {
            out.push_str(&c.to_line());
        }
        if let Some(total) = self.lowest_of {
            out.push_str(&format!(
                "   the lowest {} of {total} modes (sparse shift-invert: every rigid-body mode found and the lowest non-rigid ones)\n",
                self.modes.len()
            ));
        }
        out.push_str(&format!(
            "   {:>4} {:>16} {:>14}  {}\n",
            "mode", "omega [rad/s]", "f [Hz]", "largest-moving nodes"
        ));
        for m in &self.modes {
            let nodes: Vec<String> = m.largest_moving.iter().map(|(n, d)| format!("{n} {d:.2}")).collect();
            out.push_str(&format!(
                "   {:>4} {:>16.9} {:>14.9}  {}{}\n",
                m.index,
                m.omega_rad_per_s,
                m.frequency_hz,
                nodes.join(", "),
                if m.rigid {
                    "  (rigid)"
                } else if m.mechanism {
                    "  (mechanism: stiffened by the prestress)"
                } else {
                    ""
                }
            ));
        }
        out
    }
}

impl ConstraintsReport {
    /// The table's second header line.
    fn to_line(&self) -> String {
        let list = |v: &[String]| if v.is_empty() { "none".to_string() } else { v.join(", ") };
        let taut: Vec<String> = self.taut_cables.iter().map(|(n, t)| format!("{n} {t:.6} N")).collect();
        format!(
            "   constraints: {} rows of rank {} ({} degree(s) of freedom); loops closed by {}; taut cables {}; slack cables {}; rigid below {:.1e} rad^2/s^2 (the Hessian's own error)\n",
            self.rows,
            self.rank,
            self.degrees_of_freedom,
            list(&self.loop_closures),
            list(&taut),
            list(&self.slack_cables),
            self.zero_floor_rad2_per_s2
        )
    }
}
