"""What a simulator reports: one executed action (an Episode) or a dispatched sequence of them.

Logs carry *named* state columns (the simulator declares them), so code outside a robot's package reads
`episode.column("x")`, never a robot-specific array.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

SUCCESS = "success"


def _column_index(columns: tuple[str, ...], name: str, what: str) -> int:
    try:
        return columns.index(name)
    except ValueError:
        raise KeyError(f"{what} has no state column {name!r} (columns: {', '.join(columns)})") from None


@dataclass(frozen=True, eq=False)
class Episode:
    """One execution of one action from its initial state until success or failure, logged at 10 Hz.

    `params` are the action's parameters at the start (observed, then internal: the ActionSpec's order);
    `state` is the logged (believed, noisy) state at times `t`, one column per name in `columns`.
    """

    action: str
    params: np.ndarray  # (p,)
    t: np.ndarray  # (n,)
    state: np.ndarray  # (n, c)
    columns: tuple[str, ...]  # names of the c state columns
    outcome: str  # "success" or the simulator's failure name ("collision", "timeout", ...)
    duration: float
    seed: int

    @property
    def succeeded(self) -> bool:
        return self.outcome == SUCCESS

    def column(self, name: str) -> np.ndarray:
        """The logged values of one named state column, (n,)."""
        return self.state[:, _column_index(self.columns, name, f"episode of {self.action}")]

    def columns_of(self, names: Sequence[str]) -> np.ndarray:
        """The logged values of several named columns, (n, len(names))."""
        return self.state[:, [_column_index(self.columns, n, f"episode of {self.action}") for n in names]]


@dataclass(frozen=True)
class ActionCall:
    """An executable action with its internal (goal) parameters; observed ones come from the world."""

    action: str
    goal: tuple[float, ...]  # the ActionSpec's internal parameters, in order


@dataclass(frozen=True)
class ActionResult:
    action: str
    outcome: str
    duration: float
    start: float  # simulated time at which the action started


@dataclass(frozen=True, eq=False)
class SequenceResult:
    """A dispatched sequence: per-action results and the true trajectory at 10 Hz, one column per name in
    `columns` (the first is the time "t")."""

    results: tuple[ActionResult, ...]
    trajectory: np.ndarray  # (n, len(columns))
    columns: tuple[str, ...] = ("t",)

    @property
    def succeeded(self) -> bool:
        return all(r.outcome == SUCCESS for r in self.results) and len(self.results) > 0

    @property
    def duration(self) -> float:
        return float(sum(r.duration for r in self.results))

    def column(self, name: str) -> np.ndarray:
        return self.trajectory[:, _column_index(self.columns, name, "trajectory")]

    def has_column(self, name: str) -> bool:
        return name in self.columns


def run_in_sequence(execute, calls, clock, columns: tuple[str, ...]) -> SequenceResult:
    """Dispatch `calls` back to back without stopping: `execute(call, trajectory)` runs one action, appending
    true states (rows of `columns`) to the shared trajectory, and `clock()` tells the simulated time; stop at
    the first failure. The shared loop of every simulator's `run_sequence`."""
    trajectory: list[tuple[float, ...]] = []
    results = []
    for call in calls:
        start = clock()
        episode = execute(call, trajectory)
        results.append(ActionResult(call.action, episode.outcome, episode.duration, start))
        if not episode.succeeded:
            break
    return SequenceResult(tuple(results), np.array(trajectory, dtype=float).reshape(-1, len(columns)), columns)
