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
    /// Modes with |omega^2| below `zero_mode_ratio` of the largest (free rigid motions).
    pub rigid_modes: usize,
    pub zero_mode_ratio: f64,
    /// Ascending omega^2.
    pub modes: Vec<ModeReport>,
    /// Wall time of the analysis after the settle \[s\].
    pub wall_s: f64,
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
    /// The nodes that move most, with their motion relative to the largest.
    pub largest_moving: Vec<(String, f64)>,
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
                if m.rigid { "  (rigid)" } else { "" }
            ));
        }
        out
    }
}
