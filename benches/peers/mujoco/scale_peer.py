#!/usr/bin/env python3
"""MuJoCo peer of the testbed's scale benchmark (`tensegrity bench --scale --peer`, issue #21).

    python3 scale_peer.py CASES.json [--set NAME=VALUE ...]

CASES.json is written by the testbed (`src/bench/scale/peer.rs`): a list of cases, each with
the MJCF file the testbed exported for the case's perturbed start (`tensegrity export mjcf`'s
writer), the time step, the testbed's settle criterion (node speed below `speed_tol_m_per_s`
for `window_steps` steps), its caps (`max_steps`, `max_wall_s`), the sites to score and their
closed-form positions (`nodes`, `target`), the error measure (`measure`: "aligned" = largest
site distance after the best rigid alignment, Kabsch; "absolute"; "twist" = the n-strut prism's
largest |twist - (pi/2 + pi/n)| with bottom node i at 2 i and top node i at 2 i + 1) and the
mocap bodies to turn to their actuator command (`mocap`: body, axis, angle_rad about the
body's frame origin, the joint's anchor; MJCF draws them at the start pose).

Settings (MuJoCo's, as the mechanism peer's `tuned` variant, README.md): the MJCF as
exported: `implicitfast` integrator, solver tolerance 1e-10, free joints damped at the
testbed's body damping times the body's mass (zero at rest), elastic cables as tendons with
the dead band `springlength="0 L"`, springs as tendons, loop closures and actuated joints on
moving parents as soft equalities at MuJoCo's stiffest impedance (solimp 0.9999) and
timeconst 2 dt; the time step per family in TUNED. `--set timestep_s=...` /
`--set damping_scale=...` override the time step / scale every joint damping (for tuning).

With a "motion" entry in CASES.json (`tensegrity bench --scale --motion --peer`), each case
is moved instead, undamped, for `duration_s` at each of `dts` and once with RK4 at
`reference_dt_s` (`motion_case`); the node sites at the end of each run go back with the wall
time of its steps. With `integrator_dts` as well, the same motion is run with RK4 and with
Euler at each of those steps (`rk4_runs`, `euler_runs`: the testbed compares its judged motion
with them at equal stepping time). A case's `spin` (a body's name and its angular velocity
[rad/s], world axes) starts that body's free joint spinning (its frame has the world's axes at
the start, so the local angular velocity of `qvel` is the world one); its reference is the
exact torque-free motion at 30 digits (`torque_free_sites`) instead of RK4's. A case's `drive`
(a slide's body, axis, stroke and rate of x(t) = A sin(w t / 2)^4) is run in the slide's frame
(`set_drive`), its reference the exact motion of the one hinged body it carries
(`driven_hinge_sites`).

Each case is timed from loading the XML (model compile) to the settled state, as the testbed
times building its simulation and settling it; a case faster than 0.2 s is run again until
the runs add up to 0.2 s and its median is reported (as the testbed does). One JSON object goes to stdout:
{"simulator", "mujoco_version", "settings", "cases": [{"family", "size", "steps", "settled",
"wall_s", "compile_s", "error", "note"}]}.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time

import mpmath
import mujoco
import numpy as np


#: Tuned per family (measured on prisms 3-16, the icosahedron and towers of 1-4 stages, steps
#: to settle by the testbed's criterion): implicitfast damps the free bodies implicitly, so a
#: longer step settles in fewer steps: dt 0.005 -> 0.01 -> 0.02 -> 0.04 s took prism 8 from
#: 4031 to 2026, 1024 and 545 steps (icosahedron from 2971 at 0.002 s to 180); dt 0.08 s
#: diverged on every case. Damping x0.5 or x3 at dt 0.04 or 0.005 s took as many steps or
#: more. furet keeps the testbed's dt 0.005 s: its loop closures are soft constraints of
#: timeconst 2 dt, whose offset grows with dt (error 7e-7 m at 1 module already).
TUNED = {
    "prism": {"timestep_s": 0.04},
    "icosahedron": {"timestep_s": 0.04},
    "tower": {"timestep_s": 0.04},
    "furet": {},
}


#: Digits of the spin's exact reference (`torque_free_sites`).
EXACT_DIGITS = 30

#: A case faster than this is run again until the runs add up to it; its wall time is the
#: median (the testbed's MIN_CASE_WALL_S).
MIN_CASE_WALL_S = 0.2


def turn_mocap(model: mujoco.MjModel, data: mujoco.MjData, turns: list[dict]) -> None:
    """Turns each listed mocap body by its angle about its axis (through its frame origin)."""
    for t in turns:
        body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, t["body"])
        mocap = model.body_mocapid[body]
        if body < 0 or mocap < 0:
            raise SystemExit(f"{t['body']} is not a mocap body")
        axis = np.asarray(t["axis"], dtype=float)
        axis /= np.linalg.norm(axis)
        half = 0.5 * t["angle_rad"]
        turn = np.concatenate([[math.cos(half)], math.sin(half) * axis])
        out = np.empty(4)
        mujoco.mju_mulQuat(out, turn, data.mocap_quat[mocap])
        data.mocap_quat[mocap] = out


def settle(model, data, sites, case) -> tuple[int, bool, str | None]:
    """Steps until every scored site and every other site moved less than speed_tol * dt per
    step for `window_steps` steps (the testbed's criterion; `site_xpos` after `mj_step` is the
    state the step started from, one step late), or a cap is reached."""
    dt = model.opt.timestep
    limit_m2 = (case["speed_tol_m_per_s"] * dt) ** 2
    start = time.perf_counter()
    mujoco.mj_step(model, data)
    previous = data.site_xpos.copy()
    quiet = 0
    for k in range(2, case["max_steps"] + 1):
        mujoco.mj_step(model, data)
        moved = data.site_xpos - previous
        np.copyto(previous, data.site_xpos)
        if float(np.max(np.einsum("ij,ij->i", moved, moved))) <= limit_m2:
            quiet += 1
            if quiet >= case["window_steps"]:
                return k, True, None
        else:
            quiet = 0
        if k % 100 == 0 and time.perf_counter() - start > case["max_wall_s"]:
            return k, False, f"wall cap {case['max_wall_s']} s reached"
        if not np.all(np.isfinite(data.qpos)):
            return k, False, "diverged (non-finite state)"
    return case["max_steps"], False, f"step cap {case['max_steps']} reached"


def aligned_distance(a: np.ndarray, b: np.ndarray) -> float:
    ca, cb = a.mean(axis=0), b.mean(axis=0)
    h = (a - ca).T @ (b - cb)
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(vt.T @ u.T))
    r = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return float(np.max(np.linalg.norm((a - ca) @ r.T + cb - b, axis=1)))


def twist_error(p: np.ndarray) -> float:
    n = len(p) // 2
    bottom, top = p[0::2], p[1::2]
    cb, ct = bottom.mean(axis=0), top.mean(axis=0)
    axis = (ct - cb) / np.linalg.norm(ct - cb)
    flat = lambda v: v - np.outer(v @ axis, axis)  # noqa: E731
    u, w = flat(bottom - cb), flat(top - ct)
    twist = np.arctan2(np.cross(u, w) @ axis, np.einsum("ij,ij->i", u, w))
    return float(np.max(np.abs(twist - (math.pi / 2 + math.pi / n))))


def error(measure: str, settled: np.ndarray, target: np.ndarray) -> float:
    if measure == "aligned":
        return aligned_distance(settled, target)
    if measure == "absolute":
        return float(np.max(np.linalg.norm(settled - target, axis=1)))
    if measure == "twist":
        return twist_error(settled)
    raise ValueError(f"unknown measure {measure!r}")


def run_case(case: dict, overrides: dict) -> dict:
    overrides = {**TUNED.get(case["family"], {}), **overrides}
    t0 = time.perf_counter()
    model = mujoco.MjModel.from_xml_path(case["mjcf"])
    if "timestep_s" in overrides:
        model.opt.timestep = overrides["timestep_s"]
    if "damping_scale" in overrides:
        model.dof_damping[:] *= overrides["damping_scale"]
    data = mujoco.MjData(model)
    turn_mocap(model, data, case.get("mocap", []))
    compile_s = time.perf_counter() - t0
    sites = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, n) for n in case["nodes"]]
    steps, settled, note = settle(model, data, sites, case)
    mujoco.mj_kinematics(model, data)  # the final state's own site positions
    wall_s = time.perf_counter() - t0
    err = error(case["measure"], data.site_xpos[sites].copy(), np.asarray(case["target"], dtype=float))
    return {
        "family": case["family"],
        "size": case["size"],
        "steps": steps,
        "settled": settled,
        "wall_s": wall_s,
        "compile_s": compile_s,
        "timestep_s": model.opt.timestep,
        "error": err if math.isfinite(err) else None,
        "note": note,
    }


def motion_positions(model, data, sites, steps: int, case: dict | None = None) -> tuple[np.ndarray, float]:
    """Steps `steps` times from the model's initial state; the sites at the end (in the world:
    a driven case's moved by its slide) and the wall time of the steps alone. A driven case's
    wall is that of the same steps without the control callback: the callback is Python, called
    at every RK4 stage, a cost that MuJoCo's own step does not have."""
    t0 = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(model, data)
    wall_s = time.perf_counter() - t0
    mujoco.mj_kinematics(model, data)
    sites_now = data.site_xpos[sites].copy()
    if case is not None and case.get("drive"):
        sites_now += drive_shift(model, data, sites, case)
        mujoco.set_mjcb_control(None)
        data2 = mujoco.MjData(model)
        t0 = time.perf_counter()
        for _ in range(steps):
            mujoco.mj_step(model, data2)
        wall_s = time.perf_counter() - t0
        set_drive(model, case)
    return sites_now, wall_s


def drive_position(drive: dict, t: float) -> float:
    """The driven slide's position at time `t` [m]: x(t) = A sin(w t / 2)^4."""
    return drive["stroke_m"] * math.sin(0.5 * drive["rad_per_s"] * t) ** 4


def drive_acceleration(drive: dict, t: float) -> float:
    """Its acceleration [m/s^2]: x'' = (A w^2 / 2) (cos w t - cos 2 w t)."""
    a, w = drive["stroke_m"], drive["rad_per_s"]
    return 0.5 * a * w * w * (math.cos(w * t) - math.cos(2.0 * w * t))


def carried_bodies(model, root: int) -> list:
    """The bodies below `root` in the kinematic tree, `root` excluded."""
    return [b for b in range(model.nbody) if b != root and is_below(model, b, root)]


def is_below(model, body: int, root: int) -> bool:
    while body != 0:
        if body == root:
            return True
        body = model.body_parentid[body]
    return False


def set_drive(model, case: dict) -> None:
    """A driven case's slide, in the frame it moves: the export makes the slide's body a mocap
    body (MuJoCo holds no joint to a prescribed path inside RK4), left where it is drawn; every
    body it carries feels the frame's fictitious force -m x''(t) along the slide, at its centre
    of mass, set at each evaluation of the dynamics (each RK4 stage, at its time) by MuJoCo's
    control callback. The sites are moved by x(t) along the slide afterwards (`drive_shift`).
    The same equations as the testbed's cart on its slide; MuJoCo's RK4 is fourth order on them
    (measured 6.2e-10, 3.9e-11, 2.4e-12 m at 4, 2, 1 ms)."""
    drive = case.get("drive")
    if not drive:
        mujoco.set_mjcb_control(None)
        return
    root = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, drive["body"])
    carried = carried_bodies(model, root)
    axis = np.array(drive["axis"], dtype=float)

    def fictitious(m, d):
        a = drive_acceleration(drive, d.time)
        for b in carried:
            d.xfrc_applied[b, :3] = -m.body_mass[b] * a * axis

    mujoco.set_mjcb_control(fictitious)


def drive_shift(model, data, sites: list, case: dict) -> np.ndarray:
    """What moves each of a driven case's sites from the slide's frame to the world's at the
    data's time: x(t) along the slide for the sites on the slide's body and the bodies it
    carries, nothing for the others (the ground's)."""
    drive = case["drive"]
    root = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, drive["body"])
    shift = drive_position(drive, data.time) * np.array(drive["axis"], dtype=float)
    moved = [is_below(model, model.site_bodyid[site], root) for site in sites]
    return np.array([shift if m else np.zeros(3) for m in moved])


def spun(model, data, case: dict) -> None:
    """Sets the angular velocity of the case's spinning body's free joint, if any."""
    spin = case.get("spin")
    if spin:
        body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, spin["body"])
        dof = model.jnt_dofadr[model.body_jntadr[body]]
        data.qvel[dof + 3 : dof + 6] = spin["angular_velocity"]


def quat_matrix(q) -> list:
    """The rotation matrix (rows) of MuJoCo's quaternion (w, x, y, z), in mpmath numbers."""
    w, x, y, z = (mpmath.mpf(float(c)) for c in q)
    return [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]


def matmul(a, b) -> list:
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def transpose(a) -> list:
    return [[a[j][i] for j in range(3)] for i in range(3)]


def torque_free_sites(model, case: dict, sites: list, duration: float) -> np.ndarray:
    """The exact sites of the case's spinning body after `duration` [m]: the body is the case's
    only one, free, with no force on it, so its motion is Euler's equations in its principal
    frame, I1 w1' = (I2 - I3) w2 w3 (and cyclic), with R' = R [w]x, integrated by mpmath's Taylor
    method at EXACT_DIGITS digits. MuJoCo's RK4 at the reference step carries a round-off of its
    own of about 1e-14 m (measured against this), the level at which the spin is compared."""
    mpmath.mp.dps = EXACT_DIGITS
    body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, case["spin"]["body"])
    inertia = [mpmath.mpf(float(i)) for i in model.body_inertia[body]]
    to_principal = quat_matrix(model.body_iquat[body])  # principal axes in the body frame
    start = quat_matrix(model.body_quat[body])  # body frame in the world at the start
    w_local = [mpmath.mpf(float(c)) for c in case["spin"]["angular_velocity"]]
    w0 = [sum(to_principal[k][i] * w_local[k] for k in range(3)) for i in range(3)]

    def rates(_t, y):
        w, r = y[:3], [y[3:6], y[6:9], y[9:12]]
        i1, i2, i3 = inertia
        dw = [(i2 - i3) * w[1] * w[2] / i1, (i3 - i1) * w[2] * w[0] / i2, (i1 - i2) * w[0] * w[1] / i3]
        skew = [[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]]
        return dw + [x for row in matmul(r, skew) for x in row]

    tolerance = mpmath.mpf(10) ** (-EXACT_DIGITS)
    y = mpmath.odefun(rates, 0, w0 + [1, 0, 0, 0, 1, 0, 0, 0, 1], tol=tolerance, degree=EXACT_DIGITS)(duration)
    turned = [y[3:6], y[6:9], y[9:12]]
    # The body's frame in the world: start * P * turned * P^T (P: principal axes in the body).
    frame = matmul(matmul(matmul(start, to_principal), turned), transpose(to_principal))
    origin = [mpmath.mpf(float(c)) for c in model.body_pos[body]]
    ipos = [mpmath.mpf(float(c)) for c in model.body_ipos[body]]
    com = [origin[i] + sum(start[i][k] * ipos[k] for k in range(3)) for i in range(3)]  # at rest
    out = []
    for site in sites:
        if model.site_bodyid[site] != body:
            raise ValueError("a spin case's sites must all be on its spinning body")
        arm = [mpmath.mpf(float(c)) - o for c, o in zip(model.site_pos[site], ipos)]
        out.append([float(com[i] + sum(frame[i][k] * arm[k] for k in range(3))) for i in range(3)])
    return np.array(out)


def rotated(axis: list, angle, v: list) -> list:
    """v turned by `angle` about the unit `axis` (Rodrigues), in mpmath numbers."""
    c, s_ = mpmath.cos(angle), mpmath.sin(angle)
    dot = sum(a * b for a, b in zip(axis, v))
    cross = [axis[1] * v[2] - axis[2] * v[1], axis[2] * v[0] - axis[0] * v[2], axis[0] * v[1] - axis[1] * v[0]]
    return [v[i] * c + cross[i] * s_ + axis[i] * dot * (1 - c) for i in range(3)]


def driven_hinge_sites(model, case: dict, sites: list, duration: float) -> np.ndarray | None:
    """The exact sites of a driven case whose slide carries one body on one hinge, after
    `duration` [m], or None for any other driven case. In the slide's frame the body turns about
    the hinge under gravity and the fictitious force: I_n theta'' = n . (r(theta) x m (g - x''(t)
    e)), I_n its moment about the hinge axis n, r(theta) its centre of mass from the hinge, e the
    slide's axis; integrated by mpmath's Taylor method at EXACT_DIGITS digits from rest (the
    drive starts with zero rate and acceleration), the sites then moved by x(t) e."""
    mpmath.mp.dps = EXACT_DIGITS
    drive = case["drive"]
    root = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, drive["body"])
    carried = carried_bodies(model, root)
    if len(carried) != 1 or model.body_jntnum[carried[0]] != 1:
        return None
    body = carried[0]
    joint = model.body_jntadr[body]
    if model.jnt_type[joint] != mujoco.mjtJoint.mjJNT_HINGE:
        return None
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    mp = lambda v: [mpmath.mpf(float(x)) for x in v]  # noqa: E731
    n, pivot, com = mp(data.xaxis[joint]), mp(data.xanchor[joint]), mp(data.xipos[body])
    r0 = [c - p for c, p in zip(com, pivot)]
    frame = [mp(data.ximat[body][3 * i : 3 * i + 3]) for i in range(3)]
    moments = mp(model.body_inertia[body])
    frame_n = [sum(frame[k][i] * n[k] for k in range(3)) for i in range(3)]  # n in the inertia frame
    mass = mpmath.mpf(float(model.body_mass[body]))
    off_axis = [r0[i] - sum(a * b for a, b in zip(r0, n)) * n[i] for i in range(3)]
    moment_n = sum(moments[i] * frame_n[i] ** 2 for i in range(3)) + mass * sum(x * x for x in off_axis)
    gravity, e = mp(model.opt.gravity), mp(drive["axis"])
    a_, w = mpmath.mpf(drive["stroke_m"]), mpmath.mpf(drive["rad_per_s"])

    def rates(t, y):
        accel = a_ * w * w / 2 * (mpmath.cos(w * t) - mpmath.cos(2 * w * t))
        force = [mass * (gravity[i] - accel * e[i]) for i in range(3)]
        r = rotated(n, y[0], r0)
        torque = [r[1] * force[2] - r[2] * force[1], r[2] * force[0] - r[0] * force[2], r[0] * force[1] - r[1] * force[0]]
        return [y[1], sum(a * b for a, b in zip(n, torque)) / moment_n]

    tolerance = mpmath.mpf(10) ** (-EXACT_DIGITS)
    theta = mpmath.odefun(rates, 0, [0, 0], tol=tolerance, degree=EXACT_DIGITS)(duration)[0]
    shift = [a_ * mpmath.sin(w * duration / 2) ** 4 * x for x in e]
    out = []
    for site in sites:
        p0 = mp(data.site_xpos[site])
        site_body = model.site_bodyid[site]
        if site_body == body:
            p0 = [pv + d for pv, d in zip(pivot, rotated(n, theta, [a - b for a, b in zip(p0, pivot)]))]
        if is_below(model, site_body, root):
            p0 = [a + b for a, b in zip(p0, shift)]
        out.append([float(x) for x in p0])
    return np.array(out)


def integrator_runs(load, case: dict, motion: dict, integrator) -> list:
    """The motion at each of `integrator_dts` with `integrator`: end sites and median wall."""
    duration, runs = motion["duration_s"], []
    for dt in motion.get("integrator_dts", []):
        steps = round(duration / dt)
        walls = []
        while not walls or sum(walls) < MIN_CASE_WALL_S:
            model, data, sites = load(dt, integrator)
            pos, wall_s = motion_positions(model, data, sites, steps, case)
            walls.append(wall_s)
        runs.append({"dt_s": dt, "steps": steps, "wall_s": statistics.median(walls), "positions": pos.tolist()})
    return runs


def motion_case(case: dict, motion: dict) -> dict:
    """The motion protocol (`src/bench/scale/motion.rs`): the undamped export moved for
    `duration_s` at each of `dts` (the export's integrator, implicitfast) and once with RK4
    at `reference_dt_s`, the reference; node sites at the end of each run."""

    def load(dt: float, integrator=None):
        mujoco.set_mjcb_control(None)  # compiling evaluates the dynamics: no callback of a case before
        model = mujoco.MjModel.from_xml_path(case["mjcf"])
        model.opt.timestep = dt
        model.dof_damping[:] = 0.0
        if integrator is not None:
            model.opt.integrator = integrator
        sites = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, n) for n in case["nodes"]]
        data = mujoco.MjData(model)
        spun(model, data, case)
        set_drive(model, case)
        return model, data, sites

    duration = motion["duration_s"]
    runs = []
    for dt in motion["dts"]:
        steps = round(duration / dt)
        model, data, sites = load(dt)
        pos, wall_s = motion_positions(model, data, sites, steps, case)
        walls = [wall_s]
        while sum(walls) < MIN_CASE_WALL_S:
            model, data, sites = load(dt)
            walls.append(motion_positions(model, data, sites, steps, case)[1])
        runs.append({"dt_s": dt, "steps": steps, "wall_s": statistics.median(walls), "positions": pos.tolist()})
    ref_dt = motion["reference_dt_s"]
    model, data, sites = load(ref_dt, mujoco.mjtIntegrator.mjINT_RK4)
    exact = driven_hinge_sites(model, case, sites, duration) if case.get("drive") else None
    if case.get("spin"):
        reference = torque_free_sites(model, case, sites, duration)
    elif exact is not None:
        reference = exact
    else:
        reference, _ = motion_positions(model, data, sites, round(duration / ref_dt), case)
    rk4 = integrator_runs(load, case, motion, mujoco.mjtIntegrator.mjINT_RK4)
    euler = integrator_runs(load, case, motion, mujoco.mjtIntegrator.mjINT_EULER)
    mujoco.set_mjcb_control(None)
    return {
        "family": case["family"],
        "size": case["size"],
        "reference": reference.tolist(),
        "runs": runs,
        "rk4_runs": rk4,
        "euler_runs": euler,
    }


def parse_override(text: str) -> tuple[str, float]:
    name, value = text.split("=", 1)
    return name, float(value)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("cases", help="case list JSON written by `tensegrity bench --scale --peer`")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="timestep_s or damping_scale")
    args = ap.parse_args()
    with open(args.cases) as f:
        listed = json.load(f)
    cases = listed["cases"]
    if "motion" in listed:
        out = []
        for case in cases:
            print(f"{case['family']} {case['size']}: mujoco motion ...", file=sys.stderr)
            out.append(motion_case(case, listed["motion"]))
        settings = {"integrator": "implicitfast (reference: RK4)", "damping": 0.0}
        json.dump({"simulator": "mujoco", "mujoco_version": mujoco.__version__, "settings": settings, "cases": out}, sys.stdout)
        sys.stdout.write("\n")
        return
    overrides = dict(parse_override(s) for s in args.set)
    out = []
    for case in cases:
        print(f"{case['family']} {case['size']}: mujoco ...", file=sys.stderr)
        first = run_case(case, overrides)
        walls = [first["wall_s"]]
        while sum(walls) < MIN_CASE_WALL_S:
            walls.append(run_case(case, overrides)["wall_s"])
        first["wall_s"] = statistics.median(walls)
        out.append(first)
    settings = {
        "integrator": "implicitfast",
        "timestep_s": overrides.get("timestep_s", {f: t.get("timestep_s", "the testbed's") for f, t in TUNED.items()}),
        "damping": f"the testbed's body damping x mass x {overrides.get('damping_scale', 1.0)}",
        "tolerance": 1e-10,
        "equality": "solref 2 dt 1, solimp 0.9999 0.9999 0.001 0.5 2",
    }
    json.dump({"simulator": "mujoco", "mujoco_version": mujoco.__version__, "settings": settings, "cases": out}, sys.stdout, indent=1)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
