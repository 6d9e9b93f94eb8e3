"""Check published tensegrity models against f64 rigid-body dynamics, from Python.

The testbed's own API (the same code as the ``tensegrity`` command, built with PyO3): load and
check a scenario from a path or from TOML text with ``NAME=VALUE`` overrides, run it (the GIL
released; Ctrl-C stops it at the next tick), and read the result as the JSON report (a dict),
one row per settle point (a pandas DataFrame) and every tick (a pyarrow Table). Units are SI:
m, rad, N, N m, s.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any, Callable, Mapping, NamedTuple, Optional, Sequence, Union

from . import _tensegrity

__all__ = [
    "ScenarioError", "Prediction", "Result", "Solution", "Finding",
    "check", "export_mjcf", "findings", "from_matrices", "run", "solve", "sweep",
]

Scenario = Union[str, "os.PathLike[str]"]


class ScenarioError(ValueError):
    """A scenario the testbed refuses, located: ``file``, ``line``, ``col`` (from 1), ``message``."""

    def __init__(self, file: str, line: int, col: int, message: str) -> None:
        super().__init__(f"{file}:{line}:{col}: {message}")
        self.file, self.line, self.col, self.message = file, line, col, message


def _source(scenario: Scenario, name: str) -> tuple[str, Optional[str]]:
    """(path, None) for a file, (name, text) for TOML text (anything with a newline)."""
    if isinstance(scenario, os.PathLike) or "\n" not in str(scenario):
        return os.fspath(scenario), None
    return name, str(scenario)


def _sets(set: Optional[Mapping[str, Any]]) -> list[str]:
    """``{"k1": 60.0, "sim.dt": 1e-3}`` as the CLI's ``--set NAME=VALUE`` flags."""
    return [f"{k}={v!r}" if isinstance(v, float) else f"{k}={v}" for k, v in (set or {}).items()]


class Prediction(NamedTuple):
    """What a Python model predicts, judged as a file's ``[[predictions]]`` entry: the model's
    output ``name`` against the simulated ``quantity`` (the mechanism's or the file's), in the
    error ``cls`` ("length" [m], "angle" [rad, wrapped] or "relative"), within ``tolerance`` at
    every settle point (over the motion's ticks in a motion run, with ``rms_tolerance``); it
    fails as ``prediction:NAME``."""

    name: str
    quantity: str
    cls: str
    tolerance: float
    rms_tolerance: Optional[float] = None


def _call(f, *args, **kwargs):
    try:
        return f(*args, **kwargs)
    except _tensegrity.TestbedError as e:
        raise ScenarioError(*e.args) from None


def check(scenario: Scenario, set: Optional[Mapping[str, Any]] = None, name: str = "<string>.toml") -> str:
    """Checks a scenario (a path, or TOML text named ``name``); returns its name.

    Raises ScenarioError at the file, line and column of what is wrong.
    """
    path, text = _source(scenario, name)
    return _call(_tensegrity.check, path, text, _sets(set))


class Result:
    """A finished run: ``report`` (the JSON report of ``tensegrity run --json``, one scenario,
    as a dict), ``passed`` (the physics' verdict), ``as_expected`` (whether that is what the
    scenario declares), ``failures`` (``"settle"``, ``"prediction:NAME"``, ...), ``points`` and
    ``table``."""

    def __init__(self, report: dict, table_path: Optional[Path]) -> None:
        self.report = report
        self.passed: bool = report["passed"]
        self.as_expected: Optional[bool] = report.get("as_expected")
        self.failures: list[str] = list(report["failures"])
        self._table_path = table_path
        self._table = None

    @property
    def points(self):
        """One row per settle point (pandas DataFrame): ``index``, ``settled``, ``steps``,
        ``branch``, ``stable``, residuals, and the columns ``input:NAME``, ``param:NAME``,
        ``analytic:NAME`` and ``simulated:NAME`` (the report's values, bit for bit)."""
        import pandas as pd

        scalars = ("index", "settled", "steps", "branch", "stable", "residual_force_n", "residual_torque_nm")
        rows = []
        for p in self.report["points"]:
            row = {k: p.get(k) for k in scalars}
            row.update({f"input:{k}": v for k, v in p["inputs"].items()})
            row.update({f"param:{k}": v for k, v in self.report["params"].items()})
            row.update({f"analytic:{k}": v for k, v in p["analytic"].items()})
            row.update({f"simulated:{k}": v for k, v in p["simulated"].items()})
            rows.append(row)
        return pd.DataFrame(rows)

    @property
    def table(self):
        """Every tick (pyarrow Table, the columns of ``tensegrity run --table``); None unless the
        run was asked for it (``run(..., table=True)``)."""
        if self._table is None and self._table_path is not None:
            import pyarrow.ipc

            with pyarrow.ipc.open_file(str(self._table_path)) as f:
                self._table = f.read_all()
            self._table_path.unlink(missing_ok=True)
            self._table_path = None
        return self._table

    def __repr__(self) -> str:
        verdict = "PASS" if self.passed else f"FAIL ({', '.join(self.failures)})"
        return f"<Result {self.report['name']!r}: {verdict}, as expected: {self.as_expected}>"


Model = Callable[[dict, dict, Optional[float]], Mapping[str, float]]


def run(
    scenario: Scenario,
    set: Optional[Mapping[str, Any]] = None,
    table: bool = False,
    name: str = "<string>.toml",
    model: Optional[Model] = None,
    predictions: Sequence[Prediction] = (),
) -> Result:
    """Runs a scenario (a path, or TOML text named ``name``) with overrides ``set``
    (``{"k1": 60.0, "sim.dt": 1e-3}``, as ``--set``). ``table``: keep every tick as a pyarrow
    Table (``Result.table``).

    ``model``: a Python model, ``model(params, inputs, t) -> {name: value}`` (dicts of floats in
    SI units; ``t`` the time since a motion started [s], None outside a motion), called at every
    settle point and tick, each of ``predictions`` compared as a file's ``[[predictions]]``
    entry (report rows of kind "prediction", failures ``prediction:NAME``). An exception in the
    model, or a prediction it leaves out or makes non-finite, is raised after the run.

    Raises ScenarioError on bad input, KeyboardInterrupt on Ctrl-C."""
    if model is not None and not callable(model):
        raise TypeError(f"model must be callable, got {type(model).__name__}")
    if predictions and model is None:
        raise ValueError("predictions need a model")
    preds = [tuple(Prediction(*p)) for p in predictions]
    path, text = _source(scenario, name)
    table_path = None
    if table:
        fd, tmp = tempfile.mkstemp(suffix=".arrow", prefix="tensegrity-")
        os.close(fd)
        table_path = Path(tmp)
    report = json.loads(
        _call(_tensegrity.run_json, path, text, _sets(set), str(table_path) if table_path else None, model, preds)
    )
    return Result(report, table_path)


def sweep(
    scenario: Scenario,
    set: Optional[Mapping[str, Any]] = None,
    jobs: int = 0,
    name: str = "<string>.toml",
):
    """Settles every point of a scenario's grid (or points) in parallel on ``jobs`` threads
    (0: every core). Returns (DataFrame, summary): the DataFrame has the columns of
    ``tensegrity sweep --out`` (one row per point, values as the CSV writes them: shortest
    round-trip decimals, so bit for bit), the summary is the dict of ``--json``. Raises
    ScenarioError on bad input, KeyboardInterrupt on Ctrl-C."""
    import io

    import pandas as pd

    path, text = _source(scenario, name)
    csv, summary = _call(_tensegrity.sweep_csv, path, text, _sets(set), jobs)
    return pd.read_csv(io.StringIO(csv)), json.loads(summary)


def _matrix(name: str, a, rows: Optional[int] = None, cols: Optional[int] = None):
    """``a`` as a finite 2-D float array, or ValueError naming the matrix and what is wrong."""
    import numpy as np

    m = np.asarray(a, dtype=float)
    if m.ndim != 2 or (rows is not None and m.shape[0] != rows) or (cols is not None and m.shape[1] != cols):
        want = f"({rows if rows is not None else 'k'}, {cols if cols is not None else 'n'})"
        raise ValueError(f"{name} has shape {m.shape}: expected {want}")
    bad = np.argwhere(~np.isfinite(m))
    if len(bad):
        r, c = bad[0]
        raise ValueError(f"{name}[{r}, {c}] is {m[r, c]}, not a finite number")
    return m


def from_matrices(
    N,
    Cb,
    Cs,
    bar_mass_kg: float = 1.0,
    bar_radius_m: float = 0.01,
    string_stiffness_n_per_m: float = 100.0,
    string_tension_n: float = 10.0,
) -> str:
    """A scenario (TOML text, for ``run``, ``check`` or a file) from numpy arrays in the
    notation of Skelton and de Oliveira: N (3 x n node coordinates [m]), Cb and Cs (one row per
    bar or string: -1 at its first node, 1 at its second). The importer of ``tensegrity import
    matrices``: each bar a strut on its own body of ``bar_mass_kg``, nodes on no bar fixed,
    strings elastic of ``string_stiffness_n_per_m``, carrying the drawn structure's self-stress
    with its least tension ``string_tension_n`` [N] (every string at it where the drawing has
    no self-stress with every string taut), as the command does. Member properties are scalars. Raises ValueError on a wrong shape or a non-finite value."""
    import numpy as np

    n = _matrix("N", N, rows=3)
    cb = _matrix("Cb", Cb, cols=n.shape[1])
    cs = _matrix("Cs", Cs, cols=n.shape[1])
    with tempfile.TemporaryDirectory(prefix="tensegrity-") as d:
        paths = [Path(d) / f"{k}.csv" for k in ("N", "Cb", "Cs")]
        for p, m in zip(paths, (n, cb, cs)):
            np.savetxt(p, m, delimiter=",", fmt="%.17g")
        return _call(
            _tensegrity.import_matrices, *map(str, paths),
            bar_mass_kg, bar_radius_m, string_stiffness_n_per_m, string_tension_n,
        )


class Solution(NamedTuple):
    """One solution of an analytic query: its ``label``, its ``values`` by symbol (SI units),
    and whether it is ``stable`` (None where the query does not say)."""

    label: str
    values: dict
    stable: Optional[bool]


class Finding(NamedTuple):
    """One printed equation checked against the derivation: does it ``hold``?"""

    equation: str
    claim: str
    measured: str
    holds: bool


def solve(mechanism: str, query: str, **values: float) -> list:
    """The analytic model of a built-in mechanism alone (``tensegrity solve``): every solution of
    ``query`` ("fk", "ik", ...) at these parameters (defaults for the others) and inputs, e.g.
    ``solve("ji2014", "fk", L3=1.0, theta1=0.5)``. Raises ValueError on unknown names."""
    return [Solution(*s) for s in _tensegrity.solve(mechanism, query, {k: float(v) for k, v in values.items()})]


def findings(mechanism: str, **params: float) -> list:
    """Every printed equation of a built-in mechanism's paper checked (``tensegrity findings``)."""
    return [Finding(*f) for f in _tensegrity.findings(mechanism, {k: float(v) for k, v in params.items()})]


def export_mjcf(
    scenario: Scenario,
    set: Optional[Mapping[str, Any]] = None,
    actuators: str = "mocap",
    kp: float = 1e6,
    cable_damping: float = 0.0,
    name: str = "<string>.toml",
) -> tuple:
    """The MuJoCo MJCF of a scenario's first structure (``tensegrity export mjcf``): (XML text,
    list of what was not exported). ``actuators``: "mocap" (exact) or "position" (servos of gain
    ``kp`` [N/m or N m/rad]); ``cable_damping`` [N s/m]."""
    path, text = _source(scenario, name)
    xml, warnings = _call(_tensegrity.export_mjcf, path, text, _sets(set), actuators, kp, cable_damping)
    return xml, list(warnings)
