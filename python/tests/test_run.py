"""The Python package against the CLI: the same scenarios, the same numbers, the same errors."""

import json
import math
import os
import subprocess
from pathlib import Path

import pytest

import tensegrity_testbed as tt

ROOT = Path(__file__).resolve().parents[2]
QUICK = ROOT / "scenarios" / "ji2014" / "quick.toml"
BAR = ROOT / "scenarios" / "custom" / "pinned_bar_vibration.toml"


def cli_json(command, path, *flags):
    """The CLI's JSON output of `tensegrity COMMAND PATH --json -` (the binary the README's first
    command built)."""
    target = os.environ.get("CARGO_TARGET_DIR", str(ROOT / "target"))
    out = subprocess.run(
        [os.path.join(target, "release", "tensegrity"), command, str(path), "--json", "-", *flags],
        capture_output=True, text=True, cwd=ROOT,
    )
    return json.loads(out.stdout)


def cli_report(path, *flags):
    """The CLI's JSON report of one scenario."""
    return cli_json("run", path, *flags)["scenarios"][0]


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


LARGE = ROOT / "scenarios" / "custom" / "pinned_bar_large_amplitude.toml"


def test_the_table_has_the_lagrangian_model_beside_the_simulation():
    """A motion with [energy.trajectory]: per tick, qe simulated, the model's qe and their error
    (the first motion tick, one the model starts from, uncompared), as the CLI's table has them;
    the largest error is the report's."""
    result = tt.run(LARGE, table=True)
    frame = result.table.to_pandas()
    sim, model, error = (frame[f"trajectory_{k}:qe"] for k in ("sim", "model", "error"))
    compared = model.notna()
    lagrangian = result.report["motion"]["lagrangian"]
    assert lagrangian["start"] == "samples"
    assert int(compared.sum()) == lagrangian["coordinates"][0]["ticks_compared"] == len(frame) - 1
    assert ((model - sim).abs() - error)[compared].abs().max() <= 1e-15
    assert error.max() == lagrangian["coordinates"][0]["max_error"]


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
    """SIGINT to a Python running a long motion (1000 s simulated) stops it with
    KeyboardInterrupt before the motion's end. The signal is sent once the run ticks: a model
    callable, called at every tick, says so at the motion's first tick and keeps the last motion time it
    saw, printed after the interrupt (below 1000 s: stopped early). The child takes Python's own
    SIGINT handler: started from a shell's background job it inherits SIGINT ignored, and Python
    then installs none."""
    text = BAR.read_text().replace("duration_s = 4.0", "duration_s = 1000.0")
    script = (
        "import signal, sys, tensegrity_testbed as tt\n"
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "seen = []\n"
        "def model(params, inputs, t):\n"
        "    if t is not None and not seen:\n"
        "        print('ticking', flush=True)\n"
        "    seen[:] = [t] if t is not None else seen\n"
        "    return {}\n"
        "try:\n"
        f"    tt.run({text!r}, name='long.toml', model=model)\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted at t =', seen[0], flush=True); sys.exit(3)\n"
    )
    code, out = interrupted(script, "ticking")
    assert code == 3 and out.startswith("interrupted at t = "), out
    assert float(out.split("=")[1]) < 1000.0, out  # the motion's last tick is at 1000 s


@pytest.mark.parametrize("block", ["while True:\n            pass", "time.sleep(1000)"])
def test_ctrl_c_stops_a_run_whose_callable_blocks(block):
    """A model callable that never returns (a loop in Python, or a sleep of 1000 s in C) keeps
    the run from its next tick; SIGINT still raises KeyboardInterrupt in the caller: into the
    loop at its next bytecode, and past the sleep once the run has been waited for one second
    (the run itself stops at its next tick, when the sleep ends). The signal is sent once the
    callable says it blocks; the 60 s guard is against a hang, not a speed target."""
    text = BAR.read_text().replace("duration_s = 4.0", "duration_s = 1000.0")
    script = (
        "import signal, sys, time, tensegrity_testbed as tt\n"
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "def model(params, inputs, t):\n"
        "    if t is not None:\n"
        "        print('blocking', flush=True)\n"
        f"        {block}\n"
        "    return {}\n"
        "try:\n"
        f"    tt.run({text!r}, name='long.toml', model=model)\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted', flush=True); sys.exit(3)\n"
    )
    code, out = interrupted(script, "blocking")
    assert code == 3 and out.strip() == "interrupted", (code, out)


def interrupted(script, event):
    """Runs ``script`` in a child Python, sends it SIGINT once it prints the line ``event`` (the
    event the signal waits for) and returns (its exit code, the rest of its output). The 60 s
    wait is a guard against a hang, not a speed target."""
    import signal
    import sys

    child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == event
    child.send_signal(signal.SIGINT)
    out, _ = child.communicate(timeout=60)
    return child.returncode, out


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
    spans = strut_spans(result.report["points"][0]["simulated"], ["n1", "n2", "n3"], ["n4", "n5", "n6"],
                        [("n1", "n5"), ("n2", "n6"), ("n3", "n4")])
    assert max(abs(t - (np.pi / 2 + np.pi / 3)) for t in spans) <= 1e-8


def test_a_clustering_matrix_makes_one_cable_of_the_bottom_ring():
    """``clusters`` (CTSFEM's S): the three bottom strings one cable through n1, n2, n3 and back;
    the prism settles at the closed-form twist (1e-8 rad) with the ring's one tension; an S whose
    rows overlap is a ValueError naming the string and the two cables."""
    import numpy as np

    N, Cb, Cs = prism_arrays()
    S = np.zeros((1, 9))
    S[0, :3] = 1.0
    text = tt.from_matrices(N, Cb, Cs, bar_radius_m=0.02, clusters=S)
    assert 'through = ["n2", "n3"]' in text.toml
    result = tt.run(text, name="ring.toml")
    assert result.passed, result.failures
    spans = strut_spans(result.report["points"][0]["simulated"], ["n1", "n2", "n3"], ["n4", "n5", "n6"],
                        [("n1", "n5"), ("n2", "n6"), ("n3", "n4")])
    assert max(abs(t - (np.pi / 2 + np.pi / 3)) for t in spans) <= 1e-8
    overlapping = np.zeros((2, 9))
    overlapping[0, :2] = overlapping[1, 1:3] = 1.0
    with pytest.raises(ValueError, match="string2 is in clustered cables 1 and 2"):
        tt.from_matrices(N, Cb, Cs, clusters=overlapping)


def strut_spans(sim, bottom, top, struts):
    """The angle [rad] each strut (bottom node, top node) spans about a prism's axis, from the
    centroid of the ``bottom`` nodes to that of the ``top`` ones, in the settled values ``sim``."""
    import numpy as np

    p = lambda n: np.array([sim[f"{n}.{c}"] for c in "xyz"])
    b, t = np.mean([p(n) for n in bottom], axis=0), np.mean([p(n) for n in top], axis=0)
    axis = (t - b) / np.linalg.norm(t - b)
    flat = lambda v, c: (v - c) - np.dot(v - c, axis) * axis
    spans = []
    for low, high in struts:
        u, w = flat(p(low), b), flat(p(high), t)
        spans.append(abs(np.arctan2(np.dot(np.cross(u, w), axis), np.dot(u, w))))
    return spans


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
    with pytest.raises(ValueError, match=r"Cb\[0\]: a member's row holds one -1, one 1"):
        tt.from_matrices(N, Cb * 2, Cs)
    with pytest.raises(ValueError, match=r"^bar_mass_kg\[0\] must be a finite number > 0, got -1"):
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


def test_member_properties_as_arrays():
    """One stiffness, tension, mass and radius per member, as numpy arrays, land in the
    scenario member by member (rest length = drawn - tension / stiffness, to 1e-15 m); the
    prism with its bottom strings twice as stiff still settles."""
    import numpy as np

    tomllib = pytest.importorskip("tomllib")  # Python >= 3.11
    N, Cb, Cs = prism_arrays()
    k = np.array([200.0, 200.0, 200.0, 100, 100, 100, 100, 100, 100])
    tension = np.linspace(10.0, 26.0, 9)
    s = tt.from_matrices(N, Cb, Cs, bar_mass_kg=[1.0, 1.5, 2.0], bar_radius_m=np.array([0.02, 0.03, 0.04]),
                         string_stiffness_n_per_m=k, string_tension_n=tension)
    doc = tomllib.loads(s.to_toml())
    cables, bodies = doc["structure"]["cables"], doc["structure"]["bodies"]
    drawn = [np.linalg.norm(N[:, (Cs[i] == 1).argmax()] - N[:, (Cs[i] == -1).argmax()]) for i in range(9)]
    assert [c["stiffness"] for c in cables] == k.tolist()
    assert max(abs(c["length"] - (d - t / kk)) for c, d, t, kk in zip(cables, drawn, tension, k)) <= 1e-15
    assert [b["mass"] for b in bodies if b["name"].startswith("bar") and "mass" in b] == [1.5, 2.0]
    assert [st["radius"] for st in doc["structure"]["struts"]] == [0.02, 0.03, 0.04]
    rest = tt.from_matrices(N, Cb, Cs, string_rest_length_m=np.full(9, 1.25))
    assert {c["length"] for c in tomllib.loads(rest.toml)["structure"]["cables"]} == {1.25}
    assert tt.run(s).passed


def test_bad_member_properties_are_value_errors():
    import numpy as np

    N, Cb, Cs = prism_arrays()
    with pytest.raises(ValueError, match=r"string_stiffness_n_per_m has shape \(8,\): expected one number or 9 \(one per string\)"):
        tt.from_matrices(N, Cb, Cs, string_stiffness_n_per_m=np.ones(8))
    with pytest.raises(ValueError, match=r"bar_mass_kg has shape \(2,\): expected one number or 3 \(one per bar\)"):
        tt.from_matrices(N, Cb, Cs, bar_mass_kg=[1.0, 2.0])
    with pytest.raises(ValueError, match=r"bar_radius_m\[1\] is nan"):
        tt.from_matrices(N, Cb, Cs, bar_radius_m=[0.01, np.nan, 0.01])
    with pytest.raises(ValueError, match=r"string_tension_n\[4\] is inf"):
        tt.from_matrices(N, Cb, Cs, string_tension_n=[0, 0, 0, 0, np.inf, 0, 0, 0, 0])
    with pytest.raises(ValueError, match=r"string_rest_length_m\[2\] must be a finite number >= 0, got -1"):
        tt.from_matrices(N, Cb, Cs, string_rest_length_m=[1, 1, -1, 1, 1, 1, 1, 1, 1])
    with pytest.raises(ValueError, match=r"Cs\[6\]: string7: tension 200 N at 100 N/m leaves no rest length"):
        tt.from_matrices(N, Cb, Cs, string_tension_n=[0, 0, 0, 0, 0, 0, 200, 0, 0])
    with pytest.raises(ValueError, match="not both"):
        tt.from_matrices(N, Cb, Cs, string_tension_n=1.0, string_rest_length_m=1.0)
    with pytest.raises(ValueError, match="no node 'n9'"):
        tt.from_matrices(N, Cb, Cs, pins={"n9": (0, 0, 1)})
    with pytest.raises(ValueError, match=r"pins\['n1'\]\[0, 2\] is nan"):
        tt.from_matrices(N, Cb, Cs, pins={"n1": (0, 0, np.nan)})
    with pytest.raises(ValueError, match="not all zero"):
        tt.from_matrices(N, Cb, Cs, pins={"n1": (0, 0, 0)})
    with pytest.raises(tt.ScenarioError, match="n9"):
        tt.from_matrices(N, Cb, Cs, quantities={"q": "n9.x"})


def pinned_bar(k1, k2=30.0, a=0.8, b=0.6, L=1.0, q0=math.pi / 10):
    """The README tutorial's pinned bar from numpy arrays: n1 the pin A at the origin, n2 the
    bar's end P drawn at q0, n3 the anchor U = (0, a), n4 the anchor V = (b, 0); the bar n1-n2
    of 0.5 kg pinned to the ground about z; zero-free-length springs P-U of k1 and P-V of k2."""
    import numpy as np

    N = np.array([[0.0, L * math.cos(q0), 0.0, b], [0.0, L * math.sin(q0), a, 0.0], [0.0, 0.0, 0.0, 0.0]])
    Cb = np.array([[-1.0, 1.0, 0.0, 0.0]])
    Cs = np.array([[0.0, -1.0, 1.0, 0.0], [0.0, -1.0, 0.0, 1.0]])
    return tt.from_matrices(
        N, Cb, Cs, bar_mass_kg=0.5, string_stiffness_n_per_m=np.array([k1, k2]), string_rest_length_m=0.0,
        tension_only=False, pins={"n1": (0.0, 0.0, 1.0)}, quantities={"q": "atan2(n2.y - n1.y, n2.x - n1.x)"},
        name=f"pinned_bar_k1_{k1}.toml",
    )


def test_the_tutorials_pinned_bar_from_numpy_swept_from_python_has_the_files_errors():
    """The pinned bar built from arrays at each k1 of pinned_bar_sweep.toml (10 to 90 N/m),
    swept in a Python loop and judged against the callable q = atan2(k1 a, k2 b): at every k1
    its error is the file's [[predictions]] error (|simulated q - atan2(ratio a, b)|, wrapped)
    within 1e-15 rad."""
    import numpy as np

    file = tt.run(SWEEP)
    def angle_error(predicted, simulated):  # the testbed's class "angle": |wrap(simulated - predicted)|
        r = (simulated - predicted) % (2 * math.pi)
        return abs(r - 2 * math.pi if r > math.pi else r)

    file_errors = {p["inputs"]["k1"]: angle_error(p["analytic"]["q"], p["simulated"]["q"]) for p in file.report["points"]}
    file_row = next(c for c in file.report["model_checks"] if c["name"] == "q")
    assert max(file_errors.values()) == file_row["max_error"]
    a, b, k2 = 0.8, 0.6, 30.0
    k1s = np.linspace(10.0, 90.0, 9)
    assert sorted(file_errors) == k1s.tolist()
    for k1 in k1s:
        model = lambda p, i, t: {"q_py": math.atan2(k1 * a, k2 * b)}
        r = tt.run(pinned_bar(k1), model=model, predictions=[tt.Prediction("q_py", "q", "angle", 1e-9)])
        row = next(c for c in r.report["model_checks"] if c["name"] == "q_py")
        assert r.passed and row["points_compared"] == 1, (k1, r.failures)
        assert abs(row["max_error"] - file_errors[k1]) <= 1e-15, (k1, row["max_error"], file_errors[k1])


def test_a_structure_is_written_back_as_a_scenario(tmp_path):
    """A structure from arrays written to a file is the same scenario read back; writing over
    the file a structure was read from is refused, and nothing half-written is left."""
    s = pinned_bar(50.0)
    out = s.write(tmp_path / "bar.toml")
    assert out.read_text() == s.to_toml()
    again = tt.from_toml(out)
    assert tt.run(again).points["simulated:q"].tolist() == tt.run(s).points["simulated:q"].tolist()
    with pytest.raises(ValueError, match="refusing to overwrite"):
        again.write(out)
    with pytest.raises(ValueError, match="not a regular file"):
        s.write(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bar.toml"]


SQUARE_PRISM_YAML = """\
# A 4-strut prism in NTRT's YAML model format (nodes, pair_groups, builders), written for this
# test: y up, the top square drawn turned by 20 degrees from the bottom one (about y, the
# right-handed way about the testbed's z once y becomes z); rod k joins bottom k to top k+1,
# spanning 110 degrees: it settles at the closed form's 135.
nodes:
  bottom1: [1.0, 0.0, 0.0]
  bottom2: [0.0, 0.0, -1.0]
  bottom3: [-1.0, 0.0, 0.0]
  bottom4: [0.0, 0.0, 1.0]
  top1: [0.9396926207859084, 1.2, -0.3420201433256687]
  top2: [-0.3420201433256687, 1.2, -0.9396926207859084]
  top3: [-0.9396926207859084, 1.2, 0.34202014332566866]
  top4: [0.342020143325669, 1.2, 0.9396926207859083]
pair_groups:
  strut:
    - [bottom1, top2]
    - [bottom2, top3]
    - [bottom3, top4]
    - [bottom4, top1]
  cable ring:
    - [bottom1, bottom2]
    - [bottom2, bottom3]
    - [bottom3, bottom4]
    - [bottom4, bottom1]
    - [top1, top2]
    - [top2, top3]
    - [top3, top4]
    - [top4, top1]
  cable side:
    - [bottom1, top1]
    - [bottom2, top2]
    - [bottom3, top3]
    - [bottom4, top4]
builders:
  strut:
    class: tgRodInfo
    parameters:
      density: 300.0
      radius: 0.03
      restitution: 0.5
  cable:
    class: tgBasicActuatorInfo
    parameters:
      stiffness: 150.0
      pretension: 15.0
"""


def square_prism_twist(sim):
    """The largest departure of the four struts' span about the prism's axis from the closed
    form pi/2 + pi/4 of a 4-strut prism [rad]."""
    import numpy as np

    bottom, top = [f"bottom{k}" for k in range(1, 5)], [f"top{k}" for k in range(1, 5)]
    spans = strut_spans(sim, bottom, top, [(f"bottom{k}", f"top{k % 4 + 1}") for k in range(1, 5)])
    return max(abs(t - (np.pi / 2 + np.pi / 4)) for t in spans)


def test_an_ntrt_model_imports_runs_and_settles(tmp_path):
    """NTRT YAML given as text and as a file imports (the rods' restitution listed as skipped),
    runs and settles with every strut spanning pi/2 + pi/4 about the axis (the 4-strut prism's
    closed form; drawn at 110 degrees) within 1e-12 rad (measured 4.4e-16), every cable taut;
    written back, it is the same scenario."""
    s = tt.from_ntrt(SQUARE_PRISM_YAML, name="square.yaml")
    assert any("restitution" in x for x in s.skipped), s.skipped
    r = tt.run(s)
    assert r.passed and r.report["points"][0]["settled"], r.failures
    sim = r.report["points"][0]["simulated"]
    assert square_prism_twist(sim) <= 1e-12
    assert min(v for k, v in sim.items() if k.startswith("cable") and k.endswith(".force")) > 1.0
    yaml = tmp_path / "square.yaml"
    yaml.write_text(SQUARE_PRISM_YAML)
    from_file = tt.from_ntrt(yaml)
    assert from_file.to_toml().replace(str(yaml), "square.yaml") == s.to_toml()
    with pytest.raises(ValueError, match="refusing to overwrite"):
        from_file.write(yaml)
    assert yaml.read_text() == SQUARE_PRISM_YAML
    written = from_file.write(tmp_path / "square.toml")
    assert tt.run(written).report["points"][0]["simulated"] == r.report["points"][0]["simulated"]


def test_bad_ntrt_is_a_located_exception():
    bad = SQUARE_PRISM_YAML.replace("  strut:\n    class: tgRodInfo", "  strut:\n    class: tgRodInfo\n    colour: red")
    with pytest.raises(tt.ScenarioError) as e:
        tt.from_ntrt(bad, name="bad.yaml")
    assert e.value.file == "bad.yaml" and e.value.line == bad.splitlines().index("    colour: red") + 1
    with pytest.raises(tt.ScenarioError, match="no_such.yaml"):
        tt.from_ntrt("no_such.yaml")


def test_the_table_is_the_clis_arrow_table_bit_for_bit(tmp_path):
    """run(..., table=True) hands the ticks over in memory through the Arrow PyCapsule
    interface: the same columns, types and values (every f64 bit, nulls in place) as
    `tensegrity run --table FILE.arrow` of the same scenario."""
    import pyarrow as pa
    import pyarrow.ipc

    result = tt.run(SWEEP, table=True)
    target = os.environ.get("CARGO_TARGET_DIR", str(ROOT / "target"))
    path = tmp_path / "sweep.arrow"
    subprocess.run([os.path.join(target, "release", "tensegrity"), "run", str(SWEEP), "--table", str(path)],
                   capture_output=True, cwd=ROOT, check=True)
    with pa.ipc.open_file(str(path)) as f:
        cli = f.read_all()
    table = result.table
    assert table.schema == cli.schema and table.num_rows == cli.num_rows == result.arrow.num_rows >= 100
    assert table.equals(cli)  # values, nulls, types
    for name in cli.column_names[1:]:
        ours = table.column(name).to_numpy(zero_copy_only=False).view("u8") if table.column(name).null_count == 0 else None
        if ours is not None:
            assert (ours == cli.column(name).to_numpy().view("u8")).all(), name
    assert pa.table(result.arrow).equals(table)  # any PyCapsule consumer, and again
    assert tt.run(SWEEP).table is None and tt.run(SWEEP).arrow is None


def test_bad_models_on_a_structure_from_arrays_raise_not_crash():
    """On a structure built from arrays: a callable that raises, returns another name, NaN or
    not a dict raises after the run; a pin axis of the wrong shape and non-numeric properties
    are ValueErrors. The interpreter lives on (the next run passes)."""
    import numpy as np

    bar = pinned_bar(50.0)
    pred = [tt.Prediction("q_py", "q", "angle", 1e-9)]
    with pytest.raises(ZeroDivisionError):
        tt.run(bar, model=lambda p, i, t: {"q_py": 1 / 0}, predictions=pred)
    with pytest.raises(ValueError, match="no prediction 'q_py'"):
        tt.run(bar, model=lambda p, i, t: {"q": 0.5}, predictions=pred)
    with pytest.raises(ValueError, match="'q_py' is NaN, not a finite number"):
        tt.run(bar, model=lambda p, i, t: {"q_py": float("nan")}, predictions=pred)
    with pytest.raises(TypeError):
        tt.run(bar, model=lambda p, i, t: 0.5, predictions=pred)
    N, Cb, Cs = prism_arrays()
    with pytest.raises(ValueError, match=r"pins\['n1'\] has shape \(1, 2\)"):
        tt.from_matrices(N, Cb, Cs, pins={"n1": (0.0, 1.0)})
    with pytest.raises(ValueError, match="bar_mass_kg must be a number or one per bar"):
        tt.from_matrices(N, Cb, Cs, bar_mass_kg="heavy")
    with pytest.raises(ValueError, match=r"Cb has shape \(6,\): expected \(k, 6\)"):
        tt.from_matrices(N, Cb[0], Cs)
    assert tt.run(bar, model=lambda p, i, t: {"q_py": math.atan2(50.0 * 0.8, 30.0 * 0.6)}, predictions=pred).passed


ROCKER = ROOT / "scenarios" / "custom" / "rocker_frequency_curve.toml"


def test_modes_from_python_are_the_clis_modes_json():
    """tt.modes is `tensegrity modes --json`: every field equal (floats bit for bit), the
    analysis's own wall time aside."""
    py, cli = tt.modes(str(ROCKER)), cli_json("modes", ROCKER)
    py.pop("wall_s"), cli.pop("wall_s")
    assert py == cli
    assert py["joint_coordinates"] == ["pin"] and len(py["modes"]) == 1


def test_equilibrium_from_python_is_the_clis_equilibrium_json():
    """tt.equilibrium is `tensegrity equilibrium --json`: every field equal (floats bit for bit),
    the wall time aside; Kenner's prism has s = 1 and m = 2; a jointed structure raises
    ValueError naming the joint."""
    prism = ROOT / "scenarios" / "custom" / "prism3.toml"
    py, cli = tt.equilibrium(str(prism)), cli_json("equilibrium", prism)
    py.pop("wall_s"), cli.pop("wall_s")
    assert py == cli
    assert (py["self_stress_states"], py["mechanisms"]) == (1, 2)
    with pytest.raises(ValueError, match="joint 'theta1' holds a body"):
        tt.equilibrium(str(ROOT / "scenarios" / "ji2014" / "grid.toml"))


def test_a_modes_count_outside_its_range_raises():
    """count is how many non-rigid modes the sparse solver computes, 1 to 200 as
    ``modes --count``: outside, a ValueError naming the range, before any settle."""
    for count in (0, 201):
        with pytest.raises(ValueError, match="count must be from 1 to 200"):
            tt.modes(str(ROCKER), count=count)


def test_sensitivity_from_python_is_the_clis_sensitivity_json():
    """tt.sensitivity is `tensegrity sensitivity --json`: every field equal (floats bit for bit),
    the wall times aside; the rocker's d omega/d k1 agrees with the settles' within 1e-6; a cable
    with friction (its force depends on the path) raises ValueError."""
    py, cli = tt.sensitivity(str(ROCKER), check=True), cli_json("sensitivity", ROCKER, "--check")
    for r in (py, cli):
        r.pop("wall_s"), r.pop("check_wall_s")
    assert py == cli
    names = [o["name"] for o in py["outputs"]]
    k1 = next(p for p in py["parameters"] if p["name"] == "k1")
    i = names.index("mode1.omega")
    assert abs(k1["derivatives"][i] - k1["check"][i]) <= 1e-6 * abs(k1["check"][i])
    with pytest.raises(ValueError, match="cable 'rope' has friction at a node"):
        tt.sensitivity(str(ROOT / "scenarios" / "custom" / "capstan.toml"))


def test_certify_from_python_is_the_clis_certify_json():
    """tt.certify is `tensegrity certify --json`: every field equal (floats bit for bit), the wall
    times aside; the prism is proven unique up to its free turn and stable, its settled state
    within 1e-11 m of the equilibrium; a jointed structure raises ValueError naming its joint."""
    prism = ROOT / "scenarios" / "custom" / "prism3.toml"
    py, cli = tt.certify(str(prism)), cli_json("certify", prism)
    for r in (py, cli):
        r.pop("settle_wall_s"), r.pop("certify_wall_s")
    assert py == cli
    proof = py["certificate"]["proof"]
    assert proof["settled_offset_m"] <= 1e-11 and proof["held_coordinate"]
    assert proof["stability"]["kind"] == "stable"
    with pytest.raises(ValueError, match="joint 'pin'"):
        tt.certify(str(ROOT / "scenarios" / "custom" / "pendulum_tip_load.toml"))


def test_the_proven_stability_agrees_with_crlins_verified_bound():
    """The oracle: the stiffness at each settled state, exported (`stiffness=True`), is proven
    positive definite by crlin (verified linear algebra, independent of the testbed), and the
    certificate's lower bound on its smallest eigenvalue lies below crlin's verified upper
    bound on it (the certificate's holds over the equilibrium's enclosure, crlin's at the
    settled state: 1e-9 relative apart at most); on the prism, the icosahedron and the
    catenary."""
    import crlin
    import numpy as np

    for file in ["prism3.toml", "icosahedron6.toml", "catenary.toml"]:
        r = tt.certify(str(ROOT / "scenarios" / "custom" / file), stiffness=True)
        a = np.array(r["stiffness"]["matrix"])
        assert a.shape == (len(r["stiffness"]["coordinates"]),) * 2
        lam = crlin.spd(a)
        assert lam > 0, file
        lo, hi = crlin.eig_sym(a)
        ours = r["certificate"]["proof"]["stability"]["smallest_eigenvalue_at_least_n_per_m"]
        assert 0 < ours <= hi[0] * (1 + 1e-9), (file, ours, lo[0], hi[0])


def rocker_from_matrices(k1=10.0, k2=30.0, a=0.8, b=0.6, L=1.0, l1=0.5, l2=0.4, m=0.5):
    """The rocker of rocker_frequency_curve.toml from numpy arrays: n1 the pin at the origin, n2
    the strut's tip drawn at pi/4, n3 the anchor U = (0, a), n4 the anchor V = (b, 0); springs
    n2-n3 (k1, l1) and n2-n4 (k2, l2); the motion and the energy model given as dicts."""
    import numpy as np

    q0 = math.pi / 4
    N = np.array([[0.0, L * math.cos(q0), 0.0, b], [0.0, L * math.sin(q0), a, 0.0], [0.0, 0.0, 0.0, 0.0]])
    Cb = np.array([[-1.0, 1.0, 0.0, 0.0]])
    Cs = np.array([[0.0, -1.0, 1.0, 0.0], [0.0, -1.0, 0.0, 1.0]])
    potential = (f"0.5*{k1}*(sqrt({L}^2 + {a}^2 - 2*{a}*{L}*sin(phi)) - {l1})^2"
                 f" + 0.5*{k2}*(sqrt({L}^2 + {b}^2 - 2*{b}*{L}*cos(phi)) - {l2})^2")
    return tt.from_matrices(
        N, Cb, Cs, bar_mass_kg=m, string_stiffness_n_per_m=np.array([k1, k2]),
        string_rest_length_m=np.array([l1, l2]), tension_only=False, pins={"n1": (0.0, 0.0, 1.0)},
        params={"I": m * L * L / 3},
        motion={"duration_s": 4.0, "start": "settled", "coordinate": "pin_n1", "displacement": 1e-3,
                "undamped": True,
                "frequencies": [{"name": "omega", "mode": 1, "formula": "sqrt(V_phi_phi/I)",
                                 "tolerance": 1e-6, "measure": "period"}]},
        energy={"potential": potential, "kinetic": "0.5*I*phi_dot^2", "tolerance": 1e-9,
                "coordinates": [{"name": "phi", "measured": "atan2(n2.y - n1.y, n2.x - n1.x)", "class": "angle"}]},
        name="rocker_from_matrices.toml",
    )


def test_the_rocker_from_matrices_has_the_toml_rockers_inertia_and_frequency():
    """One set of physics per structure: the rocker made from arrays and the rocker written in
    TOML have the same modal frequency within 1e-12 (the bar's inertia is the file's default by
    either route, m L^2 / 12 about its middle), and its motion from Python passes the same
    three-way frequency claim."""
    rocker = rocker_from_matrices()
    made, written = tt.modes(rocker), tt.modes(str(ROCKER))  # the file's first point: k1 = 10 N/m
    assert made["settled"] and written["settled"]
    made, written = made["modes"][0]["omega_rad_per_s"], written["modes"][0]["omega_rad_per_s"]
    assert abs(made - written) <= 1e-12 * written, (made, written)
    r = tt.run(rocker)
    assert r.passed, r.failures
    f = r.report["motion"]["frequencies"][0]
    assert abs(f["predicted_rad_per_s"] - written) <= 1e-9 * written
    assert f["error"] <= 1e-6 and f["modal_error"] <= 1e-8


def test_hostile_text_is_bounded_as_a_file_and_stdin_is_refused():
    """Text past the 16 MiB a file may have is refused at its first line (30 MB had crashed the
    interpreter); '-' would read the interpreter's own standard input and is refused."""
    text = QUICK.read_text() + "#" * (16 << 20)
    with pytest.raises(tt.ScenarioError) as e:
        tt.check(text, name="huge.toml")
    assert (e.value.file, e.value.line, e.value.col) == ("huge.toml", 1, 1)
    assert "at most 16777216" in e.value.message
    with pytest.raises(ValueError, match="standard input"):
        tt.check("-")


def test_a_prediction_of_an_unknown_quantity_raises():
    """A prediction compared with a quantity the scenario does not measure is refused before
    the run (it had run and reported max_error null)."""
    with pytest.raises(ValueError, match="no quantity 'nope'"):
        tt.run(SWEEP, model=bar_model, predictions=[tt.Prediction("q_py", "nope", "angle", 1e-9)])


SWEPT_BAR = ROOT / "scenarios" / "custom" / "pinned_bar_sweep.toml"
ANGLES = ROOT / "tests" / "fixtures" / "fit" / "pinned_bar_angles.csv"


def test_fit_from_python_is_the_clis_fit_json():
    """tt.fit is `tensegrity fit --json`: every field equal (floats bit for bit), the wall time
    aside, with the data as the CSV's path and as a pandas DataFrame read from it; the estimate
    of k2 (truth 33 N/m, the file's 30 the start) holds the truth in its 95 % interval, within
    0.01 N/m."""
    import pandas as pd

    cli = cli_json("fit", SWEPT_BAR, "--data", str(ANGLES), "--param", "k2=1:100")
    by_path = tt.fit(str(SWEPT_BAR), ANGLES, {"k2": (1.0, 100.0)})
    by_frame = tt.fit(str(SWEPT_BAR), pd.read_csv(ANGLES), {"k2": (1, 100)})
    for r in (cli, by_path, by_frame):
        assert r.pop("wall_s") > 0.0
    assert by_path == cli and by_frame == cli
    k2 = cli["parameters"][0]
    assert k2["name"] == "k2" and k2["low"] <= 33.0 <= k2["high"] and abs(k2["value"] - 33.0) <= 0.01


def test_a_trajectory_fits_from_python_as_from_the_cli(tmp_path):
    """A DataFrame with t_s rows (the released bar's pin angle at twenty times, read off
    ``tt.run(..., table=True)``) fits k2 from 25 back to the run's 30 N/m within 1e-6, and the
    report is the CLI's on the same rows written as a CSV."""
    import pandas as pd

    released = ROOT / "scenarios" / "custom" / "pinned_bar_large_amplitude.toml"
    ticks = tt.run(str(released), table=True).table.to_pandas()
    ticks = ticks[ticks["motion_time_s"].notna()]
    rows = []
    for k in range(1, 21):
        tick = ticks.iloc[(ticks["motion_time_s"] - 0.1 * k).abs().argmin()]
        rows.append({"point": 0, "output": "joint:pin.angle", "value": tick["joint:pin.angle"],
                     "sigma": 1e-4, "t_s": tick["motion_time_s"]})
    frame = pd.DataFrame(rows)
    py = tt.fit(str(released), frame, ["k2"], set={"k2": 25})
    k2 = py["parameters"][0]
    assert abs(k2["value"] - 30.0) <= 1e-6 * 30.0 and all(r["time_s"] is not None for r in py["residuals"])
    data = tmp_path / "trajectory_rows.csv"
    frame.to_csv(data, index=False, float_format="%.17g")
    cli = cli_json("fit", released, "--data", str(data), "--param", "k2", "--set", "k2=25")
    py.pop("wall_s"), cli.pop("wall_s")
    assert py == cli


def test_fit_from_python_names_the_unidentifiable_pair_as_the_cli_does():
    """k2 and b from the angle atan2(k1 a, k2 b) alone: the one combination names both, with
    weights of magnitude 1/sqrt(2) within 1e-6, both intervals infinite (None, as in the CLI's
    JSON), and the report the CLI's."""
    cli = cli_json("fit", SWEPT_BAR, "--data", str(ANGLES), "--param", "k2", "--param", "b")
    py = tt.fit(str(SWEPT_BAR), ANGLES, ["k2", "b"])
    py.pop("wall_s"), cli.pop("wall_s")
    assert py == cli
    (combination,) = py["unidentifiable"]
    assert sorted(n for n, _ in combination["weights"]) == ["b", "k2"]
    assert all(abs(abs(w) - math.sqrt(0.5)) <= 1e-6 for _, w in combination["weights"])
    # JSON has no infinity: the CLI's JSON and the dict both hold None there.
    assert py["covariance"][0][0] is None and py["parameters"][0]["sigma"] is None and py["parameters"][0]["high"] is None


def test_bad_fit_input_raises_a_clear_python_exception():
    """An unknown parameter (its close names listed), a NaN in the data (its row named), a
    column that names nothing, a negative point, bounds that are not a pair, mixed sigmas, and a
    bound the fit runs into: each a ValueError saying what, none a crash."""
    import pandas as pd

    frame = pd.read_csv(ANGLES)
    with pytest.raises(ValueError, match=r"no parameter 'k3', close names: .*k2"):
        tt.fit(str(SWEPT_BAR), frame, ["k3"])
    nan = frame.copy()
    nan.loc[4, "value"] = float("nan")
    with pytest.raises(ValueError, match=r"data\[4\]: the measured value of q is NaN \(not a finite number\)"):
        tt.fit(str(SWEPT_BAR), nan, ["k2"])
    with pytest.raises(ValueError, match=r"the column 'valeu' names nothing"):
        tt.fit(str(SWEPT_BAR), frame.rename(columns={"value": "valeu"}), ["k2"])
    negative = frame.copy()
    negative.loc[0, "point"] = -1
    with pytest.raises(ValueError, match=r"data\[0\]: point -1 is not a point number"):
        tt.fit(str(SWEPT_BAR), negative, ["k2"])
    with pytest.raises(ValueError, match=r"params\['k2'\] = 3.0: give \(low, high\)"):
        tt.fit(str(SWEPT_BAR), frame, {"k2": 3.0})
    mixed = frame.copy()
    mixed.loc[2, "sigma"] = float("nan")
    with pytest.raises(ValueError, match=r"data\[2\]: no sigma for q, where other rows state one"):
        tt.fit(str(SWEPT_BAR), mixed, ["k2"])
    with pytest.raises(ValueError, match=r"k2 ran into its bound 31"):
        tt.fit(str(SWEPT_BAR), frame, {"k2": (1.0, 31.0)})
    with pytest.raises(ValueError, match=r"has no parameter 'k3'"):
        tt.fit(str(SWEPT_BAR), ANGLES, {"k3": None})


def test_a_million_rows_raise_a_value_error_as_the_clis_data_bound(tmp_path):
    """A 1,000,000-row DataFrame is refused with a ValueError naming the bound, before its rows
    are copied (it aborted the interpreter on an allocation failure); a CSV of one row past the
    bound is refused as the CLI's --data refuses it, at its line."""
    import numpy as np
    import pandas as pd

    bound = tt._tensegrity.MAX_DATA_ROWS
    n = 1_000_000
    frame = pd.DataFrame({"point": np.zeros(n, dtype=np.int64), "output": ["q"] * n, "value": np.zeros(n)})
    with pytest.raises(ValueError, match=rf"data: 1000000 rows: more than {bound} measurement rows"):
        tt.fit(str(SWEPT_BAR), frame, ["k2"])
    csv = tmp_path / "many.csv"
    csv.write_text("point,output,value\n" + "0,q,0.1\n" * (bound + 1))
    with pytest.raises(ValueError, match=rf"many.csv:{bound + 2}:1: more than {bound} measurement rows"):
        tt.fit(str(SWEPT_BAR), csv, ["k2"])


def test_a_column_named_twice_raises_as_the_cli_refuses_it(tmp_path):
    """Data naming ``value`` twice are refused, as a DataFrame and as a CSV's path, each with a
    ValueError naming the column (the DataFrame's rows had been read from the first of the two
    columns, the CLI's from the last)."""
    import pandas as pd

    frame = pd.read_csv(ANGLES)
    twice = pd.concat([frame, frame[["value"]] + 1.0], axis=1)
    assert list(twice.columns).count("value") == 2
    with pytest.raises(ValueError, match=r"data: the column 'value' is named twice"):
        tt.fit(str(SWEPT_BAR), twice, ["k2"])
    csv = tmp_path / "twice.csv"
    csv.write_text("point,output,value,value\n0,q,1,2\n1,q,1,2\n")
    with pytest.raises(ValueError, match=r"twice.csv:1:20: the column 'value' is named twice \(also at column 14\)"):
        tt.fit(str(SWEPT_BAR), csv, ["k2"])


ELASTIC_STRUT = ROOT / "scenarios" / "custom" / "elastic_strut.toml"
BEADED = ROOT / "scenarios" / "custom" / "beaded_string.toml"


def test_elastic_struts_and_heavy_cables_reach_python_as_the_cli():
    """The new keys from Python as from the CLI: the elastic strut's settled force is the CLI's
    bit for bit and F = 2 k a EA / (EA + k L) within 1e-10; EA set from Python
    (set={"EA": 900}) moves it to the closed form's again; its d force/d EA is the CLI's; the
    beaded string's beads and segments are named columns of the per-tick table; a bad segment
    count raises ScenarioError at its line and column."""
    result, cli = tt.run(str(ELASTIC_STRUT)), cli_report(ELASTIC_STRUT)
    force = result.points.iloc[0]["simulated:strut.force"]
    assert force == cli["points"][0]["simulated"]["strut.force"]
    k, a, L = 100.0, 0.2, 1.0
    for ea in (1000.0, 900.0):
        r = result if ea == 1000.0 else tt.run(str(ELASTIC_STRUT), set={"EA": ea})
        want = -2 * k * a * ea / (ea + k * L)
        assert abs(r.points.iloc[0]["simulated:strut.force"] - want) <= 1e-10 * abs(want)
    py, cli = tt.sensitivity(str(ELASTIC_STRUT)), cli_json("sensitivity", ELASTIC_STRUT)
    ea_py = next(p for p in py["parameters"] if p["name"] == "EA")
    ea_cli = next(p for p in cli["parameters"] if p["name"] == "EA")
    assert ea_py["derivatives"] == ea_cli["derivatives"]
    table = tt.run(str(BEADED), table=True).table
    assert "node:string_b1.z" in table.column_names and "cable:string_s6.tension_n" in table.column_names
    bad = BEADED.read_text().replace('segments = "N"', "segments = 0", 1)
    with pytest.raises(tt.ScenarioError) as e:
        tt.check(bad, name="beaded.toml")
    line = bad[: bad.index("segments = 0")].count("\n") + 1
    assert (e.value.line, e.value.col) == (line, 12) and "from 1 to 1000" in e.value.message


def test_a_modes_shape_reaches_python():
    """tt.modes gives each non-rigid mode's shape as the CLI does: the beaded string's lowest
    mode moves bead i by sin(pi i / 6) of the middle bead's displacement (within 1e-9) and its
    anchors not at all."""
    r = tt.modes(str(BEADED))
    shape = dict((name, d) for name, d in r["modes"][0]["node_displacements_m"])
    assert shape["A"] == [0.0, 0.0, 0.0] and shape["B"] == [0.0, 0.0, 0.0]
    middle = shape["string_b3"]
    top = math.hypot(*middle)
    for i in range(1, 6):
        sine = math.sin(math.pi * i / 6)
        assert all(abs(d - sine * m) <= 1e-9 * top for d, m in zip(shape[f"string_b{i}"], middle))


def test_attribute_from_python_is_the_clis_attribute_json():
    """tt.attribute is `tensegrity attribute --json`: every field equal (floats bit for bit), the
    wall times aside; on the hanging bar the elastic cable's share is -M g l / EA_c = -1.962e-2 m
    within 1e-9 m; a file without relaxations raises ValueError, a relaxation of a member that
    does not exist ScenarioError at its table."""
    hanging = ROOT / "tests" / "fixtures" / "attribution" / "hanging_bar.toml"
    py, cli = tt.attribute(str(hanging)), cli_json("attribute", hanging)
    for r in (py, cli):
        for level in r["levels"]:
            level.pop("wall_s")
    assert py == cli
    assert abs(py["items"][0]["shares"][1] + 2.0 * 9.81 * 1.0 / 1e3) <= 1e-9
    text = hanging.read_text()
    with pytest.raises(ValueError, match="no \\[\\[fidelity\\]\\] relaxation"):
        tt.attribute(text[: text.index("[[fidelity]]")], name="bare.toml")
    with pytest.raises(tt.ScenarioError, match="no member 'rod'") as e:
        tt.attribute(text.replace('relax = "rigid struts"', 'relax = "rigid struts"\nmembers = ["rod"]'), name="rod.toml")
    assert e.value.line == text[: text.index('[[fidelity]]\nname = "elastic bar"')].count("\n") + 1


def test_sensitivity_lists_derived_parameters_apart_and_takes_params():
    """tt.sensitivity lists the derived parameters apart (``derived``) and, with ``params``,
    differentiates the named ones alone, as ``--param`` does; an unknown name raises ValueError."""
    strut = ROOT / "scenarios" / "custom" / "elastic_strut.toml"
    full = tt.sensitivity(str(strut))
    assert full["derived"] == ["F", "delta"]
    asked = tt.sensitivity(str(strut), params=["delta", "k"])
    assert [p["name"] for p in asked["parameters"]] == ["delta", "k"]
    assert asked == {**cli_json("sensitivity", strut, "--param", "delta", "--param", "k"), "wall_s": asked["wall_s"]}
    with pytest.raises(ValueError, match="'nope' is not a parameter"):
        tt.sensitivity(str(strut), params=["nope"])
