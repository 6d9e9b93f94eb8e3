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


def prism_arrays():
    """A 3-strut prism drawn untwisted (radius 1 m, height 1.5 m): N, Cb (bars 1-5, 2-6, 3-4),
    Cs (bottom, top, verticals i to i+3), nodes counted from 1 as in the notation."""
    import numpy as np

    k = np.arange(6)
    angle = 2 * np.pi * k / 3
    N = np.vstack([np.cos(angle), np.sin(angle), np.where(k < 3, 0.0, 1.5)])

    def rows(pairs):
        C = np.zeros((len(pairs), 6))
        for r, (a, b) in enumerate(pairs):
            C[r, a - 1], C[r, b - 1] = -1.0, 1.0
        return C

    Cb = rows([(1, 5), (2, 6), (3, 4)])
    Cs = rows([(1, 2), (2, 3), (3, 1), (4, 5), (5, 6), (6, 4), (1, 4), (2, 5), (3, 6)])
    return N, Cb, Cs


def test_a_prism_from_numpy_arrays_settles_to_the_closed_form_twist():
    """From N, Cb, Cs as arrays, the prism settles with its bars turned by pi/2 + pi/3 (1e-8)."""
    import numpy as np

    N, Cb, Cs = prism_arrays()
    text = tt.from_matrices(N, Cb, Cs, bar_radius_m=0.02, string_tension_n=20.0)
    result = tt.run(text, name="prism.toml")
    assert result.passed, result.failures
    sim = result.report["points"][0]["simulated"]
    p = lambda k: np.array([sim[f"n{k}.{c}"] for c in "xyz"])
    bottom, top = np.mean([p(k) for k in (1, 2, 3)], axis=0), np.mean([p(k) for k in (4, 5, 6)], axis=0)
    axis = (top - bottom) / np.linalg.norm(top - bottom)
    flat = lambda v, c: (v - c) - np.dot(v - c, axis) * axis
    twists = []
    for a, b in [(1, 5), (2, 6), (3, 4)]:
        u, w = flat(p(a), bottom), flat(p(b), top)
        twists.append(abs(np.arctan2(np.dot(np.cross(u, w), axis), np.dot(u, w))))
    assert max(abs(t - (np.pi / 2 + np.pi / 3)) for t in twists) <= 1e-8


def test_bad_arrays_are_value_errors():
    import numpy as np

    N, Cb, Cs = prism_arrays()
    with pytest.raises(ValueError, match=r"N has shape \(2, 6\)"):
        tt.from_matrices(N[:2], Cb, Cs)
    bad = N.copy()
    bad[1, 4] = np.nan
    with pytest.raises(ValueError, match=r"N\[1, 4\] is nan"):
        tt.from_matrices(bad, Cb, Cs)
    with pytest.raises(ValueError, match=r"Cs has shape \(9, 5\)"):
        tt.from_matrices(N, Cb, Cs[:, :5])
    with pytest.raises(tt.ScenarioError, match="one -1, one 1"):
        tt.from_matrices(N, Cb * 2, Cs)
    with pytest.raises(ValueError, match="bar-mass"):
        tt.from_matrices(N, Cb, Cs, bar_mass_kg=-1.0)


FURET = ROOT / "scenarios" / "furet2018" / "trajectory.toml"


def furet_ik_branch(params, inputs, t):
    """furet2018's inverse kinematics in numpy: the end point by Eq. 3 from the commanded
    angles, the roots t = tan(phi1 / 2) of the characteristic quartic (Eq. 6, derived for any L)
    by numpy.roots, theta1 = atan2((b+L) t^2 + b - L, 2 L t) (Eq. 12) for each real root, and
    the branch nearest the commanded theta1."""
    import numpy as np

    L, b = params["L"], params["b"]
    th1, th2 = inputs["theta1"], inputs["theta2"]
    mid = lambda th: np.sqrt(L * L - b * b * np.cos(th) ** 2)
    x = -mid(th1) * np.sin(th1) - mid(th2) * np.sin(2 * th1 + th2)
    y = mid(th1) * np.cos(th1) + mid(th2) * np.cos(2 * th1 + th2)
    l2, l3, l4, b2, x2, y2 = L * L, L**3, L**4, b * b, x * x, y * y
    r4 = (x2 + y2) ** 2
    a4 = (L + b) ** 2 * (2 * l3 * x + 5 * l2 * x2 + l2 * y2 + 4 * L * x * x2 + 4 * L * x * y2 + b2 * y2 + r4)
    a3 = -4 * L * y * (L + b) * (l3 + 4 * l2 * x - L * b2 + 2 * L * x2 + 2 * L * y2 - 2 * b2 * x)
    a2 = 2 * (-3 * l4 * x2 + 9 * l4 * y2 + l2 * b2 * x2 - 10 * l2 * b2 * y2 + l2 * r4 + b2 * b2 * y2 + b2 * r4)
    a1 = 4 * L * y * (b - L) * (l3 - 4 * l2 * x - L * b2 + 2 * L * x2 + 2 * L * y2 + 2 * b2 * x)
    a0 = (b - L) ** 2 * (-2 * l3 * x + 5 * l2 * x2 + l2 * y2 - 4 * L * x * x2 - 4 * L * x * y2 + b2 * y2 + r4)
    roots = np.roots([a4, a3, a2, a1, a0])
    real = roots[np.abs(roots.imag) <= 1e-7 * (1 + np.abs(roots))].real
    branches = np.arctan2((b + L) * real**2 + b - L, 2 * L * real)
    wrap = lambda a: (a + np.pi) % (2 * np.pi) - np.pi
    best = branches[np.argmin(np.abs(wrap(branches - th1)))]
    return {"theta1 (IK branch)": float(best)}


def test_a_furet2018_ik_branch_from_numpy_roots_is_compared_tick_by_tick():
    """Along trajectory.toml's eight waypoints the branch numpy.roots picks is the simulated
    theta1 within 1e-7 rad at every settle point and at every tick (measured 2.4e-8 over 48
    ticks: numpy.roots' accuracy on the quartic)."""
    pred = [tt.Prediction("theta1 (IK branch)", "theta1", "angle", 1e-7)]
    result = tt.run(FURET, model=furet_ik_branch, predictions=pred)
    row = next(c for c in result.report["model_checks"] if c["name"] == "theta1 (IK branch)")
    assert row["points_compared"] == 8 and row["passed"], row
    assert row["ticks_compared"] >= 40 and row["transient_max_error"] <= 1e-7, row
    assert result.as_expected


def test_solve_findings_and_export_are_the_clis():
    sols = tt.solve("ji2014", "fk", L3=1.0, theta1=0.5)
    cli = json.loads(subprocess.run(
        [os.path.join(os.environ.get("CARGO_TARGET_DIR", str(ROOT / "target")), "release", "tensegrity"),
         "solve", "ji2014", "fk", "--set", "L3=1.0", "--set", "theta1=0.5", "--json"],
        capture_output=True, text=True, cwd=ROOT).stdout)
    assert [s.values for s in sols] == [s["values"] for s in cli["solutions"]]
    assert [s.stable for s in sols] == [s["stable"] for s in cli["solutions"]]
    found = tt.findings("ji2014")
    assert len(found) == 33 and sum(not f.holds for f in found) == 15
    xml, skipped = tt.export_mjcf(ROOT / "scenarios" / "custom" / "prism3.toml")
    assert xml.lstrip().startswith("<mujoco") and "tendon" in xml
    with pytest.raises(ValueError, match="unknown mechanism"):
        tt.solve("ji2015", "fk")
    with pytest.raises(ValueError, match="needs theta1"):
        tt.solve("ji2014", "fk", L3=1.0)
    with pytest.raises(ValueError, match="actuators"):
        tt.export_mjcf(QUICK, actuators="torque")
