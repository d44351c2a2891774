"""What a simulator reports: one executed action (an Episode) or a dispatched sequence of them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

PARAMETER_NAMES = ("x", "y", "phi", "v", "xg", "yg", "phig", "vg")
SUCCESS = "success"


@dataclass(frozen=True, eq=False)
class Episode:
    """One execution of one action from its initial state until success or failure, logged at 10 Hz.

    `params` are the action's parameters at the start (observed x, y, phi, v; internal xg, yg, phig, vg);
    `robot` is the logged (noisy, as the robot believes it) dynamic pose at times `t`, `ball` the logged
    ball position (NaN where the scene has no ball).
    """

    action: str
    params: np.ndarray  # (8,)
    t: np.ndarray  # (n,)
    robot: np.ndarray  # (n, 4) x, y, phi, v
    ball: np.ndarray  # (n, 2)
    outcome: str  # "success", "collision", "ball_lost", "timeout"
    duration: float
    seed: int

    @property
    def succeeded(self) -> bool:
        return self.outcome == SUCCESS


@dataclass(frozen=True)
class ActionCall:
    """An executable action with its internal (goal) parameters; observed ones come from the world."""

    action: str
    goal: tuple[float, float, float, float]  # xg, yg, phig, vg


@dataclass(frozen=True)
class ActionResult:
    action: str
    outcome: str
    duration: float
    start: float  # simulated time at which the action started


@dataclass(frozen=True, eq=False)
class SequenceResult:
    """A dispatched sequence: per-action results and the true trajectory (t, x, y, phi, v, ball_x, ball_y)."""

    results: tuple[ActionResult, ...]
    trajectory: np.ndarray  # (n, 7) at 10 Hz

    @property
    def succeeded(self) -> bool:
        return all(r.outcome == SUCCESS for r in self.results) and len(self.results) > 0

    @property
    def duration(self) -> float:
        return float(sum(r.duration for r in self.results))
