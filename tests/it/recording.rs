//! A recording is never assumed to be right: a written `.rrd` is decoded again and the entities
//! and ticks it holds are checked.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use tensegrity_testbed::run::{run, RunOptions};
use tensegrity_testbed::scenario;

/// What a recording file holds: per entity of the recording store, the set of `tick` values
/// logged; the entities of its blueprint store; and whether that blueprint is activated.
struct Contents {
    entities: BTreeMap<String, BTreeSet<i64>>,
    blueprint: BTreeSet<String>,
    blueprint_activated: bool,
}

fn read_back(path: &Path) -> Contents {
    let file = std::io::BufReader::new(std::fs::File::open(path).expect("recording exists"));
    let mut out = Contents { entities: BTreeMap::new(), blueprint: BTreeSet::new(), blueprint_activated: false };
    for msg in re_log_encoding::Decoder::<re_log_types::LogMsg>::decode_lazy(file) {
        match msg.expect("decodes") {
            re_log_types::LogMsg::ArrowMsg(store, arrow) => {
                let chunk = re_chunk::Chunk::from_arrow_msg(&arrow).expect("a chunk");
                if store.kind() == re_log_types::StoreKind::Blueprint {
                    out.blueprint.insert(chunk.entity_path().to_string());
                    continue;
                }
                let ticks = out.entities.entry(chunk.entity_path().to_string()).or_default();
                if let Some(col) = chunk.timelines().iter().find(|(name, _)| name.as_str() == "tick").map(|(_, c)| c) {
                    ticks.extend(col.times_raw().iter().copied());
                }
            }
            re_log_types::LogMsg::BlueprintActivationCommand(cmd) => out.blueprint_activated |= cmd.make_active,
            re_log_types::LogMsg::SetStoreInfo(_) => {}
        }
    }
    out
}

#[test]
fn a_recorded_run_holds_every_entity_at_every_tick() {
    let dir = std::env::temp_dir().join(format!("tensegrity-rec-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let rrd = dir.join("mohr.rrd");
    let sc = scenario::load(Path::new("scenarios/mohr2011/trajectory.toml")).unwrap();
    let r = run(&sc, &RunOptions { record: Some(rrd.clone()), ..RunOptions::default() });
    assert!(r.passed, "{:?}", r.error);
    let partials = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".partial"));
    assert_eq!(partials.count(), 0, "no temporary file left");
    let contents = read_back(&rrd);
    let entities = &contents.entities;
    let ticks = r.settle.steps as usize;
    for e in [
        "/structure/nodes",
        "/structure/struts",
        "/structure/cables",
        "/analytic/nodes",
        "/errors",
        "/forces/cables",
        "/inputs",
        "/errors_log10",
        "/energy/kinetic_j",
    ] {
        let t =
            entities.get(e).unwrap_or_else(|| panic!("{e} missing; have {:?}", entities.keys().collect::<Vec<_>>()));
        assert_eq!(t.len(), ticks, "{e}: {} ticks recorded of {ticks}", t.len());
        assert_eq!(*t.iter().next().unwrap(), 1);
        assert_eq!(*t.iter().last().unwrap(), ticks as i64);
    }
    // The equilibrium residual is computed once the motion has stopped: it is recorded at those
    // ticks, the last one the tick the run settled at.
    let residual = entities.get("/residual").expect("residual recorded");
    assert!(!residual.is_empty() && residual.len() < ticks, "{} residual ticks of {ticks}", residual.len());
    assert_eq!(*residual.iter().last().unwrap(), ticks as i64);
    assert!(entities.contains_key("/events"), "events recorded");
    assert!(entities.contains_key("/scenario") && entities.contains_key("/report"), "documents recorded");
    // The layout travels with the data: a blueprint store with a viewport and its views,
    // activated when the file is opened.
    let bp = &contents.blueprint;
    assert!(bp.contains("/viewport") && bp.contains("/time_panel"), "blueprint stored; have {bp:?}");
    assert!(bp.iter().filter(|e| e.starts_with("/view/") && e.ends_with("/ViewContents")).count() >= 8, "{bp:?}");
    assert!(contents.blueprint_activated, "blueprint activated");
}

/// `record_every = N` keeps every N-th tick only.
#[test]
fn record_every_thins_the_recording() {
    let dir = std::env::temp_dir().join(format!("tensegrity-rec-every-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let rrd = dir.join("thin.rrd");
    let sc = scenario::load(Path::new("scenarios/ji2014/quick.toml")).unwrap();
    let r = run(&sc, &RunOptions { record: Some(rrd.clone()), record_every: 10, ..RunOptions::default() });
    assert!(r.passed, "{:?}", r.error);
    let ticks = &read_back(&rrd).entities["/structure/nodes"];
    assert_eq!(ticks.len() as u64, r.settle.steps / 10);
    assert!(ticks.iter().all(|t| t % 10 == 0));
}

/// Streaming to an address where no viewer listens neither fails nor stalls the run: it says
/// so once and goes on.
#[test]
fn connect_without_a_viewer_goes_on() {
    let args = ["run", "scenarios/ji2014/quick.toml", "--connect", "rerun+http://127.0.0.1:1/proxy", "--json", "-"];
    let (code, out, err) = super::common::tensegrity_guarded(&args);
    assert_eq!(code, 0, "{err}");
    assert_eq!(err.matches("no rerun viewer").count(), 1, "{err}");
    // Not stalled: the run went to its end, as many ticks as without a viewer to stream to.
    let steps = |json: &str| {
        let v: serde_json::Value = serde_json::from_str(json).expect("a JSON report");
        v["scenarios"][0]["settle"]["steps"].as_u64().expect("settle steps")
    };
    let alone = super::common::tensegrity(&["run", "scenarios/ji2014/quick.toml", "--json", "-"]).1;
    assert_eq!(steps(&out), steps(&alone), "{out}");
}

/// The printout of a recording's `/events` chunks.
fn events_of(rrd: &Path) -> String {
    let file = std::io::BufReader::new(std::fs::File::open(rrd).unwrap());
    let mut events = String::new();
    for msg in re_log_encoding::Decoder::<re_log_types::LogMsg>::decode_lazy(file) {
        if let re_log_types::LogMsg::ArrowMsg(_, arrow) = msg.unwrap() {
            let chunk = re_chunk::Chunk::from_arrow_msg(&arrow).unwrap();
            if chunk.entity_path().to_string() == "/events" {
                events.push_str(&format!("{chunk}"));
            }
        }
    }
    events
}

/// A check that fails at a settle point is an event of the recording, with the quantity, its
/// error and the tolerance (a tolerance of 1e-30 on theta2 fails at every point).
#[test]
fn a_failed_check_is_an_event_of_the_recording() {
    let dir = std::env::temp_dir().join(format!("tensegrity-rec-fail-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let rrd = dir.join("fail.rrd");
    let path = Path::new("scenarios/ji2014/quick.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let text = format!("{text}\n[[checks]]\nquantity = \"theta2\"\ntolerance = 1e-30\n");
    let sc = scenario::parse(path, &text).expect("valid");
    let r = run(&sc, &RunOptions { record: Some(rrd.clone()), ..RunOptions::default() });
    assert!(!r.passed);
    let events = events_of(&rrd);
    assert!(events.contains("point 0: check theta2 failed: error"), "{events}");
    assert!(events.contains("> tolerance 1.0e-30"), "{events}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A certified settle point (`[certify]`) is an event of the recording, with what is proven:
/// the prism's equilibrium unique in a box, up to its free turn.
#[test]
fn a_certificate_is_an_event_of_the_recording() {
    let dir = std::env::temp_dir().join(format!("tensegrity-rec-certify-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let rrd = dir.join("certified.rrd");
    let path = Path::new("scenarios/custom/prism3.toml");
    let text = format!("{}\n[certify]\n", std::fs::read_to_string(path).unwrap());
    let sc = scenario::parse(path, &text).expect("valid");
    let r = run(&sc, &RunOptions { record: Some(rrd.clone()), ..RunOptions::default() });
    assert!(r.passed);
    let events = events_of(&rrd);
    assert!(events.contains("point 0: certificate: one equilibrium within"), "{events}");
    // The chunk's printout cuts long cells short: what follows the free turn is not shown.
    assert!(events.contains("up to the free turn (strut2.z held)"), "{events}");
    std::fs::remove_dir_all(&dir).unwrap();
}
