//! `tensegrity certify`: a scenario's point settled afresh as `run` settles it, and a proof
//! of its equilibrium there (`crate::certify`, the equations from `sim/certificate.rs`).

use crate::report::certificate::CertificateReport;
use crate::run::{settle_at, RunError};
use crate::scenario::Scenario;
use crate::sim::{CertifyError, Simulation};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// Why a point has no certificate report.
#[derive(Debug, thiserror::Error)]
pub enum CertifyRunError {
    #[error(transparent)]
    Run(#[from] RunError),
    /// The structure is outside the proof's domain (bad input).
    #[error(transparent)]
    Refused(CertifyError),
    /// A motion has no equilibrium to prove (bad input).
    #[error("the scenario is a motion ([motion]): a motion has no settled equilibrium to certify; certify its settle points in a scenario without [motion]")]
    Motion,
    #[error("the scenario has no point {0} (its points are numbered from 0)")]
    NoPoint(usize),
}

/// Whether point `point` of `sc` can be certified, known before any settle from the structure as
/// drawn there: not in a motion, and a structure in the proof's domain.
pub fn certifiable(sc: &Scenario, point: usize) -> Result<(), CertifyRunError> {
    if sc.motion.is_some() {
        return Err(CertifyRunError::Motion);
    }
    let (sc, inputs) = super::sensitivity::point_of(sc, point).ok_or(CertifyRunError::NoPoint(point))?;
    let params = sc.params_at(&inputs);
    let structure = sc.mechanism().build(&params, &inputs, &sc.start).map_err(RunError::from)?;
    let sim = Simulation::new(&structure, &sc.sim).map_err(RunError::from)?;
    sim.equilibrium_problem().map(|_| ()).map_err(CertifyRunError::Refused)
}

/// The certificate of `sc` at point `point` (from 0, as `run` numbers them), named by `file`.
pub fn certify(
    sc: &Scenario,
    file: &str,
    point: usize,
    cancel: Option<&AtomicBool>,
) -> Result<CertificateReport, CertifyRunError> {
    certify_with(sc, file, (point, false), cancel)
}

/// [`certify`], with the stiffness at the settled state when `stiffness`
/// ([`CertificateReport::stiffness`]).
pub fn certify_with(
    sc: &Scenario,
    file: &str,
    (point, stiffness): (usize, bool),
    cancel: Option<&AtomicBool>,
) -> Result<CertificateReport, CertifyRunError> {
    certifiable(sc, point)?;
    let (sc, inputs) = super::sensitivity::point_of(sc, point).ok_or(CertifyRunError::NoPoint(point))?;
    let params = sc.params_at(&inputs);
    let settle_wall = Instant::now();
    let state = settle_at(sc, &inputs, params, cancel)?;
    let settle_wall_s = settle_wall.elapsed().as_secs_f64();
    let wall = Instant::now();
    let problem = state.sim.equilibrium_problem().map_err(CertifyRunError::Refused)?;
    let certificate = crate::certify::certify(&problem);
    let stiffness = stiffness.then(|| {
        let (coordinates, matrix) = crate::certify::reduced_stiffness(&problem);
        crate::report::certificate::StiffnessExport { coordinates, matrix }
    });
    Ok(CertificateReport {
        name: sc.name.clone(),
        file: file.to_string(),
        point,
        inputs,
        settled: state.settled,
        settle_steps: state.steps,
        settle_wall_s,
        certify_wall_s: wall.elapsed().as_secs_f64(),
        certificate,
        stiffness,
    })
}
