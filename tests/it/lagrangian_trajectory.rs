//! A motion against the file's Lagrangian model (`[energy.trajectory]`), value by value where
//! the user looks: the per-tick table (CSV and Arrow) and the recording hold, at every tick,
//! each coordinate simulated, the model's value and the error; and the model started from the
//! file's stated initial condition (`start = "stated"`) instead of the motion's samples. The
//! scenario is the shipped pinned bar released 0.5 rad from its drawn equilibrium
//! (`scenarios/custom/pinned_bar_large_amplitude.toml`), the smallest with `[energy.trajectory]`.

use arrow_array::{Array, Float64Array};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use tensegrity_testbed::report::{LagrangianReport, ScenarioReport};
use tensegrity_testbed::run::{run, RunOptions};
use tensegrity_testbed::scenario;

const LARGE: &str = "scenarios/custom/pinned_bar_large_amplitude.toml";

/// The table's columns of coordinate `qe`: simulated, model, error.
const COLUMNS: [&str; 3] = ["trajectory_sim:qe", "trajectory_model:qe", "trajectory_error:qe"];

/// The largest |(model - simulated)| - error| allowed at a row: the subtraction's round-off.
const ROW_ROUND_OFF: f64 = 1e-15;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tensegrity-lagrangian-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `text` with `opts`.
fn run_text(text: &str, opts: &RunOptions) -> ScenarioReport {
    run(&scenario::parse(Path::new("variant.toml"), text).expect("a valid variant"), opts)
}

fn lagrangian(r: &ScenarioReport) -> &LagrangianReport {
    r.motion.as_ref().and_then(|m| m.lagrangian.as_ref()).expect("a Lagrangian comparison")
}

/// The CSV's header and its cells (None where empty).
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<Option<f64>>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines.map(|l| l.split(',').map(|c| c.parse::<f64>().ok()).collect()).collect();
    (header, rows)
}

/// The named columns of an Arrow IPC table file (None for nulls).
fn read_arrow(path: &Path, names: &[&str]) -> Vec<Vec<Option<f64>>> {
    let reader = arrow_ipc::reader::FileReader::try_new(std::fs::File::open(path).unwrap(), None).unwrap();
    let schema = reader.schema();
    let at: Vec<usize> = names.iter().map(|n| schema.index_of(n).expect("the column")).collect();
    let mut out = vec![Vec::new(); names.len()];
    for batch in reader {
        let batch = batch.unwrap();
        for (o, i) in out.iter_mut().zip(&at) {
            let col = batch.column(*i).as_any().downcast_ref::<Float64Array>().expect("Float64");
            o.extend((0..col.len()).map(|k| (!col.is_null(k)).then(|| col.value(k))));
        }
    }
    out
}

/// The table of the shipped half-radian release has, per tick, qe simulated, the Lagrangian
/// model's qe and their error: the first motion tick (one of the samples the model starts
/// from) uncompared, every other one with |model - simulated| = error within 1e-15, the
/// largest error the report's; the Arrow file holds the CSV's values bit for bit.
#[test]
fn the_table_holds_the_model_and_its_error_at_every_tick() {
    let d = dir("table");
    let (csv, arrow) = (d.join("t.csv"), d.join("t.arrow"));
    let sc = scenario::load(Path::new(LARGE)).unwrap();
    let r = run(&sc, &RunOptions { table: Some(csv.clone().into()), ..RunOptions::default() });
    run(&sc, &RunOptions { table: Some(arrow.clone().into()), ..RunOptions::default() });
    let (header, rows) = read_csv(&csv);
    let col = |name: &str| header.iter().position(|h| h == name).unwrap_or_else(|| panic!("{name} in {header:?}"));
    let [sim, model, error] = COLUMNS.map(col);
    let l = lagrangian(&r);
    assert_eq!(l.start, "samples");
    let compared: Vec<&Vec<Option<f64>>> = rows.iter().filter(|row| row[model].is_some()).collect();
    assert_eq!(compared.len(), l.coordinates[0].ticks_compared);
    assert_eq!(rows.len(), compared.len() + 1, "all but the first motion tick compared");
    assert!(rows[0][sim].is_some() && rows[0][error].is_none());
    let mut largest: f64 = 0.0;
    for row in &compared {
        let (s, m, e) = (row[sim].unwrap(), row[model].unwrap(), row[error].unwrap());
        assert!(((m - s).abs() - e).abs() <= ROW_ROUND_OFF, "tick {:?}: {s} {m} {e}", row[0]);
        largest = largest.max(e);
    }
    assert_eq!(largest, l.coordinates[0].max_error, "the report's largest error is the table's");
    let from_arrow = read_arrow(&arrow, &COLUMNS);
    for (c, values) in [sim, model, error].iter().zip(&from_arrow) {
        let from_csv: Vec<Option<f64>> = rows.iter().map(|row| row[*c]).collect();
        assert_eq!(&from_csv, values, "{}", header[*c]);
    }
}

/// Per entity of a recording, its scalar rows: (tick, the values logged there).
pub(super) type Scalars = BTreeMap<String, Vec<(i64, Vec<f64>)>>;

/// The component of a `Scalars` archetype.
const SCALARS_COMPONENT: &str = "Scalars:scalars";

/// Per entity of a recording (data store only), the `tick` values logged, and its scalar rows.
pub(super) fn read_recording(path: &Path) -> (BTreeMap<String, BTreeSet<i64>>, Scalars) {
    let file = std::io::BufReader::new(std::fs::File::open(path).expect("recording exists"));
    let (mut ticks, mut scalars): (BTreeMap<String, BTreeSet<i64>>, Scalars) = Default::default();
    for msg in re_log_encoding::Decoder::<re_log_types::LogMsg>::decode_lazy(file) {
        let re_log_types::LogMsg::ArrowMsg(store, arrow) = msg.expect("decodes") else { continue };
        let chunk = re_chunk::Chunk::from_arrow_msg(&arrow).expect("a chunk");
        if store.kind() == re_log_types::StoreKind::Blueprint {
            continue;
        }
        let entity = chunk.entity_path().to_string();
        let Some(col) = chunk.timelines().iter().find(|(name, _)| name.as_str() == "tick").map(|(_, c)| c) else {
            continue;
        };
        ticks.entry(entity.clone()).or_default().extend(col.times_raw().iter().copied());
        let id = chunk.components_identifiers().find(|id| id.as_str() == SCALARS_COMPONENT);
        if let Some(id) = id {
            let rows = col.times_raw().iter().zip(chunk.iter_slices::<f64>(id));
            scalars.entry(entity.clone()).or_default().extend(rows.map(|(t, v)| (*t, v.to_vec())));
        }
    }
    (ticks, scalars)
}

/// The recording holds qe simulated against its model (`trajectory/qe`) and their error
/// (`trajectory_error/qe`) at every compared tick (2 to 4000), the table's values there bit for
/// bit, and each frequency check's fit and model value over the motion (`frequencies/NAME`, at
/// its first and last tick) as the report has them.
#[test]
fn the_recording_holds_the_model_beside_the_simulation() {
    let d = dir("record");
    let (rrd, csv) = (d.join("bar.rrd"), d.join("bar.csv"));
    let sc = scenario::load(Path::new(LARGE)).unwrap();
    let r =
        run(&sc, &RunOptions { record: Some(rrd.clone()), table: Some(csv.clone().into()), ..RunOptions::default() });
    let m = r.motion.as_ref().unwrap();
    let steps = m.steps_taken as i64;
    let (entities, scalars) = read_recording(&rrd);
    let compared: BTreeSet<i64> = (2..=steps).collect();
    for e in ["/trajectory/qe", "/trajectory_error/qe"] {
        let ticks = entities.get(e).unwrap_or_else(|| panic!("{e} missing: {:?}", entities.keys()));
        assert_eq!(ticks, &compared, "{e}");
    }
    let (header, rows) = read_csv(&csv);
    let col = |name: &str| header.iter().position(|h| h == name).expect("the column");
    let [sim, model, error] = COLUMNS.map(col);
    let by_tick: BTreeMap<i64, &Vec<Option<f64>>> = rows.iter().map(|row| (row[0].unwrap() as i64, row)).collect();
    for (tick, values) in &scalars["/trajectory/qe"] {
        assert_eq!(values, &[by_tick[tick][sim].unwrap(), by_tick[tick][model].unwrap()], "tick {tick}");
    }
    for (tick, values) in &scalars["/trajectory_error/qe"] {
        assert_eq!(values, &[by_tick[tick][error].unwrap()], "tick {tick}");
    }
    // rerun's entity paths escape spaces and colons.
    let checks = ["/frequencies/linear", "/frequencies/at\\ amplitude\\ A"];
    for (e, f) in checks.iter().zip(&m.frequencies) {
        let want = vec![f.corrected_rad_per_s, f.predicted_rad_per_s];
        assert_eq!(scalars[*e], [(0, want.clone()), (steps, want)], "{e}");
    }
    let c = &m.lagrangian.as_ref().unwrap().coordinates[0];
    let want = vec![c.simulated_omega_rad_per_s, c.model_omega_rad_per_s];
    assert_eq!(scalars["/frequencies/trajectory\\:qe"], [(0, want.clone()), (steps, want)]);
    // The simulation's own error estimate per quantity, joint coordinate and node coordinate at
    // every tick of the motion (named in order), the table's `estimate:` columns bit for bit.
    let largest = &m.extrapolation.as_ref().expect("extrapolated").largest_estimate;
    let nodes = header.iter().filter_map(|h| h.strip_prefix("estimate:").filter(|n| n.starts_with("node:")));
    let mut keys: Vec<&str> = largest.keys().map(String::as_str).filter(|k| *k != "node positions").collect();
    keys.extend(nodes);
    keys.sort_unstable();
    let k = keys.iter().position(|key| *key == "joint:pin.angle").expect("the pin's estimate");
    let estimate = col("estimate:joint:pin.angle");
    let series = &scalars["/simulation_error"];
    assert_eq!(series.len() as i64, steps, "one row per tick of the motion");
    for (tick, values) in series {
        assert_eq!(values.len(), keys.len());
        assert_eq!(Some(values[k]), by_tick[tick][estimate], "tick {tick}");
    }
}

/// The shipped file's text started from its stated initial condition, at time step `dt_s`.
fn stated(dt_s: f64) -> String {
    super::common::edited(
        LARGE,
        &[
            ("[sim]\ndt = 1e-3", &format!("[sim]\ndt = {dt_s}")),
            ("[energy.trajectory]\n", "[energy.trajectory]\nstart = \"stated\"\n"),
        ],
    )
}

/// Time steps [s] of the stated start's measurement.
const STATED_STEPS_S: [f64; 4] = [2e-3, 1e-3, 5e-4, 2.5e-4];

/// The largest |qe_sim - qe_model| from the stated start with rapier's steps alone
/// (`[motion] extrapolate = false`), measured at [`STATED_STEPS_S`] [rad]: the motion starts at
/// a half step (the leapfrog scheme), second order. (A first step taken in full from rest made
/// it 9.21e-3, 4.31e-3, 2.08e-3, 1.02e-3: first order.)
const STATED_STEPPED_RAD: [f64; 4] = [1.309e-3, 3.271e-4, 8.179e-5, 2.045e-5];

/// The same, the motion extrapolated over the time step (the default): fourth order, what is
/// left at 0.25 ms the model's own integration tolerance.
const STATED_EXTRAPOLATED_RAD: [f64; 4] = [2.804e-8, 1.744e-9, 1.087e-10, 6.781e-12];

/// Started from the stated initial condition (the drawn angle plus 0.5 rad, at rest, t = 0),
/// the model is compared from the first tick; the report says which start; the error is
/// second order in dt with rapier's steps alone and fourth order extrapolated, as measured
/// (regression pins, met within a factor 2 either way; the orders are the claims).
#[test]
fn the_model_starts_from_the_stated_initial_condition() {
    let q_star = f64::atan2(50.0 * 0.8, 30.0 * 0.6);
    for (extrapolate, pins, order_wanted) in [(false, STATED_STEPPED_RAD, 2.0), (true, STATED_EXTRAPOLATED_RAD, 4.0)] {
        let mut errors = Vec::new();
        for (dt, measured) in STATED_STEPS_S.iter().zip(pins) {
            let text = stated(*dt).replacen("[motion]", &format!("[motion]\nextrapolate = {extrapolate}"), 1);
            let r = run_text(&text, &RunOptions::default());
            let l = lagrangian(&r);
            assert_eq!((l.start.as_str(), l.start_time_s, l.error.as_ref()), ("stated", 0.0, None));
            assert!(l.method.contains("initial condition"), "{}", l.method);
            assert!((l.start_coordinates[0] - (q_star + 0.5)).abs() <= 1e-12, "{:?}", l.start_coordinates);
            assert_eq!(l.start_rates, [0.0]);
            let c = &l.coordinates[0];
            assert_eq!(c.ticks_compared as u64, r.motion.as_ref().unwrap().steps_taken);
            assert!(c.max_error <= 2.0 * measured && c.max_error >= 0.5 * measured, "dt {dt}: {}", c.max_error);
            errors.push(c.max_error);
        }
        let order = super::common::fitted_order(&STATED_STEPS_S, &errors);
        eprintln!(
            "stated start (extrapolated {extrapolate}): errors {errors:?} at dt {STATED_STEPS_S:?}, order {order:.3}"
        );
        let low = if extrapolate { 3.5 } else { 1.9 };
        assert!(order >= low && order <= order_wanted + 0.3, "order {order}");
    }
}

/// A stated start with a rate: the rate along the coordinate is `[motion]`'s (the coordinate
/// moves one to one with the pin), and the model follows the motion as closely as from rest.
#[test]
fn a_stated_rate_starts_the_model_moving() {
    let rate = 0.3;
    let text = stated(1e-3).replacen("displacement = \"A\"\n", &format!("displacement = \"A\"\nrate = {rate}\n"), 1);
    let r = run_text(&text, &RunOptions::default());
    let l = lagrangian(&r);
    assert!((l.start_rates[0] - rate).abs() <= 1e-12, "{:?}", l.start_rates);
    assert!(l.coordinates[0].max_error <= 2.0 * STATED_EXTRAPOLATED_RAD[1], "{:?}", l.coordinates[0]);
}

/// From a settled start the stated start is the settled angle plus the displacement: the
/// settle lands on q* (within the settle tolerances), so the model starts at q* + 0.5 rad
/// within 1e-9 and the error is the drawn start's within 1 %.
#[test]
fn the_stated_start_after_a_settle_is_the_settled_state_displaced() {
    let q_star = f64::atan2(50.0 * 0.8, 30.0 * 0.6);
    let r = run_text(&stated(1e-3).replacen("start = \"drawn\"", "start = \"settled\"", 1), &RunOptions::default());
    let l = lagrangian(&r);
    assert_eq!(l.start, "stated");
    assert!((l.start_coordinates[0] - (q_star + 0.5)).abs() <= 1e-9, "{:?}", l.start_coordinates);
    let e = l.coordinates[0].max_error;
    assert!((e - STATED_EXTRAPOLATED_RAD[1]).abs() <= 0.01 * STATED_EXTRAPOLATED_RAD[1], "{e}");
}

/// A start that is neither "samples" nor "stated" is refused where it is written.
#[test]
fn an_unknown_start_is_located() {
    let text = super::common::edited(LARGE, &[("[energy.trajectory]\n", "[energy.trajectory]\nstart = \"paper\"\n")]);
    let err = scenario::parse(Path::new("variant.toml"), &text).expect_err("refused").to_string();
    assert!(err.contains("unknown energy.trajectory.start 'paper' (expected one of: samples, stated)"), "{err}");
}

/// `[energy.trajectory] measure = "period"` (issue 62 item 7: the trajectories' frequencies had
/// been cosine fits only): at half a radian the model's and the simulation's frequencies by
/// their periods meet the pendulum's exact omega_A within 1e-9 (measured 4.1e-10 and 1.0e-11),
/// where the cosine fit's are 2.0e-7 off (its bias over this record); an unknown measure is an
/// error at its key.
#[test]
fn the_trajectorys_frequencies_by_their_periods_meet_the_exact_pendulum() {
    let file = "scenarios/custom/pinned_bar_large_amplitude.toml";
    let omegas = |measure: &str| {
        let text = super::common::edited(
            file,
            &[("rms_tolerance = 2e-4", &format!("rms_tolerance = 2e-4\nmeasure = \"{measure}\""))],
        );
        let v = super::common::json_of("run", &text, &format!("period-{measure}"));
        let s = &v["scenarios"][0];
        let exact = s["motion"]["frequencies"][1]["predicted_rad_per_s"].as_f64().unwrap();
        let c = &s["motion"]["lagrangian"]["coordinates"][0];
        let rel = |key: &str| (c[key].as_f64().unwrap() - exact).abs() / exact;
        (rel("model_omega_rad_per_s"), rel("simulated_omega_rad_per_s"), s["motion"]["lagrangian"]["measure"].clone())
    };
    let (model, simulated, named) = omegas("period");
    assert!(model <= 1e-9 && simulated <= 1e-9, "{model} {simulated}");
    assert_eq!(named, "period");
    let (model, simulated, named) = omegas("cosine");
    assert!(model >= 1e-7 && simulated >= 1e-7, "{model} {simulated}");
    assert!(named.is_null(), "{named}");
    let bad = super::common::edited(file, &[("rms_tolerance = 2e-4", "rms_tolerance = 2e-4\nmeasure = \"fft\"")]);
    super::common::error_at(&bad, "\"fft\"", 0, "measure must be \"cosine\"");
}
