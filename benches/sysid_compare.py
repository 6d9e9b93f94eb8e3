"""`tensegrity fit` against MuJoCo's `mujoco.sysid` on the same structure and the same data.

The problem: the pinned bar of scenarios/custom/pinned_bar_sweep.toml (a bar pinned at O between
two zero-length springs, k1 swept over 10 .. 90 N/m at nine settle points), k2 fitted from the
bar's equilibrium angle q at the nine points, tests/fixtures/fit/pinned_bar_angles.csv (k2 = 33
N/m, a deterministic noise below 1e-4 rad, sigma 1e-4 rad), from the file's k2 = 30 within
[1, 100] N/m.

The testbed: `tensegrity fit ... --param k2=1:100 --json -`, Levenberg-Marquardt on the settled
states with the Jacobian from the implicit function theorem, 95 % interval value -+ 1.96 sigma,
sigma from (J^T J)^-1 (the rows state their sigma: not scaled).

MuJoCo: the structure exported by `tensegrity export mjcf` (springs as tendons), one MjSpec per
settle point with tendon s1's stiffness set to that point's k1, k2 a `sysid.Parameter` whose
modifier sets tendon s2's stiffness; `sysid.optimize` (its default backend, MuJoCo's
`minimize.least_squares`, with its finite-difference Jacobian) on the same weighted residuals
(q_model - q_measured) / sigma, and `sysid.calculate_intervals` on the Jacobian at the optimum
(which scales by chi^2 / dof and takes Student's t: the half-width is reported as sysid gives
it and also rescaled to the testbed's convention). What differs: sysid identifies from
trajectories (sensor time series under controls); measurements of settled states have no time
series, so its trajectory residual (`sysid.residual`) cannot express them, and the residual here
is a custom one that settles each point by a rollout of the exported model (`mujoco.rollout`,
the nine points a batch on one thread a core as the testbed's fit uses; its damping as exported,
SETTLE_STEPS steps of its time step, qvel below 1e-12 checked) and reads the angle from the
sites. Everything else (the parameter, its modifier, the optimizer, the intervals) is
sysid's.

Run from the repository root, with mujoco 4.x and sysid's extras (`pip install 'mujoco[sysid]'`,
or absl-py, colorama, pyyaml, scipy, tabulate beside mujoco) and the release binary built:

    python benches/sysid_compare.py [--tensegrity target/release/tensegrity]

It prints both estimates, intervals and wall times as JSON on standard output.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import json
import math
import os
import subprocess
import sys
import time

import mujoco
import numpy as np
from mujoco import rollout, sysid

SCENARIO = "scenarios/custom/pinned_bar_sweep.toml"
DATA = "tests/fixtures/fit/pinned_bar_angles.csv"
K1 = [10.0 + 10.0 * i for i in range(9)]
K2_START, K2_LOW, K2_HIGH = 30.0, 1.0, 100.0
SETTLE_STEPS = 2500  # the fewest of 1500, 2000, 2500, 3000 that bring qvel below 1e-12 (the angle then exact to 2.2e-16)
# MuJoCo's rollout threads: as many as the testbed's fit settles points on (one a core).
THREADS = os.cpu_count() or 1
Z_95 = 1.959963984540054


def testbed(binary: str) -> tuple[dict, float]:
    """The testbed's fit as its JSON report, and the command's wall time [s]."""
    command = [binary, "fit", SCENARIO, "--data", DATA, "--param", f"k2={K2_LOW:g}:{K2_HIGH:g}", "--json", "-"]
    start = time.perf_counter()
    out = subprocess.run(command, capture_output=True, text=True, check=True)
    return json.loads(out.stdout), time.perf_counter() - start


def measured() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(points, angles, sigmas) of the data."""
    with open(DATA, newline="") as f:
        rows = [r for r in csv.DictReader(f)]
    assert all(r["output"] == "q" for r in rows)
    return (np.array([int(r["point"]) for r in rows]), np.array([float(r["value"]) for r in rows]),
            np.array([float(r["sigma"]) for r in rows]))


def exported(binary: str) -> str:
    """The MJCF of `tensegrity export mjcf` (the first point's structure: k1 = 10 N/m)."""
    out = subprocess.run([binary, "export", "mjcf", SCENARIO, "--out", "-"], capture_output=True, text=True, check=True)
    return out.stdout


def settled_angles(models: list, datas: list) -> list:
    """The bar's angle atan2(P.y - A.y, P.x - A.x) of each model after SETTLE_STEPS steps from
    its drawn state: one `mujoco.rollout` of the batch (C, on the threads of `datas`)."""
    full = mujoco.mjtState.mjSTATE_FULLPHYSICS
    data = datas[0]
    initial = []
    for m in models:
        d = mujoco.MjData(m)
        state = np.empty(mujoco.mj_stateSize(m, full))
        mujoco.mj_getState(m, d, state, full)
        initial.append(state)
    states, _ = rollout.rollout(models, datas, np.array(initial), nstep=SETTLE_STEPS)
    angles = []
    for m, final in zip(models, states[:, -1, :]):
        mujoco.mj_setState(m, data, final, full)
        if np.max(np.abs(data.qvel)) > 1e-12:
            raise RuntimeError(f"MuJoCo did not settle in {SETTLE_STEPS} steps: qvel {data.qvel}")
        mujoco.mj_kinematics(m, data)
        p, a = data.site("P").xpos, data.site("A").xpos
        angles.append(math.atan2(p[1] - a[1], p[0] - a[0]))
    return angles


def mujoco_sysid(xml: str) -> dict:
    """sysid's fit of k2 on the exported structure: estimate, intervals, steps, wall time."""
    points, values, sigmas = measured()

    def set_k2(spec: mujoco.MjSpec, param: sysid.Parameter) -> None:
        spec.tendon("s2").stiffness = [float(param.value[0]), 0.0, 0.0]  # (linear, higher orders) in MuJoCo 4

    params = sysid.ParameterDict({"k2": sysid.Parameter("k2", K2_START, K2_LOW, K2_HIGH, modifier=set_k2)})
    specs = []
    for k1 in K1:
        spec = mujoco.MjSpec.from_string(xml)
        spec.tendon("s1").stiffness = [k1, 0.0, 0.0]
        specs.append(spec)
    evaluations = [0]

    def residual_fn(x, p):
        x = np.asarray(x, dtype=float)
        columns = x.reshape(-1, 1) if x.ndim == 1 else x
        out = np.empty((len(values), columns.shape[1]))
        for c in range(columns.shape[1]):
            p.update_from_vector(columns[:, c])
            models = [sysid.apply_param_modifiers(p, spec.copy()) for spec in specs]
            angles = settled_angles(models, [mujoco.MjData(models[0]) for _ in range(THREADS)])
            out[:, c] = [(angles[i] - v) / s for i, v, s in zip(points, values, sigmas)]
            evaluations[0] += 1
        return [out[:, 0] if x.ndim == 1 else out], None, None

    start = time.perf_counter()
    with contextlib.redirect_stdout(sys.stderr):  # the backend's iteration log
        best, result = sysid.optimize(params, residual_fn, verbose=False)
    wall = time.perf_counter() - start
    k2 = float(best["k2"].value[0])
    residuals, _, _ = residual_fn(np.array([k2]), best.copy())
    jac = np.asarray(result.jac, dtype=float).reshape(len(values), 1)
    _, half = sysid.calculate_intervals(residuals, jac)
    chi2 = float(np.dot(residuals[0], residuals[0]))
    dof = len(values) - 1
    # sysid's half-width: t(dof, 0.975) sqrt(chi2 / dof (J^T J)^-1); the testbed's: 1.96 sqrt((J^T J)^-1).
    unscaled = float(half[0]) / math.sqrt(chi2 / dof) * Z_95 / float(_student_t_975(dof))
    return {"k2": k2, "half_width_sysid": float(half[0]), "half_width_testbed_convention": unscaled,
            "chi2": chi2, "residual_evaluations": evaluations[0], "wall_s": wall,
            "settle_steps_per_point": SETTLE_STEPS, "timestep_s": specs[0].option.timestep, "threads": THREADS}


def _student_t_975(dof: int) -> float:
    import scipy.special

    return float(scipy.special.stdtrit(dof, 0.975))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tensegrity", default=os.path.join(os.environ.get("CARGO_TARGET_DIR", "target"),
                                                             "release", "tensegrity"))
    args = parser.parse_args()
    ours, ours_wall = testbed(args.tensegrity)
    theirs = mujoco_sysid(exported(args.tensegrity))
    k2 = ours["parameters"][0]
    ours_half = k2["high"] - k2["value"]
    result = {
        "mujoco": mujoco.__version__,
        "testbed": {"k2": k2["value"], "half_width": ours_half, "chi2": ours["chi2"], "iterations": ours["iterations"],
                    "fit_wall_s": ours["wall_s"], "command_wall_s": ours_wall},
        "sysid": theirs,
        "difference": theirs["k2"] - k2["value"],
        "sysid_estimate_in_testbed_interval": abs(theirs["k2"] - k2["value"]) <= ours_half,
        "testbed_estimate_in_sysid_interval": abs(theirs["k2"] - k2["value"]) <= theirs["half_width_sysid"],
        "sysid_wall_over_testbed_fit_wall": theirs["wall_s"] / ours["wall_s"],
    }
    json.dump(result, sys.stdout, indent=2)
    print()
    return 0 if result["sysid_estimate_in_testbed_interval"] and result["testbed_estimate_in_sysid_interval"] else 1


if __name__ == "__main__":
    sys.exit(main())
