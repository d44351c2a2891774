"""What a simulator reports: one executed action (an Episode) or a dispatched sequence of them.

Logs carry *named* state columns (the simulator declares them), so code outside a robot's package reads
`episode.column("x")`, never a robot-specific array.

Besides its duration an executed action reports named *measures* (Ch. 8.1: what to optimise besides time),
each in the unit its simulator declares in `SimulatorEntry.units`; a measure a simulator does not define is
absent:
- "energy" (J): the mechanical energy the motors spent during the action, the integral of |force . velocity|
  + |torque . angular velocity| over its motors (braking costs too: nothing is recovered); each bundled
  simulator documents what it integrates, with which masses and moments of inertia;
- "error" (m): the distance between the commanded subgoal and the state reached at the action's end (which
  point of the robot, and which state, each simulator documents);
- "heading_error" (rad, in [0, pi]): the angle between the goal's heading and the one reached, where the goal
  has a heading.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

SUCCESS = "success"
# s charged on top of a failed run's time where runs are compared (the evaluations): a failure is as bad as
# waiting for one more action to time out (the mobile robots' action timeout)
FAILED_RUN_PENALTY = 30.0
ENERGY, ERROR, HEADING_ERROR = "energy", "error", "heading_error"  # the bundled simulators' measures


class Measures(Mapping[str, float]):
    """An action's measures, name -> finite value: an immutable mapping (unlike a MappingProxyType it pickles,
    so episodes cross to and from worker processes)."""

    __slots__ = ("_values",)

    def __init__(self, values: Mapping[str, float] | Iterable[tuple[str, float]] = ()):
        items = dict(values)
        for name, value in items.items():
            if not isinstance(name, str) or not name:
                raise ValueError(f"a measure's name is a non-empty string, not {name!r}")
            if not math.isfinite(float(value)):
                raise ValueError(f"measure {name!r} must be a finite number, got {value!r}")
        self._values = {name: float(value) for name, value in items.items()}

    def __getitem__(self, name: str) -> float:
        return self._values[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __hash__(self) -> int:
        return hash(frozenset(self._values.items()))

    def __repr__(self) -> str:
        return f"Measures({self._values!r})"

    def __reduce__(self):
        return Measures, (self._values,)


def _column_index(columns: tuple[str, ...], name: str, what: str) -> int:
    try:
        return columns.index(name)
    except ValueError:
        raise KeyError(f"{what} has no state column {name!r} (columns: {', '.join(columns)})") from None


@dataclass(frozen=True, eq=False)
class Episode:
    """One execution of one action from its initial state until success or failure, logged at 10 Hz.

    `params` are the action's parameters at the start (observed, then internal: the ActionSpec's order);
    `state` is the logged (believed, noisy) state at times `t`, one column per name in `columns`; `measures`
    what else it measured besides its duration (the module doc: "energy", "error", "heading_error"), empty
    where the simulator (or the log, or the file) defines none.
    """

    action: str
    params: np.ndarray  # (p,)
    t: np.ndarray  # (n,)
    state: np.ndarray  # (n, c)
    columns: tuple[str, ...]  # names of the c state columns
    outcome: str  # "success" or the simulator's failure name ("collision", "timeout", ...)
    duration: float
    seed: int
    measures: Mapping[str, float] = field(default_factory=Measures)

    def __post_init__(self) -> None:
        if not isinstance(self.measures, Measures):
            object.__setattr__(self, "measures", Measures(self.measures))

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
    """One action of a dispatched sequence: its outcome, duration, start and measures (as its Episode's)."""

    action: str
    outcome: str
    duration: float
    start: float  # simulated time at which the action started
    measures: Mapping[str, float] = field(default_factory=Measures)

    def __post_init__(self) -> None:
        if not isinstance(self.measures, Measures):
            object.__setattr__(self, "measures", Measures(self.measures))


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
        results.append(ActionResult(call.action, episode.outcome, episode.duration, start, episode.measures))
        if not episode.succeeded:
            break
    return SequenceResult(tuple(results), np.array(trajectory, dtype=float).reshape(-1, len(columns)), columns)
