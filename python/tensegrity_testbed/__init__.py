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
from pathlib import Path
from typing import Any, Callable, Mapping, NamedTuple, Optional, Sequence, Union

from . import _tensegrity

__all__ = [
    "ScenarioError", "Prediction", "Result", "Solution", "Finding", "Structure",
    "attribute", "certify", "check", "equilibrium", "export_mjcf", "findings", "fit", "from_matrices", "from_ntrt", "from_toml", "modes", "run", "sensitivity", "solve",
    "sweep",
]

Scenario = Union[str, "os.PathLike[str]", "Structure"]


class ScenarioError(ValueError):
    """A scenario the testbed refuses, located: ``file``, ``line``, ``col`` (from 1), ``message``."""

    def __init__(self, file: str, line: int, col: int, message: str) -> None:
        super().__init__(f"{file}:{line}:{col}: {message}")
        self.file, self.line, self.col, self.message = file, line, col, message


def _source(scenario: Scenario, name: str) -> tuple[str, Optional[str]]:
    """(path, None) for a file, (name, text) for TOML text (anything with a newline) and for a
    Structure (its own name)."""
    if isinstance(scenario, Structure):
        return scenario.name, scenario.toml
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
    ``table`` (pyarrow) and ``arrow`` (the same ticks for any Arrow PyCapsule consumer)."""

    def __init__(self, report: dict, arrow: Optional["_tensegrity.ArrowTable"]) -> None:
        self.report = report
        self.passed: bool = report["passed"]
        self.as_expected: Optional[bool] = report.get("as_expected")
        self.failures: list[str] = list(report["failures"])
        self.arrow = arrow
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
        """Every tick (pyarrow Table, the columns of ``tensegrity run --table FILE.arrow``: ``tick``
        UInt64, the others Float64 in SI units, null where the CSV leaves a cell empty); None
        unless the run was asked for it (``run(..., table=True)``). Handed over in memory through
        the Arrow PyCapsule interface, without a copy (``pyarrow.table(result.arrow)``)."""
        if self._table is None and self.arrow is not None:
            import pyarrow

            self._table = pyarrow.table(self.arrow)
        return self._table

    def __repr__(self) -> str:
        verdict = "PASS" if self.passed else f"FAIL ({', '.join(self.failures)})"
        return f"<Result {self.report['name']!r}: {verdict}, as expected: {self.as_expected}>"


Model = Callable[[dict, dict, Optional[float]], dict]


def run(
    scenario: Scenario,
    set: Optional[Mapping[str, Any]] = None,
    table: bool = False,
    name: str = "<string>.toml",
    model: Optional[Model] = None,
    predictions: Sequence[Prediction] = (),
) -> Result:
    """Runs a scenario (a path, TOML text named ``name``, or a ``Structure``) with overrides
    ``set`` (``{"k1": 60.0, "sim.dt": 1e-3}``, as ``--set``). ``table``: keep every tick in
    memory as Arrow (``Result.table``, a pyarrow Table; ``Result.arrow`` for other consumers).

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
    report, arrow = _call(_tensegrity.run_json, path, text, _sets(set), bool(table), model, preds)
    return Result(json.loads(report), arrow)


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


def equilibrium(scenario: Scenario, set: Optional[Mapping[str, Any]] = None, name: str = "<string>.toml") -> dict:
    """The equilibrium matrix of a pin-jointed structure at its first point, settled as ``run``
    settles it, and its SVD: the report of ``tensegrity equilibrium --json`` as a dict
    (``rows`` = 3 j, ``columns`` = b, ``rank``, ``self_stress_states`` = s,
    ``mechanisms`` = m, ``singular_values``, ``self_stress``: per state ``[member, tension]``
    pairs, largest 1; ``mechanism_shapes``: per mechanism ``[node, [dx, dy, dz]]``). Raises
    ScenarioError on bad input, ValueError where the structure is not pin-jointed or too large
    (the reason named), KeyboardInterrupt on Ctrl-C."""
    path, text = _source(scenario, name)
    return json.loads(_call(_tensegrity.equilibrium_json, path, text, _sets(set)))


def modes(scenario: Scenario, set: Optional[Mapping[str, Any]] = None, name: str = "<string>.toml",
          count: int = 20) -> dict:
    """The structure's natural frequencies and mode shapes at its first point, settled as
    ``run`` settles it: the report of ``tensegrity modes --json`` as a dict (``modes``: one per
    mode, ascending omega^2, with ``omega_rad_per_s``, ``frequency_hz``, ``rigid``, the
    nodes that move most and, for a non-rigid mode, ``node_displacements_m``: its shape, every
    node's ``[name, [dx, dy, dz]]`` for the mass-normalised amplitude; ``coordinates``, ``joint_coordinates``, ``rigid_modes``; above 100
    free bodies ``lowest_of``: the list is the lowest ``count`` non-rigid modes (1 to 200, as
    ``modes --count``) and every rigid one, of that many). Raises
    ScenarioError on bad input, ValueError where the structure's modes are not computed (the
    reason named) or ``count`` is out of range, KeyboardInterrupt on Ctrl-C."""
    path, text = _source(scenario, name)
    return json.loads(_call(_tensegrity.modes_json, path, text, _sets(set), count))


def sensitivity(scenario: Scenario, set: Optional[Mapping[str, Any]] = None, name: str = "<string>.toml",
                check: bool = False, point: int = 0, params: Optional[list] = None) -> dict:
    """How the settled state at point ``point`` (from 0, as ``run`` numbers them; settled as
    ``run`` settles it) moves with every
    parameter: the report of ``tensegrity sensitivity --json`` as a dict (``outputs``: each
    output's ``name``, ``value`` and ``free``; ``parameters``: one per parameter with its
    ``derivatives``, one per output, each one's error estimate in ``estimates``, and
    d(coordinate)/dp in ``coordinates``; with ``check``
    also the differences of settles in ``check`` and their ``max_check_error``). The derived
    parameters (expressions of others) are listed in ``derived``, not differentiated, unless
    ``params`` names the parameters to differentiate by (the CLI's ``--param``). Raises
    ScenarioError on bad input, ValueError where the structure's sensitivities are not
    computed (the reason named), KeyboardInterrupt on Ctrl-C."""
    path, text = _source(scenario, name)
    return json.loads(_call(_tensegrity.sensitivity_json, path, text, _sets(set), check, point, list(params or [])))


def certify(scenario: Scenario, set: Optional[Mapping[str, Any]] = None, name: str = "<string>.toml",
            point: int = 0, stiffness: bool = False) -> dict:
    """A proof, in interval arithmetic, of the settled equilibrium at point ``point`` (from 0,
    settled as ``run`` settles it): the report of ``tensegrity certify --json`` as a dict
    (``certificate``: ``residual``, ``boxes``, and ``proof`` with the largest box that holds
    exactly one equilibrium, ``radius_m``, ``node_radius_m``, the equilibrium's enclosure
    ``enclosure_radius_m``, the settled state's distance from it ``settled_offset_m``, a free
    turn's ``held_coordinate``, and ``stability`` (``kind``: ``stable`` with
    ``smallest_eigenvalue_at_least_n_per_m``, ``unstable`` with ``index``, or ``unproven`` with
    ``why``); or no ``proof`` and the ``reason``). Raises ScenarioError on bad input, ValueError
    for a structure outside the proof's domain (joints, supports, inextensible or clustered
    cables) or a motion, KeyboardInterrupt on Ctrl-C. With ``stiffness``, also ``stiffness``:
    the stiffness at the settled state over the proof's unknowns (``coordinates``, ``matrix``,
    N/m, rotations as arcs at the structure's size), for an independent check of the
    stability."""
    path, text = _source(scenario, name)
    return json.loads(_call(_tensegrity.certify_json, path, text, _sets(set), point, stiffness))


def attribute(scenario: Scenario, set: Optional[Mapping[str, Any]] = None, name: str = "<string>.toml") -> dict:
    """What each idealization costs the file's model: the report of ``tensegrity attribute
    --json`` as a dict. The checks run under the ideal structure, under each ``[[fidelity]]``
    relaxation alone (on top of its base, ``on_top_of``) and under all of them together:
    ``relaxations`` (each ``name``, ``assumption``, data, ``relaxes``: its members), ``levels``
    (each ``name``, ``relaxed``, ``passed``, ``error``, ``wall_s``) and ``items``, one per compared
    value (``kind``, ``name``, ``point``, ``model``, ``deviation`` at each level: simulated -
    model, ``shares`` per relaxation, ``interaction``: the shares and it add up to the last
    level's deviation less the ideal's). Raises ScenarioError on bad input (a relaxation the
    structure cannot take among it), ValueError for a file without relaxations,
    KeyboardInterrupt on Ctrl-C."""
    path, text = _source(scenario, name)
    return json.loads(_call(_tensegrity.attribute_json, path, text, _sets(set)))


_FIT_COLUMNS = ("point", "output", "value", "sigma", "t_s")


def _fit_params(params) -> list:
    """``{"k2": (1.0, 100.0), "b": None, "k1": (None, 80.0)}`` or ``["k2", "b"]`` as (name, low,
    high) triples; ValueError naming what is wrong."""
    if isinstance(params, str):
        params = [params]
    items = params.items() if isinstance(params, Mapping) else ((p, None) for p in params)
    out = []
    for name, bounds in items:
        if not isinstance(name, str):
            raise ValueError(f"params: the parameter name {name!r} is not a string")
        if bounds is None:
            out.append((name, None, None))
            continue
        try:
            low, high = bounds
        except (TypeError, ValueError):
            raise ValueError(f"params[{name!r}] = {bounds!r}: give (low, high), either None, or None") from None
        for b in (low, high):
            if b is not None and not isinstance(b, (int, float)):
                raise ValueError(f"params[{name!r}]: the bound {b!r} is not a number")
        out.append((name, None if low is None else float(low), None if high is None else float(high)))
    return out


def _fit_rows(data) -> list:
    """A DataFrame (or anything ``pandas.DataFrame`` takes) with the columns point, output,
    value and optionally sigma as (where, point, output, value, sigma) rows; a missing sigma
    (NaN or None) is no sigma, as an empty CSV cell is."""
    import pandas as pd

    frame = data if isinstance(data, pd.DataFrame) else pd.DataFrame(data)
    if len(frame) > _tensegrity.MAX_DATA_ROWS:
        # Bounded as a data file is, before a row is copied.
        raise ValueError(f"data: {len(frame)} rows: more than {_tensegrity.MAX_DATA_ROWS} measurement rows: "
                         f"at most {_tensegrity.MAX_DATA_ROWS} (fit fewer, or average repeated rows)")
    columns = list(frame.columns)
    twice = [c for k, c in enumerate(columns) if c in columns[:k]]
    if twice:
        # As the CSV reader refuses it: the rows had been read from the first of the two.
        raise ValueError(f"data: the column {twice[0]!r} is named twice: which of the two to read is not said")
    unknown = [c for c in frame.columns if c not in _FIT_COLUMNS]
    if unknown:
        raise ValueError(f"data: the column {unknown[0]!r} names nothing: the columns are "
                         f"{','.join(_FIT_COLUMNS)} (sigma and t_s optional)")
    missing = [c for c in _FIT_COLUMNS[:3] if c not in frame.columns]
    if missing:
        raise ValueError(f"data: no column {missing[0]!r} (the columns are {','.join(_FIT_COLUMNS)}, sigma and t_s optional)")
    rows = []
    for index, row in zip(frame.index, frame.itertuples(index=False)):
        at = f"data[{index}]"
        point = row.point
        if isinstance(point, float) and point.is_integer():
            point = int(point)
        if isinstance(point, bool) or not hasattr(point, "__index__"):
            raise ValueError(f"{at}: point {point!r} is not a point number (from 0)")
        try:
            value = float(row.value)
        except (TypeError, ValueError):
            raise ValueError(f"{at}: value {row.value!r} is not a number") from None
        sigma, t_s = _optional_number(row, "sigma", at), _optional_number(row, "t_s", at)
        rows.append((at, int(point), str(row.output), value, sigma, t_s))
    return rows


def _optional_number(row, column: str, at: str) -> Optional[float]:
    """A row's optional number (sigma, t_s): None where the column is absent, None or NaN (as
    an empty cell of the CSV), else the float, ValueError naming the row if it is none."""
    cell = getattr(row, column, None)
    if cell is None:
        return None
    try:
        number = float(cell)
    except (TypeError, ValueError):
        raise ValueError(f"{at}: {column} {cell!r} is not a number") from None
    return None if number != number else number


def fit(scenario: Scenario, data, params, set: Optional[Mapping[str, Any]] = None,
        name: str = "<string>.toml") -> dict:
    """Parameters of a scenario fitted to measured outputs, as ``tensegrity fit`` fits them (the
    same Rust function): the report of ``tensegrity fit --json`` as a dict (``parameters``: each
    ``name``, ``initial``, ``value``, ``sigma`` and 95 % interval ``low``, ``high``;
    ``covariance``, an infinite entry None; ``residuals``; ``chi2``; ``unidentifiable``: the
    combinations the data cannot separate, as (name, weight) pairs; ``wall_s``).

    ``data``: a CSV path (read as ``--data`` reads it) or a pandas DataFrame with the columns
    point (from 0), output (as ``tensegrity sensitivity`` names them), value and optionally
    sigma and t_s (a row of the scenario's motion at that time since its start, output a
    column of its table: ``joint:pin.angle``). ``params``: ``{name: (low, high)}`` (either bound None) or ``{name: None}``, or a list
    of names. ``set``: the CLI's ``--set``. Raises ScenarioError on a bad scenario, ValueError on
    bad data or parameters (the row or name said; a parameter the fit ran into its bound or away
    with named), Exception when a settle fails (the point named), KeyboardInterrupt on Ctrl-C.
    """
    path, text = _source(scenario, name)
    bounds = _fit_params(params)
    if isinstance(data, (str, os.PathLike)):
        return json.loads(_call(_tensegrity.fit_json, path, text, _sets(set), bounds, os.fspath(data), []))
    rows = _fit_rows(data)
    return json.loads(_call(_tensegrity.fit_json, path, text, _sets(set), bounds, None, rows))


class Structure:
    """A structure made in Python (``from_matrices``, ``from_ntrt``, ``from_toml``) as the
    scenario file it is, checked when made: ``toml`` (the text), ``name`` (the file name its
    errors carry), ``skipped`` (what an import left out), ``sources`` (the files it was read
    from). ``run``, ``check``, ``sweep`` and ``export_mjcf`` take it as they take a path."""

    def __init__(self, toml: str, name: str = "structure.toml", skipped: Sequence[str] = (),
                 sources: Sequence[Union[str, "os.PathLike[str]"]] = ()) -> None:
        self.toml, self.name = str(toml), str(name)
        self.skipped = list(skipped)
        self.sources = [os.fspath(p) for p in sources]
        self.scenario_name = _call(_tensegrity.check, self.name, self.toml, [])

    def to_toml(self) -> str:
        """The scenario file's text."""
        return self.toml

    def write(self, path: Union[str, "os.PathLike[str]"]) -> Path:
        """Writes the scenario file to ``path`` as the CLI writes its outputs: through a
        temporary file and a rename (never half-written), never over one of ``sources`` (nor
        over anything but a regular file: ValueError). Returns the path."""
        _tensegrity.write_scenario(os.fspath(path), self.toml, self.sources)
        return Path(path)

    def __str__(self) -> str:
        return self.toml

    def __repr__(self) -> str:
        return f"<Structure {self.scenario_name!r} ({self.name})>"


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


def _per_member(name: str, value, count: int, what: str, dtype=float) -> list:
    """A scalar or one value per member as a list of ``count`` values, or ValueError naming the
    argument: a wrong length, or a value that is not a finite number."""
    import numpy as np

    try:
        a = np.asarray(value, dtype=dtype)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number or one per {what}, got {value!r}") from None
    if a.ndim == 0:
        a = np.full(count, a[()], dtype=dtype)
    if a.ndim != 1 or len(a) != count:
        raise ValueError(f"{name} has shape {a.shape}: expected one number or {count} (one per {what})")
    if dtype is float:
        bad = np.flatnonzero(~np.isfinite(a))
        if len(bad):
            raise ValueError(f"{name}[{bad[0]}] is {a[bad[0]]}, not a finite number")
    return a.tolist()


def from_matrices(
    N,
    Cb,
    Cs,
    bar_mass_kg=1.0,
    bar_radius_m=0.01,
    string_stiffness_n_per_m=100.0,
    string_tension_n=None,
    *,
    string_rest_length_m=None,
    tension_only=True,
    clusters=None,
    pins: Optional[Mapping[str, Optional[Sequence[float]]]] = None,
    quantities: Optional[Mapping[str, str]] = None,
    params: Optional[Mapping[str, Any]] = None,
    motion: Optional[Mapping[str, Any]] = None,
    energy: Optional[Mapping[str, Any]] = None,
    name: str = "from_matrices.toml",
) -> Structure:
    """A structure from numpy arrays in the notation of Skelton and de Oliveira: N (3 x n node
    coordinates [m]), Cb and Cs (one row per bar or string: -1 at its first node, 1 at its
    second). As ``tensegrity import matrices`` makes it: node k (column k, from 1) is ``n<k>``,
    bar i (row i of Cb, from 1) the strut ``bar<i>`` on its own body, string i ``string<i>``;
    nodes on no bar are fixed (body "ground"), else bar1 is held.

    Member properties, each one number or an array of one per member (rows of Cb or Cs):
    ``bar_mass_kg`` [kg], ``bar_radius_m`` [m], ``string_stiffness_n_per_m`` [N/m], and the
    strings' rest lengths, from ``string_tension_n`` [N] at the drawn length (rest = drawn -
    tension / stiffness) or given as ``string_rest_length_m`` [m]. Neither given: the drawn
    structure's own self-stress with its least string tension 10 N (every string at 10 N where
    the drawing has none with every string taut), as ``tensegrity import matrices`` chooses;
    the scenario's description says which.
    ``tension_only``: True (default) for cables, False (one or per string) for linear springs
    that push as well (zero rest length allowed). ``clusters``: a clustering matrix S as CTSFEM
    writes it (one row per clustered cable, one column per string, 1 where the string is a
    segment of it): each row's strings become one cable ``cluster<r>`` through their nodes, one
    tension in every segment, its stiffness theirs in series (rows must not overlap; a row's
    strings make one path or ring). ``pins``: bar nodes joined to the ground,
    ``{"n1": (0, 0, 1)}`` a revolute joint ``pin_n1`` about that axis, ``{"n1": None}`` a
    spherical one. ``quantities``: ``{"q": "atan2(n2.y - n1.y, n2.x - n1.x)"}``, the
    scenario's ``[[quantities]]`` (expressions of the state), for predictions to compare with.
    ``params``, ``motion``, ``energy``: the scenario's ``[params]``, ``[motion]`` and ``[energy]``
    sections as dicts, exactly as the file writes them (``motion={"duration_s": 4.0, "start":
    "settled", "coordinate": "pin_n1", "displacement": 1e-3, "frequencies": [{"name": "omega",
    "mode": 1, "tolerance": 1e-6}]}``): a motion run, a dynamic model, from Python.
    ``name``: the file name its errors carry (the scenario is named by its stem).

    The physics is the scenario file's: a bar's inertia is the file's default for a body
    without ``inertia`` (m l^2 / 12 about every axis, a thin rod's about its middle; the radius
    only draws it and checks interference), so the same bar written in TOML and made here has
    the same frequencies. The bodies and pins are damped so that the structure settles
    (``[sim] body_damping``, each pin's ``damping``); ``[motion] undamped = true`` releases it
    for a free vibration.

    Raises ValueError on a wrong shape or length (naming the argument and the expected length),
    a value that is not finite or out of range, a malformed connectivity row (``Cb[2]: ...``)
    or a bad pin; ScenarioError on a bad quantity expression."""
    n = _matrix("N", N, rows=3)
    cb = _matrix("Cb", Cb, cols=n.shape[1])
    cs = _matrix("Cs", Cs, cols=n.shape[1])
    bars, strings = cb.shape[0], cs.shape[0]
    if string_rest_length_m is None and string_tension_n is None:
        tension, rest = None, None
    elif string_rest_length_m is None:
        tension, rest = _per_member("string_tension_n", string_tension_n, strings, "string"), None
    elif string_tension_n is None:
        tension, rest = None, _per_member("string_rest_length_m", string_rest_length_m, strings, "string")
    else:
        raise ValueError("give string_tension_n or string_rest_length_m, not both")
    pin_list = []
    for node, axis in dict(pins or {}).items():
        if axis is not None:
            a = _matrix(f"pins[{node!r}]", [axis], rows=1, cols=3)[0]
            axis = a.tolist()
        pin_list.append((str(node), axis))
    text = _tensegrity.structure_from_arrays(
        Path(name).stem,
        n.tolist(), cb.tolist(), cs.tolist(),
        _per_member("bar_mass_kg", bar_mass_kg, bars, "bar"),
        _per_member("bar_radius_m", bar_radius_m, bars, "bar"),
        _per_member("string_stiffness_n_per_m", string_stiffness_n_per_m, strings, "string"),
        tension,
        rest,
        _per_member("tension_only", tension_only, strings, "string", dtype=bool),
        pin_list,
        [(str(k), str(v)) for k, v in (quantities or {}).items()],
        [] if clusters is None else _matrix("clusters", clusters, cols=strings).tolist(),
    )
    sections = {k: dict(v) for k, v in (("params", params), ("motion", motion), ("energy", energy)) if v is not None}
    if sections:
        text = text.rstrip("\n") + "\n\n" + _tensegrity.sections_toml(json.dumps(sections))
    return Structure(text, name=name)


def from_ntrt(source: Union[str, "os.PathLike[str]"], keep_axes: bool = False, name: str = "<string>.yaml") -> Structure:
    """A structure from an NTRT YAML model (``tensegrity import ntrt``): a path, or the YAML
    text itself named ``name`` (its substructures' paths then relative to the working
    directory). NTRT's y (up) becomes z unless ``keep_axes``; rods become struts on rigid
    bodies, strings elastic tension-only cables (numbers taken as SI). What the testbed does not
    model is listed in ``Structure.skipped``. Raises ScenarioError at ``file:line:col``."""
    path, text = _source(source, name)
    toml, skipped = _call(_tensegrity.import_ntrt, path, text, keep_axes)
    stem = Path(path).stem or "ntrt"
    return Structure(toml, name=f"{stem}.toml", skipped=skipped, sources=[path] if text is None else [])


def from_toml(source: Union[str, "os.PathLike[str]"], name: str = "<string>.toml") -> Structure:
    """A scenario from a path or from TOML text named ``name``, checked (ScenarioError at its
    file, line and column), to run or to write back (``Structure.write``)."""
    path, text = _source(source, name)
    if text is None:
        return Structure(Path(path).read_text(), name=path, sources=[path])
    return Structure(text, name=path)


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
