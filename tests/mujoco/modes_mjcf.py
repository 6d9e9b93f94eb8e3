"""Settles an MJCF file in MuJoCo, linearises it there and prints its natural frequencies.

    python3 tests/mujoco/modes_mjcf.py MODEL.xml --max-time S --speed-tol M_PER_S --window N \
        [--timestep DT] [--eps EPS]

Used by tests/it/modes.rs on the files `tensegrity export mjcf` writes. Settles as
settle_mjcf.py does (the testbed's criterion), then zeroes the velocities and every
`dof_damping` (and the bodies' damping, which the export writes as dof damping too), sets the
timestep (default 1e-4 s) and takes MuJoCo's discrete-time transition matrix A
(`mjd_transitionFD`, centred differences, step eps). Each eigenvalue lambda of A gives a
frequency |Im log(lambda)| / timestep [rad/s]; each mode shows as a conjugate pair, so the
sorted list is halved by taking every other one. The step map's frequency is corrected for
the semi-implicit Euler step's dispersion, w = (2 / dt) sin(w_step dt / 2), exact for a linear
system (MuJoCo's default integrator; the export keeps it).
Output: {"mujoco": version, "settled": bool, "steps": n, "timestep": dt, "integrator": int,
"omega_step_map": [rad/s], "omega": [rad/s, corrected, ascending, one per mode]}.
"""

from __future__ import annotations

import argparse
import json

import mujoco
import numpy as np

from settle_mjcf import apply_loads, settle


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("xml")
    ap.add_argument("--max-time", type=float, required=True)
    ap.add_argument("--speed-tol", type=float, required=True)
    ap.add_argument("--window", type=int, required=True)
    ap.add_argument("--timestep", type=float, default=1e-4)
    ap.add_argument("--eps", type=float, default=1e-6)
    a = ap.parse_args()
    model = mujoco.MjModel.from_xml_path(a.xml)
    data = mujoco.MjData(model)
    key = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, "first_point")
    if key >= 0:
        mujoco.mj_resetDataKeyframe(model, data, key)
    apply_loads(model, data)
    settled, steps = settle(model, data, a.max_time, a.speed_tol, a.window)
    data.qvel[:] = 0.0
    model.dof_damping[:] = 0.0
    model.opt.timestep = a.timestep
    n = 2 * model.nv + model.na
    transition = np.zeros((n, n))
    mujoco.mjd_transitionFD(model, data, a.eps, True, transition, None, None, None)
    lam = np.linalg.eigvals(transition)
    omega = np.sort(np.abs(np.angle(lam))) / a.timestep
    # Each oscillating mode is a conjugate pair; each zero mode a pair of eigenvalues near 1.
    per_mode = omega[::2]
    # MuJoCo's default integrator steps velocities, then positions (semi-implicit Euler): for a
    # linear mode of frequency w its step map turns by theta with cos(theta) = 1 - (w dt)^2 / 2,
    # so the true w = (2 / dt) sin(theta / 2), exactly (../shared/notes/dynamics.md).
    corrected = 2.0 / a.timestep * np.sin(per_mode * a.timestep / 2.0)
    print(
        json.dumps(
            {
                "mujoco": mujoco.__version__,
                "settled": settled,
                "steps": steps,
                "timestep": a.timestep,
                "integrator": int(model.opt.integrator),
                "omega_step_map": per_mode.tolist(),
                "omega": corrected.tolist(),
            }
        )
    )


if __name__ == "__main__":
    main()
