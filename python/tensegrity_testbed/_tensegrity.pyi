from typing import Callable, Dict, List, Mapping, Optional, Sequence, Tuple

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

def export_mjcf(
    path: str, text: Optional[str] = None, set: Sequence[str] = ..., actuators: str = "mocap", kp: float = 1e6, cable_damping: float = 0.0
) -> Tuple[str, List[str]]:
    """(the MJCF XML, what was not exported)."""

def solve(mechanism: str, query: str, values: Mapping[str, float]) -> List[Tuple[str, Dict[str, float], Optional[bool]]]:
    """Every solution of an analytic query: (label, values, stable)."""

def findings(mechanism: str, params: Mapping[str, float]) -> List[Tuple[str, str, str, bool]]:
    """(equation, claim, measured, holds) for every printed equation checked."""
