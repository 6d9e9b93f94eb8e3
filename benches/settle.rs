//! `cargo bench --bench settle`: the same measurement as `tensegrity bench`, for people who
//! reach for cargo's bench command. Speed targets live here and in BENCHMARKS.md, never in tests.

fn main() {
    let rounds = std::env::var("BENCH_ROUNDS").ok().and_then(|s| s.parse().ok()).unwrap_or(5);
    for (m, file) in tensegrity_testbed::bench::CASE_SETS {
        let r =
            tensegrity_testbed::bench::bench_case_set(m, std::path::Path::new(file), rounds).expect("case set runs");
        println!("{}", serde_json::to_string(&r).unwrap());
    }
}
