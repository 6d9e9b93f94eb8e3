"""Free vibration of an MJCF export in MuJoCo: the hinge `pin` displaced by A from its drawn
angle, stepped for DURATION s at each time step and integrator; prints the fitted frequency's
error against omega, the trajectory error against q* + A cos(omega t) and the wall time.

usage: free_vibration.py model.xml omega A duration
"""
import sys
import time

import mujoco
import numpy as np


def fit_frequency(t, q):
    """Least squares of c + a cos(w t) + b sin(w t): start from the mean crossings, then
    Gauss-Newton on (c, a, b, w)."""
    c0 = q.mean()
    s = np.sign(q - c0)
    idx = np.nonzero(s[1:] != s[:-1])[0]
    tc = t[idx] + (t[idx + 1] - t[idx]) * (q[idx] - c0) / (q[idx] - q[idx + 1])
    w = np.pi * (len(tc) - 1) / (tc[-1] - tc[0])
    x = np.linalg.lstsq(np.stack([np.ones_like(t), np.cos(w * t), np.sin(w * t)], 1), q, rcond=None)[0]
    p = np.array([x[0], x[1], x[2], w])
    for _ in range(50):
        c, a, b, w = p
        cs, sn = np.cos(w * t), np.sin(w * t)
        r = q - (c + a * cs + b * sn)
        jac = np.stack([np.ones_like(t), cs, sn, t * (-a * sn + b * cs)], 1)
        d = np.linalg.lstsq(jac, r, rcond=None)[0]
        p = p + d
        if abs(d[3]) <= 1e-15 * abs(p[3]):
            break
    return p[3]


def main():
    path, omega, amplitude, duration = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4])
    model = mujoco.MjModel.from_xml_path(path)
    for integrator in ("Euler", "RK4"):
        for dt in (4e-3, 2e-3, 1e-3):
            model.opt.timestep = dt
            model.opt.integrator = getattr(mujoco.mjtIntegrator, "mjINT_" + integrator.upper())
            data = mujoco.MjData(model)
            q_star = data.qpos[0]
            data.qpos[0] += amplitude
            n = int(round(duration / dt))
            q = np.empty(n)
            start = time.perf_counter()
            for k in range(n):
                mujoco.mj_step(model, data)
                q[k] = data.qpos[0]
            wall = time.perf_counter() - start
            t = dt * np.arange(1, n + 1)
            err = np.abs(q - (q_star + amplitude * np.cos(omega * t))).max()
            w = fit_frequency(t, q)
            print(f"{integrator:5s} dt {dt:.0e}: frequency error {(w - omega) / omega:+.3e}, "
                  f"trajectory max error {err:.3e} rad, {n} steps in {wall * 1e3:.1f} ms")


if __name__ == "__main__":
    main()
