//! `tensegrity modes --record FILE.rrd`: each natural mode of a structure animated at its
//! frequency, as rerun entities `modes/NN omega=W rad/s/{nodes,struts,springs,cables}` on the
//! timeline `mode_time` (seconds of the mode's own motion: [`PERIODS`] periods each, mode after
//! mode, [`FRAMES_PER_PERIOD`] frames a period). Each node moves by a sin(omega t) times its
//! displacement in the mode, the largest scaled to [`AMPLITUDE_FRACTION`] of the structure's
//! extent. Plain data in, as every observer: no simulation here.

use super::record::RecordError;
use std::path::Path;

/// Periods shown per mode.
pub const PERIODS: usize = 2;
/// Frames per period.
pub const FRAMES_PER_PERIOD: usize = 40;
/// The largest node displacement drawn, as a fraction of the structure's extent.
pub const AMPLITUDE_FRACTION: f64 = 0.1;

/// One mode to draw.
pub struct DrawnMode {
    /// [rad/s]
    pub omega: f64,
    /// Each node's displacement in the mode (any scale; rescaled here) \[m\].
    pub node_motion: Vec<[f64; 3]>,
}

/// The structure at rest: node positions \[m\] and the members as node index pairs.
pub struct DrawnStructure {
    pub nodes: Vec<[f64; 3]>,
    pub struts: Vec<(usize, usize)>,
    pub springs: Vec<(usize, usize)>,
    pub cables: Vec<(usize, usize)>,
}

/// Writes the animation of `modes` to `path` (through `<path>.partial`, renamed when complete).
pub fn record_modes(path: &Path, s: &DrawnStructure, modes: &[DrawnMode]) -> Result<(), RecordError> {
    let shown = || path.display().to_string();
    let output = |source| RecordError::Output { path: shown(), source };
    let refused = |e: &dyn std::fmt::Display| RecordError::Rerun { path: shown(), message: e.to_string() };
    crate::output::check_replaceable(path).map_err(output)?;
    let partial = crate::output::partial_path(path);
    let rec = rerun::RecordingStreamBuilder::new("tensegrity-modes").save(&partial).map_err(|e| refused(&e))?;
    let _ = rec.log_static("/", &rerun::ViewCoordinates::RIGHT_HAND_Z_UP());
    let extent = extent(&s.nodes);
    let mut start = 0.0;
    for (k, m) in modes.iter().enumerate() {
        let largest = m.node_motion.iter().map(norm).fold(0.0, f64::max);
        if m.omega.is_nan() || m.omega <= 0.0 || largest == 0.0 {
            continue;
        }
        let scale = AMPLITUDE_FRACTION * extent / largest;
        let entity = format!("modes/{:02} omega={:.4} rad per s", k + 1, m.omega);
        let period = std::f64::consts::TAU / m.omega;
        for f in 0..=PERIODS * FRAMES_PER_PERIOD {
            let t = period * f as f64 / FRAMES_PER_PERIOD as f64;
            rec.set_duration_secs("mode_time", start + t);
            let a = scale * (m.omega * t).sin();
            let p: Vec<[f32; 3]> =
                s.nodes.iter().zip(&m.node_motion).map(|(x, d)| [0, 1, 2].map(|i| (x[i] + a * d[i]) as f32)).collect();
            log_frame(&rec, &entity, s, &p);
        }
        start += PERIODS as f64 * period;
    }
    let flushed = rec.flush_blocking();
    drop(rec);
    if let Err(e) = flushed {
        crate::output::discard(&partial);
        return Err(refused(&e));
    }
    crate::output::commit(&partial, path).map_err(output)
}

fn norm(d: &[f64; 3]) -> f64 {
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

/// The largest distance between two nodes [m] (1 m when there are none).
fn extent(nodes: &[[f64; 3]]) -> f64 {
    let mut e = 0.0f64;
    for a in nodes {
        for b in nodes {
            e = e.max(norm(&[a[0] - b[0], a[1] - b[1], a[2] - b[2]]));
        }
    }
    if e > 0.0 {
        e
    } else {
        1.0
    }
}

/// One frame: the nodes and the members between them.
fn log_frame(rec: &rerun::RecordingStream, entity: &str, s: &DrawnStructure, p: &[[f32; 3]]) {
    let _ = rec.log(format!("{entity}/nodes"), &rerun::Points3D::new(p.iter().copied()).with_radii([0.01f32]));
    let strips = |pairs: &[(usize, usize)]| pairs.iter().map(|(a, b)| vec![p[*a], p[*b]]).collect::<Vec<_>>();
    for (name, pairs, color) in [
        ("struts", &s.struts, [200u8, 200, 200, 255]),
        ("springs", &s.springs, [230, 160, 60, 255]),
        ("cables", &s.cables, [90, 160, 230, 255]),
    ] {
        if !pairs.is_empty() {
            let _ = rec.log(format!("{entity}/{name}"), &rerun::LineStrips3D::new(strips(pairs)).with_colors([color]));
        }
    }
}
