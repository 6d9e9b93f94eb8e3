import os
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union, final

__all__ = [
    "check",
    "run_json",
    "sweep_csv",
    "structure_from_arrays",
    "import_ntrt",
    "write_scenario",
    "export_mjcf",
    "solve",
    "modes_json",
    "sensitivity_json",
    "sections_toml",
    "findings",
    "ArrowTable",
    "TestbedError",
]

# A path as `PathBuf` takes it: a str or an os.PathLike.
_Path = Union[str, "os.PathLike[str]"]

class TestbedError(Exception): ...

# A #[pyclass] without `subclass`: Python cannot derive from it.
@final
class ArrowTable:
    """Every tick of a run as Arrow record batches in memory: `tick` (UInt64), the other columns
    of `tensegrity run --table FILE.arrow` (Float64, SI units: m, rad, N, N m, s, J; null where
    the CSV leaves a cell empty). An Arrow PyCapsule producer: `pyarrow.table(t)` takes the
    batches without copying; can be read any number of times."""

    def __arrow_c_stream__(self, requested_schema: Optional[Any] = None) -> Any:
        """A PyCapsule "arrow_array_stream" (`requested_schema` is not applied)."""
    def __arrow_c_schema__(self) -> Any:
        """A PyCapsule "arrow_schema"."""
    @property
    def num_rows(self) -> int: ...
    @property
    def column_names(self) -> List[str]: ...
    def __len__(self) -> int: ...
    def __repr__(self) -> str: ...

def check(path: str, text: Optional[str] = None, set: Sequence[str] = ...) -> str:
    """The scenario's name; TestbedError(file, line, col, message) when it is refused."""

def run_json(
    path: str,
    text: Optional[str] = None,
    set: Sequence[str] = ...,
    table: bool = False,
    model: Optional[Callable[[Dict[str, float], Dict[str, float], Optional[float]], Dict[str, float]]] = None,
    predictions: Sequence[Tuple[str, str, str, float, Optional[float]]] = ...,
) -> Tuple[str, Optional[ArrowTable]]:
    """The run's report (one scenario) as JSON and, with `table`, every tick in memory (None
    when no tick ran); `model` and `predictions` (name, quantity, class, tolerance [m, rad or
    relative], rms tolerance): a Python model compared as the file's predictions are."""

def sweep_csv(path: str, text: Optional[str] = None, set: Sequence[str] = ..., jobs: int = 0) -> Tuple[str, str]:
    """(the CSV of `tensegrity sweep --out`, the JSON summary of `--json`)."""

def structure_from_arrays(
    name: str,
    n: Sequence[Sequence[float]],
    cb: Sequence[Sequence[float]],
    cs: Sequence[Sequence[float]],
    bar_mass_kg: Sequence[float],
    bar_radius_m: Sequence[float],
    string_stiffness_n_per_m: Sequence[float],
    string_tension_n: Optional[Sequence[float]],
    string_rest_length_m: Optional[Sequence[float]],
    tension_only: Sequence[bool],
    pins: Sequence[Tuple[str, Optional[Sequence[float]]]],
    quantities: Sequence[Tuple[str, str]],
) -> str:
    """A scenario's TOML from N (3 rows, m), Cb and Cs as rows and one property per member (kg,
    m, N/m, N or m); ValueError (`Cb[2]: ...`, `bar_mass_kg[1] must be ...`) when refused."""

def import_ntrt(path: _Path, text: Optional[str] = None, keep_axes: bool = False) -> Tuple[str, List[str]]:
    """(a scenario's TOML, what was skipped) from NTRT YAML at `path` or given as `text`."""

def write_scenario(path: _Path, text: str, inputs: Sequence[_Path]) -> None:
    """Writes `text` to `path` atomically, never over one of `inputs` (ValueError)."""

def export_mjcf(
    path: str, text: Optional[str] = None, set: Sequence[str] = ..., actuators: str = "mocap", kp: float = 1e6, cable_damping: float = 0.0
) -> Tuple[str, List[str]]:
    """(the MJCF XML, what was not exported)."""

def solve(mechanism: str, query: str, values: Dict[str, float]) -> List[Tuple[str, Dict[str, float], Optional[bool]]]:
    """Every solution of an analytic query: (label, values, stable)."""

def modes_json(path: str, text: Optional[str] = None, set: Sequence[str] = ...) -> str:
    """The modal analysis of ``tensegrity modes --json``, as its JSON text."""

def sensitivity_json(path: str, text: Optional[str] = None, set: Sequence[str] = ..., check: bool = False,
                     point: int = 0) -> str:
    """The sensitivities of ``tensegrity sensitivity --json`` (``--check`` with ``check``, at
    ``--point point``), as its JSON text."""

def fit_json(path: str, text: Optional[str] = None, set: Sequence[str] = ...,
             params: Sequence[Tuple[str, Optional[float], Optional[float]]] = ..., data_path: Optional[_Path] = None,
             rows: Sequence[Tuple[str, int, str, float, Optional[float]]] = ...) -> str:
    """The fit of ``tensegrity fit --json`` (parameters as (name, low, high), the data from the
    CSV at ``data_path`` or as (where, point, output, value, sigma) rows), as its JSON text."""

def sections_toml(json: str) -> str:
    """Scenario sections given as a JSON object, as TOML text."""

def findings(mechanism: str, params: Dict[str, float]) -> List[Tuple[str, str, str, bool]]:
    """(equation, claim, measured, holds) for every printed equation checked."""
