#!/usr/bin/env python3
"""MusclePy against the testbed, side by side (issue 60).

    python3 compare.py [--tensegrity BIN] [--json OUT] [--case NAME ...]

Runs peer.py's cases in MusclePy (imported, in this interpreter: run it in the venv of
requirements.txt) and the scenario files cases/NAME.toml in the testbed (`tensegrity run`,
`equilibrium`, `modes`, each with --json), and prints one markdown table: every compared
quantity, MusclePy's value, the testbed's, an exact value where one is computed here, the
differences, and what explains them.

The exact values are this script's own: closed forms for the symmetric one-node cases, and for
the others Newton's method on the pin-jointed structure read from the same scenario file
(`tomllib`; bars push and pull with EA / L0, cables only pull), started from MusclePy's answer,
to a residual below 1e-9 N. The natural frequencies are the generalised eigenproblem
K phi = omega^2 M phi at the exact equilibrium, K = the material plus geometric stiffness, with
MusclePy's lumped mass (half of each member's mass at each end) and its consistent one
(m / 6 [2 1; 1 2] per direction).

Relative differences: forces against the exact value's (or the testbed's) magnitude, with the
case's largest force as the floor (a slack cable's 0 N); displacements likewise with the
case's largest displacement as the floor; counts as equal or not; vectors (self-stress states,
mechanisms, mode shapes) as 1 - |cos| of the angle between them, or for s > 1 the sine of the
largest principal angle between the two spans.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import peer  # noqa: E402

CASE_ORDER = [
    "cables2_prestress", "cables2_load", "cables3_simple_slack", "cables3_simple_prestress",
    "cables3_complex_prestress", "cables3_complex_slack", "cables3_prestress_linear", "rope_loose", "rope_tight",
    "truss2", "snap_up", "snap_down", "simplex_dr", "svd_2cables", "svd_3cables", "snelson2x_selfstress",
    "svd_simplex", "simplex_dynamic",
]
SVD_CASES = {"svd_2cables", "svd_3cables", "snelson2x_selfstress", "svd_simplex"}


# --------------------------------------------------------------------------------------------
# The testbed
# --------------------------------------------------------------------------------------------


def find_binary(arg: str | None) -> str:
    for cand in (arg, os.environ.get("TENSEGRITY_BIN"), shutil.which("tensegrity"),
                 str(HERE.parents[2] / "target/release/tensegrity")):
        if cand and Path(cand).exists():
            return cand
    sys.exit("no tensegrity binary: pass --tensegrity BIN or set TENSEGRITY_BIN")


def testbed(binary: str, command: str, toml: Path) -> tuple[dict | None, str]:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out.json"
        p = subprocess.run([binary, command, str(toml), "--json", str(out)], capture_output=True, text=True)
        if not out.exists():
            return None, (p.stderr.strip() or p.stdout.strip()).splitlines()[0] if (p.stderr or p.stdout) else f"exit {p.returncode}"
        return json.loads(out.read_text()), ""


# --------------------------------------------------------------------------------------------
# The scenario file as a pin-jointed structure (for the exact solutions)
# --------------------------------------------------------------------------------------------

FUNCS = {k: getattr(math, k) for k in ("sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sqrt", "exp", "hypot")}
FUNCS.update(pi=math.pi, e=math.e, abs=abs, min=min, max=max, pow=pow, ln=math.log)


def evaluate(v, env):
    if isinstance(v, (int, float)):
        return float(v)
    return float(eval(str(v).replace("^", "**"), {"__builtins__": {}}, {**FUNCS, **env}))  # noqa: S307


def read_structure(toml: Path, point: dict | None = None) -> dict:
    doc = tomllib.loads(toml.read_text())
    env: dict = {}
    pending = dict(doc.get("params", {}))
    for _ in range(len(pending) + 1):
        for k, v in list(pending.items()):
            try:
                env[k] = evaluate(v["value"] if isinstance(v, dict) else v, env)
                del pending[k]
            except NameError:
                pass
    env.update({k: float(v) for k, v in (point or {}).items()})
    st = doc["structure"]
    names, x, held, mass = [], [], [], []
    for body in st["bodies"]:
        for n, xyz in body["nodes"].items():
            names.append(n)
            x.append([evaluate(c, env) for c in xyz])
            held.append([bool(body.get("fixed", False))] * 3)
            mass.append(0.0 if body.get("fixed") else evaluate(body["mass"], env))
    idx = {n: i for i, n in enumerate(names)}
    for s in st.get("supports", []):
        for d in s["fixed"]:
            held[idx[s["node"]]]["xyz".index(d)] = True
    for m in st.get("masses", []):
        mass[idx[m["node"]]] += evaluate(m["mass"], env)
    members = []
    for kind in ("springs", "cables"):
        for m in st.get(kind, []):
            k, L0 = evaluate(m["stiffness"], env), evaluate(m["length"], env)
            members.append(dict(name=m["name"], a=idx[m["a"]], b=idx[m["b"]], EA=k * L0, L0=L0, cable=kind == "cables"))
    loads = np.zeros((len(names), 3))
    for ld in st.get("loads", []):
        loads[idx[ld["node"]]] += [evaluate(c, env) for c in ld["force"]]
    return dict(names=names, idx=idx, x=np.array(x), held=np.array(held), mass=np.array(mass), members=members,
                loads=loads, env=env, doc=doc)


def member_forces(s, x):
    out = []
    for m in s["members"]:
        L = np.linalg.norm(x[m["b"]] - x[m["a"]])
        t = m["EA"] * (L - m["L0"]) / m["L0"]
        out.append(max(t, 0.0) if m["cable"] else t)
    return np.array(out)


def residual_and_stiffness(s, x, musclepy_kg=False):
    """musclepy_kg: MusclePy's geometric stiffness (T / L) I in place of (T / L) (I - e e^T)."""
    n = len(s["names"])
    f = s["loads"].reshape(-1).copy()
    K = np.zeros((3 * n, 3 * n))
    for m, t in zip(s["members"], member_forces(s, x)):
        d = x[m["b"]] - x[m["a"]]
        L = np.linalg.norm(d)
        e = d / L
        f[3 * m["a"]:3 * m["a"] + 3] += t * e
        f[3 * m["b"]:3 * m["b"] + 3] -= t * e
        taut = not (m["cable"] and L <= m["L0"])
        k = (m["EA"] / m["L0"] if taut else 0.0) * np.outer(e, e) + (t / L) * (np.eye(3) - (0 if musclepy_kg else np.outer(e, e)))
        for i, j, sg in ((m["a"], m["a"], 1), (m["b"], m["b"], 1), (m["a"], m["b"], -1), (m["b"], m["a"], -1)):
            K[3 * i:3 * i + 3, 3 * j:3 * j + 3] += sg * k
    return f, K  # f: the out-of-balance force (loads + member pulls), K: the tangent stiffness


def exact_equilibrium(s, start):
    """Newton with a backtracking line search on the free coordinates, from `start`."""
    x = np.array(start, dtype=float)
    free = ~s["held"].reshape(-1)
    for _ in range(200):
        f, K = residual_and_stiffness(s, x)
        r = np.linalg.norm(f[free])
        if r < 1e-9:
            break
        dx = np.zeros_like(f)
        dx[free] = np.linalg.lstsq(K[np.ix_(free, free)], f[free], rcond=None)[0]
        step = 1.0
        while step > 1e-6:
            xt = x + step * dx.reshape(-1, 3)
            if np.linalg.norm(residual_and_stiffness(s, xt)[0][free]) < r:
                break
            step /= 2
        x = xt
    f, _ = residual_and_stiffness(s, x)
    return x, float(np.linalg.norm(f[free]))


def out_of_balance(s, x):
    """The free coordinates' out-of-balance force [N] of positions x under the exact physics."""
    f, _ = residual_and_stiffness(s, x)
    return float(np.linalg.norm(f[~s["held"].reshape(-1)]))


def bisect(g, lo, hi):
    glo = g(lo)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if (g(mid) > 0) == (glo > 0):
            lo, glo = mid, g(mid)
        else:
            hi = mid
    return 0.5 * (lo + hi)


def sag(a, L0, EA, P):
    """Mid-span node between two cables of rest length L0 from +-a under a transverse load P:
    P = 2 EA (L - L0) / L0 * z / L, L = sqrt(a^2 + z^2). Returns z and T."""
    def g(z):
        L = math.hypot(a, z)
        return 2 * EA * max(L - L0, 0) / L0 * z / L - P
    z = bisect(g, 1e-12, a)
    return z, EA * (math.hypot(a, z) - L0) / L0


# --------------------------------------------------------------------------------------------
# The table
# --------------------------------------------------------------------------------------------

ROWS: list[dict] = []


def fmt(v):
    if v is None:
        return ""
    if isinstance(v, str):
        return v
    if isinstance(v, (int, np.integer)) and not isinstance(v, bool):
        return str(v)
    return f"{v:.6g}" if abs(v) >= 1e-3 or v == 0 else f"{v:.4e}"


def rel(a, b, floor):
    if a is None or b is None:
        return None
    return abs(a - b) / max(abs(b), floor)


def row(case, quantity, mp, tb, exact=None, floor=1e-12, note=""):
    ref = exact if exact is not None else tb
    ROWS.append(dict(case=case, quantity=quantity, musclepy=mp, testbed=tb, exact=exact,
                     d_mp_tb=rel(mp, tb, floor) if isinstance(mp, float) else (None if mp is None or tb is None else float(mp != tb)),
                     d_mp_ex=rel(mp, ref, floor) if isinstance(mp, float) and exact is not None else None,
                     d_tb_ex=rel(tb, exact, floor) if isinstance(tb, float) and exact is not None else None,
                     note=note))


def vec_row(case, quantity, a, b, note=""):
    a, b = np.asarray(a, float).ravel(), np.asarray(b, float).ravel()
    c = abs(a @ b) / (np.linalg.norm(a) * np.linalg.norm(b))
    ROWS.append(dict(case=case, quantity=quantity, musclepy="vector", testbed="vector", exact=None,
                     d_mp_tb=max(0.0, 1 - c), d_mp_ex=None, d_tb_ex=None, note=note + " (1 - |cos|)"))


def span_row(case, quantity, A, B, note=""):
    qa, _ = np.linalg.qr(np.asarray(A, float).T)
    qb, _ = np.linalg.qr(np.asarray(B, float).T)
    sines = np.linalg.svd(qa - qb @ (qb.T @ qa), compute_uv=False)
    ROWS.append(dict(case=case, quantity=quantity, musclepy=f"{len(A)} vectors", testbed=f"{len(B)} vectors", exact=None,
                     d_mp_tb=float(sines.max()), d_mp_ex=None, d_tb_ex=None, note=note + " (sine of the largest principal angle)"))


def fail_row(case, err):
    ROWS.append(dict(case=case, quantity="(testbed refused)", musclepy="", testbed=err, exact=None, d_mp_tb=None,
                     d_mp_ex=None, d_tb_ex=None, note=""))


def tb_point(run, i=0):
    return run["scenarios"][0]["points"][i]["simulated"]


def tb_xyz(sim, node):
    return np.array([sim[f"{node}.x"], sim[f"{node}.y"], sim[f"{node}.z"]])


def static_rows(case, mp, run, eq, s, exact_x, notes, nodes, force_note="", reactions=True, point=0, label=""):
    sim = tb_point(run, point)
    f_ex = member_forces(s, exact_x) if exact_x is not None else None
    fmax = max(abs(t) for t in mp["forces_n"])
    for i, tm in enumerate(mp["forces_n"]):
        tb = sim[f"e{i}.force"]
        row(case, f"{label}e{i} force [N]", float(tm), float(tb), None if f_ex is None else float(f_ex[i]),
            floor=fmax, note=notes.get(f"e{i}", force_note if i == 0 else ("as e0" if force_note else "")))
    x0 = s["x"]
    dmax = max(float(np.abs(exact_x - x0).max()) if exact_x is not None else 0.0, 1e-9)
    for n in nodes:
        i = s["idx"][n]
        pm = np.array(mp["positions_m"][n])
        pt = tb_xyz(sim, n)
        for k, ax in enumerate("xyz"):
            if s["held"][i][k] or (abs(pm[k] - x0[i][k]) < 1e-12 and abs(pt[k] - x0[i][k]) < 1e-12):
                continue
            ex = None if exact_x is None else float(exact_x[i][k] - x0[i][k])
            row(case, f"{label}{n}.{ax} displacement [m]", float(pm[k] - x0[i][k]), float(pt[k] - x0[i][k]), ex,
                floor=dmax, note=notes.get(f"{n}.{ax}", ""))
    if reactions and eq is not None:
        rt = dict((n, np.array(v)) for n, v in eq.get("reactions_n", []))
        for n, vm in mp["reactions_n"].items():
            if n not in rt:
                continue
            for k, ax in enumerate("xyz"):
                if abs(vm[k]) < 1e-9 and abs(rt[n][k]) < 1e-9:
                    continue
                row(case, f"{label}{n} reaction {ax} [N]", float(vm[k]), float(rt[n][k]), None, floor=fmax,
                    note=notes.get(f"R{n}.{ax}", ""))


def linear_rows(case, mp, eq, s, nodes, note):
    """MusclePy's linear method beside the testbed's linear analysis (`tensegrity equilibrium`'s
    `linear`, about the structure settled without its point loads): the same method, so the
    same answer where their stiffness matrices agree."""
    lin = (eq or {}).get("linear")
    if lin is None:
        ROWS.append(dict(case=case, quantity="testbed linear analysis", musclepy="", testbed="",
                         exact=None, d_mp_tb=None, d_mp_ex=None, d_tb_ex=None,
                         note=f"none: {(eq or {}).get('linear_refused')}"))
        return
    forces = {name: linear for name, _, linear in lin["forces_n"]}
    fmax = max(abs(t) for t in mp["forces_n"])
    for i, tm in enumerate(mp["forces_n"]):
        row(case, f"testbed linear analysis: e{i} force [N]", float(tm), float(forces[f"e{i}"]), None,
            floor=fmax, note=note if i == 0 else "as e0")
    moved = {name: np.array(linear) for name, _, linear in lin["displacements_m"]}
    x0 = s["x"]
    dmax = max(max(float(np.abs(np.array(mp["positions_m"][n]) - x0[s["idx"][n]]).max()) for n in nodes), 1e-12)
    for n in nodes:
        i = s["idx"][n]
        for k, ax in enumerate("xyz"):
            if s["held"][i][k]:
                continue
            row(case, f"testbed linear analysis: {n}.{ax} displacement [m]", float(mp["positions_m"][n][k] - x0[i][k]),
                float(moved[n][k]), None, floor=dmax)


# --------------------------------------------------------------------------------------------
# The cases
# --------------------------------------------------------------------------------------------


def compare_case(binary, case, mp):
    toml = HERE / "cases" / f"{case}.toml"
    run, err = testbed(binary, "run", toml)
    if run is None:
        fail_row(case, err)
        return
    s = read_structure(toml)
    EA = lambda i: s["members"][[m["name"] for m in s["members"]].index(f"e{i}")]["EA"]  # noqa: E731
    eq = None
    if case not in ("rope_tight",):
        eq, err = testbed(binary, "equilibrium", toml)
        if eq is None and case in SVD_CASES:
            fail_row(case, err)
            return

    if case == "cables2_prestress":
        T = EA(0) * 0.001 / 1.999
        ex = s["x"].copy()
        ex[s["idx"]["N1"]] = [0, 0, 0]
        static_rows(case, mp, run, eq, s, ex, {}, ["N1"],
                    force_note=f"closed form EA 0.001 / 1.999; MusclePy stops at its residual tolerance (1e-6 rel.)")
    elif case in ("cables2_load", "cables3_simple_slack"):
        z, T = sag(2.0, 2.0, EA(1), 888.808)
        node = "N1" if case == "cables2_load" else "N3"
        ex = s["x"].copy()
        ex[s["idx"][node]][2] = z
        static_rows(case, mp, run, eq, s, ex, {"e0": "slack: 0 N" if case != "cables2_load" else ""}, [node],
                    force_note=f"closed form: P = 2 T z / L, T = EA (L - 2) / 2 (z = {z:.9f} m)")
    elif case in ("rope_loose",):
        z, T = sag(1.0, 1.0, EA(0), 1e5)
        ex = s["x"].copy()
        ex[s["idx"]["N1"]][2] = -z
        xm = np.array([mp["positions_m"][n] for n in s["names"]])
        static_rows(case, mp, run, eq, s, ex, {"N1.z": f"the test states -0.15874 m = -(P / EA)^(1/3), the "
                                                     f"shallow-rope approximation (2 % tolerance)",
                                              "N1.x": "MusclePy drifts sideways (its load steps are not iterated)"},
                    ["N1"], force_note=f"closed form P = 2 T z / L (the test states 313020 N, 2 % tolerance); "
                               f"MusclePy's 100 load steps without iteration leave "
                               f"{out_of_balance(s, xm):.3g} N out of balance at its own positions")
    elif case == "rope_tight":
        L0 = s["env"]["L0"]
        stages = mp["stages"]
        for k, P in enumerate((0.0, 5109.0, 9988.0)):
            sk = read_structure(toml, {"P": P})
            if P == 0:
                T, z = EA(0) * (1 - L0) / L0, 0.0
            else:
                z, T = sag(1.0, L0, EA(0), P)
            sim = tb_point(run, k)
            xm = np.array([stages[k]["positions_m"][n] for n in sk["names"]])
            obal = out_of_balance(sk, xm)
            note = ("prestress: MusclePy's linear method, its equivalent loads, exact here as the node does not move"
                    if P == 0 else f"closed form P = 2 T z / L; MusclePy's incremental steps leave {obal:.3g} N out of "
                                   f"balance at its own positions")
            row(case, f"P = {P:g} N: e0 force [N]", float(stages[k]["forces_n"][0]), float(sim["e0.force"]), T,
                floor=T, note=note)
            if P:
                row(case, f"P = {P:g} N: N1.z displacement [m]", float(stages[k]["displacements_m"]["N1"][2]),
                    float(sim["N1.z"]), -z, floor=z, note="from the prestressed state")
    elif case in ("truss2", "snap_up", "snap_down"):
        z0 = s["x"][s["idx"]["N1"]][2]
        L0 = s["env"]["L0"]
        ea, P = EA(0), s["env"]["P"]

        def g(z):
            L = math.hypot(1.0, z)
            return -2 * ea * (L - L0) / L0 * z / L - (-P)  # vertical balance at N1: member pulls + load = 0

        lo, hi = (-1.0, -1e-9) if case != "truss2" else (0.5, 1.0)
        z = bisect(lambda v: 2 * ea * (math.hypot(1.0, v) - L0) / L0 * v / math.hypot(1.0, v) + P, lo, hi)
        ex = s["x"].copy()
        ex[s["idx"]["N1"]][2] = z
        if case == "truss2":
            lin = mp["variants"]["linear"]
            nl = mp["variants"]["nonlinear"]
            dl = P * L0 / (2 * ea * 0.5)
            ROWS.append(dict(case=case, quantity="(linear method, closed form)", musclepy="", testbed="",
                             exact=None, d_mp_tb=None, d_mp_ex=None, d_tb_ex=None,
                             note=f"N = -P / sqrt 2 = {-P / math.sqrt(2):.6g} N, w = P L0 / (2 EA sin^2 45) = "
                                  f"{dl:.6g} m: small displacements, equilibrium in the drawn geometry"))
            linear_rows(case, lin, eq, s, ["N1"], "unstressed at the reference: both K = A diag(EA / L0) A^T")
            static_rows(case, lin, run, eq, s, ex, {}, ["N1"], label="linear: ",
                        force_note="MusclePy's linear method: equilibrium in the drawn geometry; exact: in the "
                                   "deformed one (the bars steepen less as N1 drops, so they push harder)")
            xm = np.array([nl["positions_m"][n] for n in s["names"]])
            static_rows(case, nl, run, eq, s, ex, {}, ["N1"], label="nonlinear: ", reactions=False,
                        force_note=f"MusclePy's 100 steps without iteration: {out_of_balance(s, xm):.3g} N out of "
                                   f"balance at its own positions")
        else:
            xm = np.array([mp["positions_m"][n] for n in s["names"]])
            static_rows(case, mp, run, eq, s, ex, {}, ["N1"],
                        force_note=f"exact root below the supports (z = {z:.6f} m); MusclePy's incremental steps "
                                   f"leave {out_of_balance(s, xm):.3g} N out of balance")
    elif case in ("cables3_simple_prestress", "cables3_complex_prestress", "cables3_complex_slack",
                  "cables3_prestress_linear", "simplex_dr"):
        xm = np.array([mp["positions_m"][n] for n in s["names"]])
        ex, res = exact_equilibrium(s, xm)
        notes = {}
        if case == "cables3_prestress_linear":
            dx = ex[s["idx"]["N1"]][0]
            kv = (member_forces(s, ex)[0] + member_forces(s, ex)[1]) / 2.0
            t2 = (math.hypot(1, dx) - 1) * EA(2) * kv / (EA(2) + kv)
            notes["e2"] = (f"MusclePy's linear method keeps e2 at 0 (second order in dx); exact: N1's move dx = "
                           f"{dx:.6g} m lengthens e2's chord by dx^2 / 2, taken up by e2 (EA) in series with the "
                           f"rope's lateral stiffness (T0 + T1) / 2 = {kv:.5g} N/m: {t2:.4g} N")
            force_note = "MusclePy: linear method (equilibrium in the drawn geometry)"
        elif case == "simplex_dr":
            force_note = (f"MusclePy's DR stops at 1e-4 of the loads ({out_of_balance(s, xm):.3g} N out of balance "
                          f"at its positions); exact: Newton from its answer to {res:.1e} N")
        else:
            force_note = (f"MusclePy's DR stops at its residual tolerance ({out_of_balance(s, xm):.3g} N out of "
                          f"balance); exact: Newton from its answer to {res:.1e} N")
        nodes = [n for n in s["names"] if not s["held"][s["idx"][n]].all()]
        static_rows(case, mp, run, eq, s, ex, notes, nodes, force_note=force_note)
    elif case in SVD_CASES:
        svd_rows(case, mp, eq, s)
    elif case == "simplex_dynamic":
        dynamic_rows(binary, case, mp, run, eq, s, toml)


def svd_rows(case, mp, eq, s):
    row(case, "rank r", mp["r"], eq["rank"], note="")
    row(case, "self-stress states s", mp["s"], eq["self_stress_states"])
    row(case, "mechanisms m", mp["m"], eq["mechanisms"])
    sv_m, sv_t = np.array(mp["singular_values"]), np.array(eq["singular_values"])
    row(case, "smallest singular value / largest", float(sv_m.min() / sv_m.max()), float(sv_t.min() / sv_t.max()),
        floor=1.0, note="rank: MusclePy counts singular values above 1e-3 of the largest, the testbed above 1e-10")
    members = [m["name"] for m in s["members"]]
    order = [members.index(f"e{i}") for i in range(len(members))]
    if mp["s"] and eq["self_stress_states"]:
        tb = []
        for st in eq["self_stress"]:
            vals = dict(st) if isinstance(st, list) and st and isinstance(st[0], list) else None
            if vals is None and isinstance(st, dict):
                vals = st
            tb.append([vals[f"e{i}"] for i in range(len(members))])
        if mp["s"] == 1 and len(tb) == 1:
            vec_row(case, "self-stress state", mp["self_stress"][0], tb[0], note="MusclePy's SVD against the testbed's")
            a, b = np.array(mp["self_stress"][0]), np.array(tb[0])
            b = b * (a @ b) / (b @ b)
            for i in range(len(a)):
                row(case, f"self-stress e{i}", float(a[i]), float(b[i]), floor=1.0,
                    note="each scaled so its largest magnitude is 1")
        else:
            span_row(case, "self-stress span", mp["self_stress"], tb, note="MusclePy's SVD against the testbed's")
            if "self_stress_localized" in mp:
                span_row(case, "MusclePy's localised states in the testbed's span", mp["self_stress_localized"], tb)
    if mp["m"] and eq["mechanisms"]:
        free = [(n, k) for n in s["names"] for k in range(3) if not s["held"][s["idx"][n]][k]]
        A = [[u[n][k] for (n, k) in free] for u in mp["mechanisms"]]
        B = []
        for shape in eq["mechanism_shapes"]:
            d = dict((n, v) for n, v in shape)
            B.append([d.get(n, [0, 0, 0])[k] for (n, k) in free])
        if len(A) == 1 and len(B) == 1:
            vec_row(case, "mechanism", A[0], B[0])
        else:
            span_row(case, "mechanism span", A, B)


def eig(K, M, free):
    Kf, Mf = K[np.ix_(free, free)], M[np.ix_(free, free)]
    C = np.linalg.cholesky(Mf)
    Ci = np.linalg.inv(C)
    w2, y = np.linalg.eigh(Ci @ Kf @ Ci.T)
    phi = Ci.T @ y
    return w2, phi


def dynamic_rows(binary, case, mp, run, eq, s, toml):
    xm = np.array([mp["positions_m"][n] for n in s["names"]])
    ex, res = exact_equilibrium(s, xm)
    f_ex = member_forces(s, ex)
    sim = tb_point(run)
    fmax = max(abs(t) for t in mp["forces_n"])
    for i in (0, 3, 9):
        row(case, f"e{i} force [N] (form-found)", float(mp["forces_n"][i]), float(sim[f"e{i}.force"]), float(f_ex[i]),
            floor=fmax, note=f"MusclePy's DR stops at 1e-4 of the loads ({out_of_balance(s, xm):.3g} N out of balance)")
    modes, err = testbed(binary, "modes", toml)
    if modes is None:
        fail_row(case + " (modes)", err)
        return
    n = len(s["names"])
    free = ~s["held"].reshape(-1)
    _, K = residual_and_stiffness(s, ex)
    # MusclePy's two mass matrices, from the test's point and member masses.
    point = {"N0": 2.642, "N1": 2.642, "N2": 2.642, "N3": 3.06, "N4": 3.06, "N5": 3.06}
    mem_mass = {f"e{i}": (2.63 if i < 3 else 0.502) for i in range(12)}
    M_l, M_c = np.zeros((3 * n, 3 * n)), np.zeros((3 * n, 3 * n))
    for nm, i in s["idx"].items():
        for k in range(3):
            M_l[3 * i + k, 3 * i + k] = M_c[3 * i + k, 3 * i + k] = point[nm]
    for m in s["members"]:
        mm = mem_mass[m["name"]]
        for k in range(3):
            a, b = 3 * m["a"] + k, 3 * m["b"] + k
            M_l[a, a] += mm / 2
            M_l[b, b] += mm / 2
            M_c[a, a] += mm / 3
            M_c[b, b] += mm / 3
            M_c[a, b] += mm / 6
            M_c[b, a] += mm / 6
    _, K_mp = residual_and_stiffness(s, xm, musclepy_kg=True)
    hz = lambda w2: np.sqrt(np.abs(w2)) / (2 * math.pi)  # noqa: E731
    f_l, f_c = hz(eig(K, M_l, free)[0]), hz(eig(K, M_c, free)[0])
    f_l_mp, f_c_mp = hz(eig(K_mp, M_l, free)[0]), hz(eig(K_mp, M_c, free)[0])
    worst = max(abs(a - b) / b for a, b in zip(mp["lumped"]["frequencies_hz"], f_l_mp))
    tb_modes = [m for m in modes["modes"] if not m["rigid"]]
    lumped, consistent = mp["lumped"], mp["consistent"]
    for k in range(len(tb_modes)):
        note = "lumped mass, both; see f1" if k else (
            "lumped mass, both. MusclePy's geometric stiffness is (T / L) I, which also adds T / L along each "
            "member (the exact one is (T / L)(I - e e^T)): its axial stiffness is EA / L0 + T / L, too stiff by "
            "the strain T / EA (1.6e-4 in the cables). With that K at MusclePy's state this script gets every "
            f"MusclePy frequency within {worst:.1e}")
        row(case, f"f{k + 1} [Hz]", float(lumped["frequencies_hz"][k]), float(tb_modes[k]["frequency_hz"]),
            float(f_l[k]), floor=0.0, note=note)
    row(case, "f1 [Hz], consistent mass: MusclePy; exact (this script)", float(consistent["frequencies_hz"][0]),
        None, float(f_c[0]), note=f"the testbed lumps a member's mass at its ends (no consistent option). The "
        f"consistent mass m / 6 [2 1; 1 2] moves a third of each member's mass from its ends to its middle, which "
        f"moves half as much in the mechanism, so f1 rises by {f_c[0] / f_l[0] - 1:.1%}; MusclePy's K gives "
        f"{f_c_mp[0]:.6f} Hz")
    names = s["names"]
    for k in range(min(3, len(tb_modes))):
        a = [lumped["mode_shapes"][k][nm][c] for nm in names for c in range(3)]
        d = dict((nm, v) for nm, v in tb_modes[k]["node_displacements_m"])
        b = [d.get(nm, [0, 0, 0])[c] for nm in names for c in range(3)]
        vec_row(case, f"mode shape {k + 1}", a, b, note="lumped mass")
    exp = np.array([[0, 0, 0], [0, 0, 0], [0, 0, 0], [3.3, 0, -1.0], [-1.7, -2.9, -1.0], [-1.7, 2.9, -1.0]])
    d = dict((nm, v) for nm, v in tb_modes[0]["node_displacements_m"])
    b = np.array([d.get(f"N{i}", [0, 0, 0]) for i in range(6)])
    c = abs(exp.ravel() @ b.ravel()) / (np.linalg.norm(exp) * np.linalg.norm(b))
    ROWS.append(dict(case=case, quantity="mode 1 against the test's stated mechanism (rounded to 0.1)",
                     musclepy="", testbed="vector", exact=None, d_mp_tb=None, d_mp_ex=None, d_tb_ex=None,
                     note=f"1 - |cos| = {1 - c:.2e} against Feron et al. 2023 Fig. 4 as the test states it"))


def markdown() -> str:
    out = ["| case | quantity | MusclePy | testbed | exact | MusclePy vs testbed | MusclePy vs exact | testbed vs exact | why |",
           "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in ROWS:
        cells = [r["case"], r["quantity"], fmt(r["musclepy"]), fmt(r["testbed"]), fmt(r["exact"]),
                 fmt(r["d_mp_tb"]), fmt(r["d_mp_ex"]), fmt(r["d_tb_ex"]), r["note"]]
        out.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
    return "\n".join(out)


def summary() -> str:
    out = ["| case | rows | MusclePy vs testbed (max) | MusclePy vs exact (max) | testbed vs exact (max) |",
           "| --- | --- | --- | --- | --- |"]
    for case in dict.fromkeys(r["case"] for r in ROWS):
        rs = [r for r in ROWS if r["case"] == case]
        col = lambda k: max((r[k] for r in rs if r[k] is not None), default=None)  # noqa: E731
        out.append(f"| {case} | {len(rs)} | {fmt(col('d_mp_tb'))} | {fmt(col('d_mp_ex'))} | {fmt(col('d_tb_ex'))} |")
    return "\n".join(out)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tensegrity", help="the testbed binary (default: $TENSEGRITY_BIN, tensegrity on PATH, target/release)")
    ap.add_argument("--json", help="also write the rows as JSON here")
    ap.add_argument("--case", action="append")
    args = ap.parse_args()
    binary = find_binary(args.tensegrity)
    import warnings
    cases = args.case or CASE_ORDER
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        for case in cases:
            np.random.seed(0)  # as peer.py: MusclePy perturbs a singular structure at random
            compare_case(binary, case, peer.CASES[case]())
    print(f"MusclePy {peer.musclepy.__version__}, numpy {np.__version__}; testbed {binary}\n")
    print(markdown())
    print()
    print(summary())
    if args.json:
        Path(args.json).write_text(json.dumps(ROWS, indent=1, default=float))
    return 0


if __name__ == "__main__":
    sys.exit(main())
