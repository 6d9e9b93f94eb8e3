//! The report of `tensegrity certify`: a settled state's certificate (`crate::certify`), as a
//! table and as JSON.

use crate::certify::{Certificate, Stability};
use crate::mechanisms::Values;
use serde::Serialize;

/// One settle point's certificate.
#[derive(Clone, Debug, Serialize)]
pub struct CertificateReport {
    pub name: String,
    pub file: String,
    pub point: usize,
    pub inputs: Values,
    /// Whether the settle criteria were met before the proof.
    pub settled: bool,
    pub settle_steps: u64,
    /// The settle's wall time and the certificate's \[s\].
    pub settle_wall_s: f64,
    pub certify_wall_s: f64,
    pub certificate: Certificate,
    /// Asked for (`tt.certify(..., stiffness=True)`): the stiffness at the settled state over
    /// the unknowns, scaled to N/m ([`crate::certify::reduced_stiffness`]), for an independent
    /// check of the stability.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<StiffnessExport>,
}

/// A stiffness matrix by its coordinates' names \[N/m\].
#[derive(Clone, Debug, Serialize)]
pub struct StiffnessExport {
    pub coordinates: Vec<String>,
    pub matrix: Vec<Vec<f64>>,
}

impl CertificateReport {
    /// Proven: one equilibrium in the box.
    pub fn proven(&self) -> bool {
        self.certificate.proof.is_some()
    }

    /// The table: what is proven, on what, or why nothing is.
    pub fn to_table(&self) -> String {
        let c = &self.certificate;
        let mut out = format!(
            "== {} [{}] point {}: {} coordinate(s), residual {:.1e} at the settled state ({} box(es) tried; settle {:.3} s, certificate {:.3} s)\n",
            self.name, self.file, self.point, c.coordinates, c.residual, c.boxes, self.settle_wall_s, self.certify_wall_s
        );
        match &c.proof {
            None => out += &format!("   not proven: {}\n", c.reason.as_deref().unwrap_or("no box passed")),
            Some(p) => {
                let turns = p.radius_rad.map(|r| format!("rotations {r:.3e} rad; ")).unwrap_or_default();
                out += &format!(
                    "   proven: exactly one equilibrium within {:.3e} m of the centre ({turns}nodes move at most {:.3e} m over the box){}\n",
                    p.radius_m,
                    p.node_radius_m,
                    p.held_coordinate.as_ref().map(|c| format!(", up to the free turn ({c} held)")).unwrap_or_default()
                );
                out += &format!(
                    "   it lies in an enclosure of radius {:.1e} m; the settled state is within {:.1e} m of it\n",
                    p.enclosure_radius_m, p.settled_offset_m
                );
                out += &match &p.stability {
                    Stability::Stable { smallest_eigenvalue_at_least_n_per_m: s } => {
                        format!("   stable: the stiffness is positive definite at the equilibrium (over a box around its enclosure), smallest eigenvalue >= {s:.3e} N/m\n")
                    }
                    Stability::Unstable { index } => {
                        format!("   unstable: the stiffness has {index} negative eigenvalue(s) at the equilibrium (over a box around its enclosure)\n")
                    }
                    Stability::Unproven { why } => format!("   stability not proven: {why}\n"),
                };
            }
        }
        out
    }
}
