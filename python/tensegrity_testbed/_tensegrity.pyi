from typing import Optional, Sequence

class TestbedError(Exception): ...

def check(path: str, text: Optional[str] = None, set: Sequence[str] = ...) -> str:
    """The scenario's name; TestbedError(file, line, col, message) when it is refused."""

def run_json(path: str, text: Optional[str] = None, set: Sequence[str] = ..., table: Optional[str] = None) -> str:
    """The run's report (one scenario) as JSON; `table`: every tick written to this file."""
