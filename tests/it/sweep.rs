//! Sweeps: bit-identical whatever the number of jobs; four interleaved shards merged give the
//! unsharded rows within the scenario's tolerances.

use crate::common;

use common::tensegrity;

fn dir() -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("tensegrity-sweep-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn column(csv: &str, name: &str) -> Vec<f64> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let k = header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("no column {name}"));
    lines.map(|l| l.split(',').nth(k).unwrap().parse().unwrap()).collect()
}

#[test]
fn one_job_and_two_jobs_give_bit_identical_csv() {
    let d = dir();
    let (a, b) = (d.join("j1.csv"), d.join("j2.csv"));
    for (jobs, out) in [("1", &a), ("2", &b)] {
        let (code, o, e) =
            tensegrity(&["sweep", "scenarios/ji2014/grid.toml", "--jobs", jobs, "--out", out.to_str().unwrap()]);
        assert_eq!(code, 0, "{o}{e}");
    }
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
}

#[test]
fn four_shards_merged_equal_the_unsharded_sweep_within_tolerance() {
    let d = dir();
    let whole = d.join("whole.csv");
    let (code, o, e) = tensegrity(&["sweep", "scenarios/ji2014/grid.toml", "--out", whole.to_str().unwrap()]);
    assert_eq!(code, 0, "{o}{e}");
    let mut shards = Vec::new();
    for k in 1..=4 {
        let p = d.join(format!("shard{k}.csv"));
        let (code, o, e) = tensegrity(&[
            "sweep",
            "scenarios/ji2014/grid.toml",
            "--shard",
            &format!("{k}/4"),
            "--out",
            p.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{o}{e}");
        shards.push(p.to_str().unwrap().to_string());
    }
    let merged = d.join("merged.csv");
    let mut args = vec!["merge"];
    args.extend(shards.iter().rev().map(String::as_str)); // any order
    args.extend(["--out", merged.to_str().unwrap()]);
    let (code, o, e) = tensegrity(&args);
    assert_eq!(code, 0, "{o}{e}");
    let (w, m) = (std::fs::read_to_string(&whole).unwrap(), std::fs::read_to_string(&merged).unwrap());
    assert_eq!(column(&w, "index"), column(&m, "index"));
    assert_eq!(column(&w, "index").len(), 110);
    // The scenario's tolerances: 1e-9 of L = 1 m for theta2, x, y (theta2 as an angle: pi and
    // -pi are the same orientation).
    for q in ["simulated_theta2", "simulated_x", "simulated_y"] {
        for (a, b) in column(&w, q).iter().zip(column(&m, q)) {
            let d = if q == "simulated_theta2" { tensegrity_testbed::mechanisms::wrap_angle(a - b) } else { a - b };
            assert!(d.abs() <= 1e-9, "{q}: {a} vs {b}");
        }
    }
    // The same shard twice is refused.
    let (code, _, e) = tensegrity(&["merge", &shards[0], &shards[0], "--out", merged.to_str().unwrap()]);
    assert_eq!(code, 2, "{e}");
    assert!(e.contains("more than one file"), "{e}");
}
