"""The Python package's overhead (BENCHMARKS.md, "Python"): a run from Python against the
CLI on the same scenario, a Python callable model per tick, and the per-tick table handed over
in memory (Arrow PyCapsule) against the CLI writing it as an Arrow file. Medians of N rounds.

    CARGO_TARGET_DIR=... python benches/python/overhead.py [rounds]
"""

import math
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import tensegrity_testbed as tt

ROOT = Path(__file__).resolve().parents[2]
CLI = os.path.join(os.environ.get("CARGO_TARGET_DIR", str(ROOT / "target")), "release", "tensegrity")
QUICK = ROOT / "scenarios" / "ji2014" / "quick.toml"
BAR = ROOT / "scenarios" / "custom" / "pinned_bar_vibration.toml"


def median_s(f, rounds):
    times = []
    for _ in range(rounds):
        start = time.perf_counter()
        f()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main(rounds):
    cli = median_s(lambda: subprocess.run([CLI, "run", str(QUICK), "--json", "-"], capture_output=True, check=True), rounds)
    py = median_s(lambda: tt.run(QUICK), rounds)
    print(f"ji2014 quick.toml: CLI process {cli * 1e3:.1f} ms, tt.run {py * 1e3:.1f} ms (ratio {py / cli:.2f})")
    omega = math.sqrt(43.8634243989 / (0.5 / 3))
    model = lambda p, i, t: {"q_py": p["q_star"] + p["A"] * math.cos(omega * (t or 0.0))}
    pred = [tt.Prediction("q_py", "q", "angle", 1.0)]
    plain = median_s(lambda: tt.run(BAR), rounds)
    called = median_s(lambda: tt.run(BAR, model=model, predictions=pred), rounds)
    ticks = 4000
    print(
        f"pinned bar motion ({ticks} ticks): {plain * 1e3:.1f} ms without a model, {called * 1e3:.1f} ms with a "
        f"Python callable: {(called - plain) / ticks * 1e6:.1f} us per tick"
    )
    # The table of a 10 s motion (10,000 ticks, 43 columns): from Python in memory, from the
    # CLI as an Arrow IPC file (what the package did before: a temporary file read back).
    import tempfile

    import pyarrow.ipc

    with tempfile.TemporaryDirectory() as d:
        long = Path(d) / "bar10.toml"
        long.write_text(BAR.read_text().replace("duration_s = 4.0", "duration_s = 10.0"))
        arrow, report = Path(d) / "t.arrow", Path(d) / "r.json"
        cli_run = [CLI, "run", str(long), "--json", str(report)]
        bare = median_s(lambda: subprocess.run(cli_run, capture_output=True), rounds)
        filed = median_s(lambda: subprocess.run(cli_run + ["--table", str(arrow)], capture_output=True), rounds)

        def read_back():
            with pyarrow.ipc.open_file(str(arrow)) as f:
                return f.read_all()

        read = median_s(read_back, rounds)
        plain = median_s(lambda: tt.run(long), rounds)
        kept = median_s(lambda: tt.run(long, table=True).table, rounds)
        rows = tt.run(long, table=True).table.num_rows
    print(
        f"table of {rows} ticks: in memory from Python +{(kept - plain) * 1e3:.1f} ms; "
        f"as an Arrow file from the CLI +{(filed - bare) * 1e3:.1f} ms, read back {read * 1e3:.1f} ms"
    )


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 7)
