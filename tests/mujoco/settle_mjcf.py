"""Settles an MJCF file in MuJoCo and prints the settled site positions as JSON.

    python3 tests/mujoco/settle_mjcf.py MODEL.xml --max-time S --speed-tol M_PER_S --window N

Used by tests/it/export_mjcf.rs on the files `tensegrity export mjcf` writes: starts from the
keyframe `first_point` when the model has one (the exported point's actuator commands),
applies the constant loads of `<custom><numeric name="load:BODY:i">` at their bodies' centres
of mass, and steps until every site has moved less than speed_tol * dt per step for `window`
consecutive steps (the testbed's settle criterion) or max_time runs out.
Output: {"mujoco": version, "settled": bool, "steps": n, "sites": {name: [x, y, z]}}.
"""

from __future__ import annotations

import argparse
import json

import mujoco
import numpy as np


def apply_loads(model: mujoco.MjModel, data: mujoco.MjData) -> None:
    for i in range(model.nnumeric):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_NUMERIC, i)
        if not name.startswith("load:"):
            continue
        body_name = name.split(":")[1]
        body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body_name)
        adr = model.numeric_adr[i]
        data.xfrc_applied[body, :3] += model.numeric_data[adr : adr + 3]


def settle(model: mujoco.MjModel, data: mujoco.MjData, max_time: float, speed_tol: float, window: int):
    """Steps until every site moves less than speed_tol * dt per step for `window` steps, or
    `max_time` runs out: (settled, steps)."""
    dt = model.opt.timestep
    max_steps = int(np.ceil(max_time / dt))
    mujoco.mj_kinematics(model, data)
    last = data.site_xpos.copy()
    quiet, steps = 0, 0
    limit_sq = (speed_tol * dt) ** 2
    while steps < max_steps:
        mujoco.mj_step(model, data)
        steps += 1
        mujoco.mj_kinematics(model, data)
        now = data.site_xpos
        moved_sq = float(np.max(np.sum((now - last) ** 2, axis=1))) if model.nsite else 0.0
        last = now.copy()
        quiet = quiet + 1 if moved_sq <= limit_sq else 0
        if quiet >= window:
            return True, steps
    return False, steps


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("xml")
    ap.add_argument("--max-time", type=float, required=True)
    ap.add_argument("--speed-tol", type=float, required=True)
    ap.add_argument("--window", type=int, required=True)
    a = ap.parse_args()
    model = mujoco.MjModel.from_xml_path(a.xml)
    data = mujoco.MjData(model)
    key = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, "first_point")
    if key >= 0:
        mujoco.mj_resetDataKeyframe(model, data, key)
    apply_loads(model, data)
    settled, steps = settle(model, data, a.max_time, a.speed_tol, a.window)
    sites = {
        mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_SITE, i): data.site_xpos[i].tolist() for i in range(model.nsite)
    }
    print(json.dumps({"mujoco": mujoco.__version__, "settled": settled, "steps": steps, "sites": sites}))


if __name__ == "__main__":
    main()
