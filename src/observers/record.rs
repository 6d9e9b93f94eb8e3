//! Recording a run to a rerun `.rrd` file, headless.
//!
//! Entities: `structure/{nodes,struts,springs,cables}` (springs and cables coloured by force),
//! `analytic/{nodes,struts}` (the analytic prediction as a ghost overlay), and time series with
//! one named series per quantity or member: `errors`, `forces/{springs,cables,actuators}`,
//! `inputs`, `residual`; `interference/min_clearance_m`; `events` (text log). The scenario file
//! and the report summary are stored as documents. Timelines: `tick` and `sim_time`.
//! The file is written to `<path>.partial` and renamed when the run ends, so a reader never
//! sees a half-written recording under the final name.

use super::{Observer, Tick};
use crate::mechanisms::wrap_angle;
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    #[error("cannot record to {path}: {message}")]
    Io { path: String, message: String },
}

pub struct Recorder {
    rec: rerun::RecordingStream,
    target: Target,
    every: u64,
    /// Series entities whose names were logged (once, as static data).
    named: std::collections::BTreeSet<String>,
}

/// Where a recording goes.
enum Target {
    /// An `.rrd` file, written to `partial` and renamed to `path` when complete.
    File { partial: PathBuf, path: PathBuf },
    /// A live stream to a rerun viewer or server.
    Live { url: String },
}

/// How long the end of a live stream waits for a viewer to take the data [s].
const LIVE_FLUSH_TIMEOUT_S: f64 = 2.0;

/// How long to wait for a viewer to accept a connection before streaming [s].
const CONNECT_PROBE_TIMEOUT_S: f64 = 0.5;

/// Whether something accepts TCP connections at the host and port of a rerun URL such as
/// `rerun+http://127.0.0.1:9876/proxy`.
fn listening(url: &str) -> bool {
    use std::net::ToSocketAddrs;
    let rest = url.split("://").nth(1).unwrap_or(url);
    let authority = rest.split('/').next().unwrap_or(rest);
    let Ok(addrs) = authority.to_socket_addrs() else { return false };
    addrs.into_iter().any(|a| {
        std::net::TcpStream::connect_timeout(&a, std::time::Duration::from_secs_f64(CONNECT_PROBE_TIMEOUT_S)).is_ok()
    })
}

/// rerun's own default address for a live viewer.
pub const DEFAULT_CONNECT_URL: &str = "rerun+http://127.0.0.1:9876/proxy";

fn f32x3(p: [f64; 3]) -> [f32; 3] {
    [p[0] as f32, p[1] as f32, p[2] as f32]
}

/// Colour of a member by its force: blue in compression, red in tension, grey when slack.
fn force_colour(force: f64, max_abs: f64) -> [u8; 4] {
    if force == 0.0 {
        return [150, 150, 150, 255];
    }
    let s = (force.abs() / max_abs.max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
    let c = (80.0 + 175.0 * s) as u8;
    if force > 0.0 {
        [c, 60, 60, 255]
    } else {
        [60, 60, c, 255]
    }
}

impl Recorder {
    /// Starts a recording that will be renamed to `path` by [`Recorder::finish`].
    pub fn create(path: &Path, app: &'static str, every: u64) -> Result<Self, RecordError> {
        let io = |e: String| RecordError::Io { path: path.display().to_string(), message: e };
        if let Some(dir) = path.parent() {
            if !dir.as_os_str().is_empty() {
                std::fs::create_dir_all(dir).map_err(|e| io(e.to_string()))?;
            }
        }
        let partial = path.with_extension("rrd.partial");
        let rec = rerun::RecordingStreamBuilder::new(app).save(&partial).map_err(|e| io(e.to_string()))?;
        Ok(Recorder {
            rec,
            target: Target::File { partial, path: path.to_path_buf() },
            every: every.max(1),
            named: Default::default(),
        })
    }

    /// Streams the same data live to a rerun viewer or server at `url` (rerun's default when
    /// empty). A run never fails or waits because nobody listens: the end of the run says so once.
    pub fn connect(url: &str, app: &'static str, every: u64) -> Result<Option<Self>, RecordError> {
        let url = if url.is_empty() { DEFAULT_CONNECT_URL.to_string() } else { url.to_string() };
        // rerun's gRPC sink blocks the logging calls while nobody listens (measured: a run
        // stalled for good): check that a viewer or server answers first.
        if !listening(&url) {
            eprintln!("note: no rerun viewer or server listens at {url}; the run goes on without streaming");
            return Ok(None);
        }
        let rec = rerun::RecordingStreamBuilder::new(app)
            .connect_grpc_opts(url.clone())
            .map_err(|e| RecordError::Io { path: url.clone(), message: e.to_string() })?;
        Ok(Some(Recorder { rec, target: Target::Live { url }, every: every.max(1), named: Default::default() }))
    }

    /// Stores a text document (static: it belongs to the whole run).
    pub fn document(&mut self, entity: &str, text: &str) {
        let _ = self.rec.log_static(entity, &rerun::TextDocument::new(text));
    }

    /// Logs several named series under one entity at the current time (names once, static).
    fn series(&mut self, entity: &str, names: Vec<String>, values: Vec<f64>) {
        if values.is_empty() {
            return;
        }
        if self.named.insert(entity.to_string()) {
            let _ = self.rec.log_static(entity, &rerun::SeriesLines::new().with_names(names));
        }
        let _ = self.rec.log(entity, &rerun::Scalars::new(values));
    }

    /// Logs one scalar time series value at `tick`.
    pub fn scalar(&mut self, tick: u64, entity: &str, value: f64) {
        self.rec.set_time_sequence("tick", tick as i64);
        let _ = self.rec.log(entity, &rerun::Scalars::single(value));
    }

    /// Flushes and moves the recording to its final name (a live stream: waits a moment for
    /// the viewer, and says once if none took the data).
    pub fn finish(self) -> Result<Option<PathBuf>, RecordError> {
        match self.target {
            Target::File { partial, path } => {
                self.rec
                    .flush_blocking()
                    .map_err(|e| RecordError::Io { path: path.display().to_string(), message: e.to_string() })?;
                drop(self.rec);
                std::fs::rename(&partial, &path)
                    .map_err(|e| RecordError::Io { path: path.display().to_string(), message: e.to_string() })?;
                Ok(Some(path))
            }
            Target::Live { url } => {
                if self.rec.flush_with_timeout(std::time::Duration::from_secs_f64(LIVE_FLUSH_TIMEOUT_S)).is_err() {
                    eprintln!("note: no rerun viewer took the live stream at {url}; the run went on without it");
                }
                Ok(None)
            }
        }
    }
}

impl Observer for Recorder {
    fn tick(&mut self, t: &Tick) {
        let snap = t.snapshot;
        if snap.tick % self.every != 0 {
            return;
        }
        let s = t.structure;
        let rec = &self.rec;
        rec.set_time_sequence("tick", snap.tick as i64);
        rec.set_duration_secs("sim_time", snap.time_s);
        let pts: Vec<[f32; 3]> = snap.nodes.iter().map(|p| f32x3(*p)).collect();
        // What does not change (labels, radii, fixed colours) is logged once, as static data;
        // every tick carries only positions and force colours.
        if self.named.insert("structure".into()) {
            let names = |v: Vec<&String>| v.into_iter().cloned().collect::<Vec<_>>();
            let _ = rec.log_static(
                "structure/nodes",
                &rerun::Points3D::update_fields()
                    .with_labels(names(s.nodes.iter().map(|n| &n.name).collect()))
                    .with_radii([0.02f32]),
            );
            let _ = rec.log_static(
                "structure/struts",
                &rerun::LineStrips3D::update_fields()
                    .with_radii(s.struts.iter().map(|m| m.radius_m as f32).collect::<Vec<_>>())
                    .with_colors([[200u8, 200, 200, 255]])
                    .with_labels(names(s.struts.iter().map(|m| &m.name).collect())),
            );
            let _ = rec.log_static(
                "structure/springs",
                &rerun::LineStrips3D::update_fields().with_labels(names(s.springs.iter().map(|m| &m.name).collect())),
            );
            let _ = rec.log_static(
                "structure/cables",
                &rerun::LineStrips3D::update_fields().with_labels(names(s.cables.iter().map(|m| &m.name).collect())),
            );
            let _ = rec.log_static(
                "analytic/nodes",
                &rerun::Points3D::update_fields().with_colors([[80u8, 220, 120, 160]]).with_radii([0.015f32]),
            );
            let _ = rec.log_static(
                "analytic/struts",
                &rerun::LineStrips3D::update_fields().with_colors([[80u8, 220, 120, 120]]),
            );
        }
        let _ = rec.log("structure/nodes", &rerun::Points3D::new(pts.clone()));
        let strips = |pairs: Vec<(usize, usize)>| -> Vec<Vec<[f32; 3]>> {
            pairs.into_iter().map(|(a, b)| vec![pts[a], pts[b]]).collect()
        };
        let _ = rec
            .log("structure/struts", &rerun::LineStrips3D::new(strips(s.struts.iter().map(|m| (m.a, m.b)).collect())));
        let f = &snap.forces;
        let max_f = f.spring_force_n.iter().chain(&f.cable_tension_n).fold(0.0f64, |m, x| m.max(x.abs()));
        if !s.springs.is_empty() {
            let _ = rec.log(
                "structure/springs",
                &rerun::LineStrips3D::new(strips(s.springs.iter().map(|m| (m.a, m.b)).collect()))
                    .with_colors(f.spring_force_n.iter().map(|x| force_colour(*x, max_f)).collect::<Vec<_>>()),
            );
        }
        if !s.cables.is_empty() {
            let _ = rec.log(
                "structure/cables",
                &rerun::LineStrips3D::new(strips(s.cables.iter().map(|m| (m.a, m.b)).collect()))
                    .with_colors(f.cable_tension_n.iter().map(|x| force_colour(*x, max_f)).collect::<Vec<_>>()),
            );
        }
        if let Some(ghost) = t.ghost_nodes {
            let g: Vec<[f32; 3]> = ghost.iter().map(|p| f32x3(*p)).collect();
            let _ = rec.log("analytic/nodes", &rerun::Points3D::new(g.clone()));
            let ghost_struts: Vec<Vec<[f32; 3]>> = s.struts.iter().map(|m| vec![g[m.a], g[m.b]]).collect();
            let _ = rec.log("analytic/struts", &rerun::LineStrips3D::new(ghost_struts));
        }
        // Time series: one entity per family, one named series per member or quantity (one
        // log call each, which keeps the cost per tick down).
        let (names, errors): (Vec<String>, Vec<f64>) = t
            .prediction
            .expected
            .iter()
            .filter_map(|(q, a)| {
                let sv = t.simulated.get(q)?;
                Some((q.clone(), if q.starts_with("theta") { wrap_angle(sv - a) } else { sv - a }))
            })
            .unzip();
        self.series("errors", names, errors);
        let springs = s.springs.iter().map(|m| m.name.clone()).collect();
        self.series("forces/springs", springs, f.spring_force_n.clone());
        let cables = s.cables.iter().map(|m| m.name.clone()).collect();
        self.series("forces/cables", cables, f.cable_tension_n.clone());
        let actuators: Vec<String> =
            s.actuators.iter().enumerate().map(|(i, a)| format!("{} #{}", a.symbol, i + 1)).collect();
        self.series("forces/actuators", actuators.clone(), f.actuator_force.clone());
        self.series("inputs", actuators, snap.actuator_values.clone());
        self.series(
            "residual",
            vec!["force_n".into(), "torque_nm".into()],
            vec![f.residual.max_force_n, f.residual.max_torque_nm],
        );
    }

    fn event(&mut self, tick: u64, text: &str) {
        self.rec.set_time_sequence("tick", tick as i64);
        let _ = self.rec.log("events", &rerun::TextLog::new(text));
    }
}
