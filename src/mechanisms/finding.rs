//! [`Finding`]: one printed equation or claim of a paper checked against the testbed's
//! derivation. Plain data, so that the papers' analytic models can build their catalogues
//! without depending on the simulation.

/// A printed equation checked against the testbed's derivation.
#[derive(Clone, Debug, PartialEq)]
pub struct Finding {
    pub equation: String,
    pub claim: String,
    pub measured: String,
    pub holds: bool,
}

/// A [`Finding`] for `equation` (as the paper numbers it), `claim` (what the paper says),
/// `measured` (what the check found) and whether the claim `holds`.
pub fn finding(equation: &str, claim: &str, measured: String, holds: bool) -> Finding {
    Finding { equation: equation.to_string(), claim: claim.to_string(), measured, holds }
}
