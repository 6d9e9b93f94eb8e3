#!/usr/bin/env python3
"""MuJoCo peer of the testbed's settle benchmark (issue #11).

    python3 peer.py CASES.json [--variant tuned|usual] [--rounds N]

CASES.json is a case set written by `tensegrity bench --export-cases DIR`. For each case the
peer sets the inputs, starts from the testbed's start state (`start_nodes`), steps until it
is settled by the testbed's criterion, reads the checked quantities and scores them with the
testbed's error measure. One JSON object goes to stdout (see README.md).
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import mujoco
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from models import MECHANISMS, MechanismPeer, SolverSettings  # noqa: E402

#: The testbed's start state must be reproduced to this fraction of the length scale.
START_MATCH_TOL_OF_LENGTH_SCALE = 1e-12


# --------------------------------------------------------------------------------------------
# Variants: MuJoCo's usual settings, and the settings tuned for this benchmark (README.md
# documents what was tried and measured).
# --------------------------------------------------------------------------------------------

#: MuJoCo's defaults (Euler, Newton with tolerance 1e-8, solref 0.02 1, solimp 0.9 0.95
#: 0.001 0.5 2), with the case set's time step and damping (the testbed's).
USUAL: dict = {}

#: Tuned per mechanism (README.md: what was tried and measured).
TUNED = {
    # No constraint rows at all (the actuator is placed, the springs are passive tendons): only
    # the time step and the damping matter. The fewest steps with every case settled, and
    # every case still settled at 100 or 120 N m s/rad or at dt 0.1 or 0.12 s (overdamped;
    # the same dt and damping as the testbed's scenario since 283c379).
    "ji2014": dict(integrator="implicitfast", timestep_s=0.15, joint_damping_nms_per_rad=80.0),
    # Cables and loop closures are soft constraints whose equilibrium offset is about
    # (1 - d) timeconst^2 x load / mass: the highest impedance d MuJoCo allows (0.9999), the
    # smallest timeconst refsafe allows (2 dt, critically damped), and dt traded against
    # steps (error ~ dt^2). Cable damping (zero at rest) stops the chatter of nearly slack
    # cables, which otherwise never settle.
    "mohr2011": dict(
        integrator="implicitfast",
        timestep_s=0.003,
        tolerance=1e-10,
        solref=(0.006, 1.0),
        solimp=(0.9999, 0.9999, 0.001, 0.5, 2.0),
        joint_damping_nms_per_rad=4.0,
        cable_damping_n_s_per_m=10.0,
    ),
}


def settings_for(mechanism: str, variant: str, dt_s: float, overrides: dict) -> SolverSettings:
    fields = dict(USUAL if variant == "usual" else TUNED[mechanism])
    fields.setdefault("timestep_s", dt_s)
    fields.update(overrides)
    return SolverSettings(**fields)


# --------------------------------------------------------------------------------------------
# Settle criterion and error measure: exactly the testbed's
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SettleCriterion:
    """Every node's speed (its displacement over one step / dt) at most `speed_tol_m_per_s`
    for `window_steps` consecutive steps; give up after `max_time_s` of simulated time."""

    speed_tol_m_per_s: float
    window_steps: int
    max_time_s: float


def settle(peer: MechanismPeer, criterion: SettleCriterion, dt_s: float) -> tuple[int, bool]:
    """Steps until settled. Returns (mj_step calls, settled).

    After `mj_step`, `data` holds the forward pass of the state the step started from, so the
    node positions seen after step k are those of state k-1: the speeds are the testbed's, one
    step late, and the state read at the end is the one that was checked (its forces come
    from the same forward pass)."""
    m, d = peer.model, peer.data
    step = mujoco.mj_step
    max_steps = math.ceil(criterion.max_time_s / dt_s)
    # Squared displacements per step against (speed_tol dt)^2: no sqrt, no division.
    limit_m2 = (criterion.speed_tol_m_per_s * dt_s) ** 2
    nodes = peer.node_positions()  # a view into data: always the latest forward pass
    node_count = nodes.shape[0]
    previous = np.empty_like(nodes)
    moved = np.empty_like(nodes)
    moved_flat = moved.reshape(-1)
    window = criterion.window_steps
    step(m, d)
    np.copyto(previous, nodes)  # the first state has no speed, as in the testbed
    quiet_steps = 0
    for k in range(2, max_steps + 1):
        step(m, d)
        np.subtract(nodes, previous, out=moved)
        np.copyto(previous, nodes)
        # The largest node displacement decides. The sum of the squares over the nodes
        # bounds it from both sides (max <= sum <= n max), so one dot product decides most
        # steps; only a sum between the bounds needs the per-node maximum.
        total_m2 = moved_flat.dot(moved_flat)
        if total_m2 <= limit_m2:
            quiet = True
        elif total_m2 > node_count * limit_m2:
            quiet = False
        else:
            quiet = float(np.max(np.sum(moved * moved, axis=1))) <= limit_m2
        if quiet:
            quiet_steps += 1
            if quiet_steps >= window:
                return k, True
        else:
            quiet_steps = 0
    return max_steps, False


def wrap_to_pi(angle_rad: float) -> float:
    return math.atan2(math.sin(angle_rad), math.cos(angle_rad))


def error(kind: str, simulated: float, analytic: float, length_scale_m: float) -> float:
    """The testbed's normalised error of one checked quantity."""
    if kind == "length":
        return abs(simulated - analytic) / length_scale_m
    if kind == "angle":
        return abs(wrap_to_pi(simulated - analytic))
    if kind == "magnitude":
        return abs(simulated - analytic) / abs(analytic) if analytic != 0.0 else math.inf
    raise ValueError(f"unknown check kind {kind!r}")


# --------------------------------------------------------------------------------------------
# The benchmark
# --------------------------------------------------------------------------------------------


def run_case(peer: MechanismPeer, case: dict, criterion: SettleCriterion, dt_s: float):
    """One timed case: reset, inputs, start state, settle, read. Returns (steps, settled,
    values, wall_s)."""
    t0 = time.perf_counter()
    peer.set_case(case["inputs"], case["start_nodes"])
    steps, settled = settle(peer, criterion, dt_s)
    values = peer.observe()
    return steps, settled, values, time.perf_counter() - t0


def bench(case_set: dict, variant: str, rounds: int, min_round_wall_s: float, overrides: dict) -> dict:
    mechanism = case_set["mechanism"]
    settings = settings_for(mechanism, variant, case_set["dt_s"], overrides)
    peer = MECHANISMS[mechanism](case_set["params"], settings)
    criterion = SettleCriterion(
        speed_tol_m_per_s=case_set["speed_tol_m_per_s"],
        window_steps=case_set["window_steps"],
        max_time_s=case_set["max_time_s"],
    )
    scale_m = case_set["length_scale_m"]
    cases = case_set["cases"]

    # Untimed: every start state must be the testbed's.
    for i, case in enumerate(cases):
        peer.set_case(case["inputs"], case["start_nodes"])
        mismatch = peer.start_mismatch_m(case["start_nodes"])
        if mismatch > START_MATCH_TOL_OF_LENGTH_SCALE * scale_m:
            raise SystemExit(f"case {i}: start state off the testbed's by {mismatch:.3e} m")

    per_case_wall = [[] for _ in cases]
    first_round = []
    round_rates, round_us_per_step = [], []
    for r in range(rounds):
        # Passes over the case set until they add up to min_round_wall_s (as the testbed times
        # its rounds): one pass of a fast case set is only about 10 ms.
        wall_total, steps_total, cases_total = 0.0, 0, 0
        while cases_total == 0 or wall_total < min_round_wall_s:
            for i, case in enumerate(cases):
                steps, settled, values, wall = run_case(peer, case, criterion, settings.timestep_s)
                wall_total += wall
                steps_total += steps
                per_case_wall[i].append(wall)
                if r == 0 and cases_total == 0:
                    first_round.append((steps, settled, values))
            cases_total += len(cases)
        round_rates.append(cases_total / wall_total)
        round_us_per_step.append(wall_total * 1e6 / max(steps_total, 1))

    out_cases, pooled_errors = [], []
    for i, (case, (steps, settled, values)) in enumerate(zip(cases, first_round)):
        errors = {
            c["quantity"]: error(c["kind"], values[c["quantity"]], case["analytic"][c["quantity"]], scale_m)
            for c in case_set["checks"]
        }
        pooled_errors.extend(errors.values())
        out_cases.append(
            {
                "inputs": case["inputs"],
                "steps": steps,
                "wall_s": statistics.median(per_case_wall[i]),
                "settled": settled,
                "errors": errors,
            }
        )
    return {
        "simulator": "mujoco",
        "mechanism": mechanism,
        "variant": variant,
        "mujoco_version": mujoco.__version__,
        "rounds": rounds,
        "settings": asdict(settings),
        "cases": out_cases,
        "all_settled": all(c["settled"] for c in out_cases),
        "median_cases_per_s": statistics.median(round_rates),
        "median_steps_per_case": statistics.median(c["steps"] for c in out_cases),
        "median_us_per_step": statistics.median(round_us_per_step),
        "median_error": statistics.median(pooled_errors),
        "max_error": max(pooled_errors),
    }


def finite_or_null(value):
    """`value` with every non-finite float replaced by None (JSON null), recursively."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: finite_or_null(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite_or_null(v) for v in value]
    return value


def parse_override(text: str) -> tuple[str, object]:
    """`--set name=value` for trying settings: a number, a tuple `a,b,...` or a word."""
    name, value = text.split("=", 1)
    if "," in value:
        return name, tuple(float(v) for v in value.split(","))
    for cast in (int, float):
        try:
            return name, cast(value)
        except ValueError:
            pass
    if value in ("true", "false"):
        return name, value == "true"
    return name, value


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("cases", type=Path, help="case set JSON from `tensegrity bench --export-cases DIR`")
    ap.add_argument("--variant", choices=("tuned", "usual"), default="tuned")
    ap.add_argument("--rounds", type=int, default=5, help="timed rounds; rates are medians over rounds")
    ap.add_argument(
        "--min-round-wall-s",
        type=float,
        default=0.0,
        help="a round repeats passes over the case set until they add up to this wall time [s]",
    )
    ap.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="override one SolverSettings field (for tuning), e.g. --set timestep_s=0.005",
    )
    args = ap.parse_args()
    case_set = json.loads(args.cases.read_text())
    overrides = dict(parse_override(s) for s in args.set)
    result = bench(case_set, args.variant, max(1, args.rounds), args.min_round_wall_s, overrides)
    # Strict JSON (a diverged case would give NaN or infinity): such numbers become null.
    json.dump(finite_or_null(result), sys.stdout, indent=1, allow_nan=False)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
