"""The Python package against the CLI: the same scenarios, the same numbers, the same errors."""

import json
import os
import subprocess
from pathlib import Path

import pytest

import tensegrity_testbed as tt

ROOT = Path(__file__).resolve().parents[2]
QUICK = ROOT / "scenarios" / "ji2014" / "quick.toml"
BAR = ROOT / "scenarios" / "custom" / "pinned_bar_vibration.toml"


def cli_report(path, *flags):
    """The CLI's JSON report of one scenario (the binary the README's first command built)."""
    target = os.environ.get("CARGO_TARGET_DIR", str(ROOT / "target"))
    out = subprocess.run(
        [os.path.join(target, "release", "tensegrity"), "run", str(path), "--json", "-", *flags],
        capture_output=True, text=True, cwd=ROOT,
    )
    return json.loads(out.stdout)["scenarios"][0]


def test_settled_values_are_the_clis_bit_for_bit():
    result = tt.run(QUICK)
    cli = cli_report(QUICK)
    assert result.passed == cli["passed"] and result.failures == cli["failures"]
    points = result.points
    assert len(points) == len(cli["points"]) >= 1
    for i, p in enumerate(cli["points"]):
        for name, value in p["simulated"].items():
            assert points[f"simulated:{name}"].iloc[i] == value  # exact: bit for bit
        for name, value in p["inputs"].items():
            assert points[f"input:{name}"].iloc[i] == value


def test_overrides_are_the_clis_set():
    result = tt.run(QUICK, set={"K1": 250.0})
    cli = cli_report(QUICK, "--set", "K1=250.0")
    assert result.report["params"]["K1"] == 250.0
    assert result.points["simulated:theta2"].tolist() == [p["simulated"]["theta2"] for p in cli["points"]]


def test_a_scenario_from_text_runs_and_keeps_its_table():
    text = BAR.read_text().replace("duration_s = 4.0", "duration_s = 0.5")
    result = tt.run(text, table=True, name="bar.toml")
    assert result.as_expected is True
    table = result.table
    assert table.num_rows == 500
    assert "joint:pin.angle" in table.column_names


def test_bad_input_is_a_located_exception():
    text = QUICK.read_text().replace("[params]", "[params]\nK9 = 1.0", 1)
    with pytest.raises(tt.ScenarioError) as e:
        tt.check(text, name="bad.toml")
    assert (e.value.file, e.value.line) == ("bad.toml", text.splitlines().index("K9 = 1.0") + 1)
    assert "K9" in e.value.message
    with pytest.raises(tt.ScenarioError):
        tt.check(QUICK, set={"K1": "oops"})
    with pytest.raises(ValueError):
        tt.check(QUICK, set={"": 1.0})


def test_ctrl_c_stops_a_run():
    """SIGINT to a Python running a long motion (100 s simulated) stops it with KeyboardInterrupt."""
    import signal
    import sys
    import time

    text = BAR.read_text().replace("duration_s = 4.0", "duration_s = 100.0")
    script = (
        "import sys, tensegrity_testbed as tt\n"
        "print('started', flush=True)\n"
        "try:\n"
        f"    tt.run({text!r}, name='long.toml')\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted', flush=True); sys.exit(3)\n"
    )
    child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == "started"
    time.sleep(0.5)
    child.send_signal(signal.SIGINT)
    out, _ = child.communicate(timeout=60)  # a guard against a hang, not a speed target
    assert child.returncode == 3 and "interrupted" in out


SWEEP = ROOT / "scenarios" / "custom" / "pinned_bar_sweep.toml"


def bar_model(params, inputs, t):
    """The pinned bar's equilibrium q = atan2(k1 a, k2 b) [rad]."""
    import math

    return {"q_py": math.atan2(params["k1"] * params["a"], params["k2"] * params["b"])}


def test_a_python_model_is_judged_as_the_files_prediction():
    """Over the nine k1 of the sweep the callable's errors are the file's prediction's to 1e-15."""
    result = tt.run(SWEEP, model=bar_model, predictions=[tt.Prediction("q_py", "q", "angle", 1e-9)])
    checks = {c["name"]: c for c in result.report["model_checks"]}
    file_row, py_row = checks["q"], checks["q_py"]
    assert py_row["kind"] == "prediction" and py_row["points_compared"] == file_row["points_compared"] == 9
    assert abs(py_row["max_error"] - file_row["max_error"]) <= 1e-15
    assert abs(py_row["transient_max_error"] - file_row["transient_max_error"]) <= 1e-15
    assert py_row["passed"] and result.as_expected


def test_a_wrong_python_model_fails_by_name():
    wrong = lambda p, i, t: {"q_py": bar_model(p, i, t)["q_py"] + 1e-3}
    result = tt.run(SWEEP, model=wrong, predictions=[tt.Prediction("q_py", "q", "angle", 1e-9)])
    assert "prediction:q_py" in result.failures
    row = next(c for c in result.report["model_checks"] if c["name"] == "q_py")
    assert abs(row["max_error"] - 1e-3) <= 1e-9


def test_a_model_that_raises_or_returns_other_names_raises():
    def raises(p, i, t):
        raise RuntimeError("no branch here")

    with pytest.raises(RuntimeError, match="no branch here"):
        tt.run(SWEEP, model=raises, predictions=[tt.Prediction("q_py", "q", "angle", 1e-9)])
    with pytest.raises(ValueError, match="no prediction 'q_py'"):
        tt.run(SWEEP, model=lambda p, i, t: {"other": 0.0}, predictions=[tt.Prediction("q_py", "q", "angle", 1e-9)])
    with pytest.raises(ValueError, match="class"):
        tt.run(SWEEP, model=bar_model, predictions=[tt.Prediction("q_py", "q", "degrees", 1e-9)])


def test_a_sweep_from_python_has_the_clis_csv():
    """The same nine points and values as `tensegrity sweep --out -`."""
    import io

    import pandas as pd

    frame, summary = tt.sweep(SWEEP, jobs=2)
    target = os.environ.get("CARGO_TARGET_DIR", str(ROOT / "target"))
    out = subprocess.run(
        [os.path.join(target, "release", "tensegrity"), "sweep", str(SWEEP), "--out", "-"],
        capture_output=True, text=True, cwd=ROOT,
    )
    cli = pd.read_csv(io.StringIO(out.stdout))
    assert len(frame) == 9 and summary["passed"]
    assert list(frame.columns) == list(cli.columns)
    pd.testing.assert_frame_equal(frame, cli, check_exact=True)
