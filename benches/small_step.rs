//! `cargo bench --bench small_step`: the cost of one physical step of the smallest structures
//! of `tensegrity bench --scale --motion` (the pendulum, the rocker, the 3-strut prism), the
//! loop of `bench/scale/motion.rs` alone, beside the physical limit: a pendulum's symplectic
//! Euler written by hand (issue 64). Speed targets live here and in BENCHMARKS.md, never in
//! tests. `BENCH_STEPS` sets the steps per measurement.

use std::time::Instant;
use tensegrity_testbed::bench::scale::{cases, judged};

/// Time step of the measurement [s] (the motion bench's equal-error step).
const DT_S: f64 = 1e-3;
/// Measurements whose median is printed.
const REPEATS: usize = 5;

/// Median wall time of one step [us] of `family`'s first case.
fn us_per_step(family: &str, steps: usize) -> f64 {
    let found = if judged::FAMILIES.contains(&family) { judged::cases(family) } else { cases(family, 3) };
    let case = found.expect("the family's cases").remove(0);
    let mut walls: Vec<f64> = (0..REPEATS)
        .map(|_| {
            let mut sim = judged::physical(&case, DT_S).expect("builds");
            let start = Instant::now();
            for _ in 0..steps {
                sim.step().expect("steps");
            }
            start.elapsed().as_secs_f64() * 1e6 / steps as f64
        })
        .collect();
    walls.sort_by(f64::total_cmp);
    walls[REPEATS / 2]
}

/// The physical limit: a rigid pendulum (a uniform bar of length 1 m pinned at one end) by
/// symplectic Euler, theta'' = -(3 g / 2 L) sin(theta), per step [us].
fn hand_written_us_per_step(steps: usize) -> f64 {
    const G_OVER_L: f64 = 1.5 * 9.81;
    let mut walls: Vec<f64> = (0..REPEATS)
        .map(|_| {
            let (mut theta, mut omega) = (std::hint::black_box(0.5_f64), 0.0_f64);
            let start = Instant::now();
            for _ in 0..steps {
                omega -= DT_S * G_OVER_L * theta.sin();
                theta += DT_S * omega;
            }
            std::hint::black_box((theta, omega));
            start.elapsed().as_secs_f64() * 1e6 / steps as f64
        })
        .collect();
    walls.sort_by(f64::total_cmp);
    walls[REPEATS / 2]
}

fn main() {
    let steps = std::env::var("BENCH_STEPS").ok().and_then(|s| s.parse().ok()).unwrap_or(200_000);
    for family in ["pendulum", "rocker", "prism"] {
        let us = us_per_step(family, steps);
        println!("{family:<10} {us:8.3} us/step  {:>9.0} steps/s", 1e6 / us);
    }
    let us = hand_written_us_per_step(10 * steps);
    println!("{:<10} {us:8.4} us/step  {:>9.0} steps/s (symplectic Euler by hand)", "limit", 1e6 / us);
}
