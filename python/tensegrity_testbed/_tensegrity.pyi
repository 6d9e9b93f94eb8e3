from typing import Callable, Mapping, Optional, Sequence, Tuple

class TestbedError(Exception): ...

def check(path: str, text: Optional[str] = None, set: Sequence[str] = ...) -> str:
    """The scenario's name; TestbedError(file, line, col, message) when it is refused."""

def run_json(
    path: str,
    text: Optional[str] = None,
    set: Sequence[str] = ...,
    table: Optional[str] = None,
    model: Optional[Callable[[dict, dict, Optional[float]], Mapping[str, float]]] = None,
    predictions: Sequence[Tuple[str, str, str, float, Optional[float]]] = ...,
) -> str:
    """The run's report (one scenario) as JSON; `table`: every tick written to this file;
    `model` and `predictions` (name, quantity, class, tolerance, rms tolerance): a Python model
    compared as the file's predictions are."""

def sweep_csv(path: str, text: Optional[str] = None, set: Sequence[str] = ..., jobs: int = 0) -> Tuple[str, str]:
    """(the CSV of `tensegrity sweep --out`, the JSON summary of `--json`)."""

def import_matrices(
    n: str, cb: str, cs: str, bar_mass_kg: float, bar_radius_m: float, string_stiffness_n_per_m: float, string_tension_n: float
) -> str:
    """A scenario's TOML from N, Cb and Cs in CSV files (`tensegrity import matrices`)."""
