//! Strut interference on furet2018: the crossed bars of an X pass through each other when they
//! lie in one plane, and clear each other when the planes are offset (the paper's remark).

use std::path::Path;
use tensegrity_testbed::run::{run, RunOptions};
use tensegrity_testbed::scenario;

#[test]
fn crossed_bars_collide_in_one_plane_and_clear_with_the_offset() {
    let same = run(
        &scenario::load(Path::new("scenarios/furet2018/interference_same_plane.toml")).unwrap(),
        &RunOptions::default(),
    );
    let i = same.interference.as_ref().expect("interference section");
    assert!(!same.passed, "a violation fails the run");
    assert_eq!(i.violations.len(), 2, "{:?}", i.violations);
    for (v, x) in i.violations.iter().zip(["X1", "X2"]) {
        assert_eq!(v.pair, [format!("{x} crossed bar AC"), format!("{x} crossed bar BD")]);
        // Radius 0.01 m each: axes crossing gives clearance -0.02 m.
        assert!((v.min_clearance_m + 0.02).abs() <= 1e-9, "{}", v.min_clearance_m);
        assert_eq!(v.first_tick, 0, "as drawn");
    }
    let offset = run(
        &scenario::load(Path::new("scenarios/furet2018/interference_offset.toml")).unwrap(),
        &RunOptions::default(),
    );
    let i = offset.interference.as_ref().expect("interference section");
    assert!(offset.passed, "{:?}", offset.error);
    assert!(i.violations.is_empty());
    // The closest pair keeps at least 2 dz - 2 r = 0.04 m between crossed bars; the minimum
    // overall is 0.01 m, between bars of different planes meeting near a joint.
    assert!(i.min_clearance_m.unwrap() >= 0.01 - 1e-9, "{:?}", i.min_clearance_m);
    assert!(i.pairs_checked > 10);
}
