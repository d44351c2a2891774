"""A team scene: several robots of one simulator side by side, for the coordination experiments (Ch. 7).

A robot package that supports coordination provides a `TeamScene` (its SimulatorEntry's `team`): it simulates
the team (robots moving about, Fig. 7.6; robots waiting and then approaching the target in turn, Fig. 7.7),
says what each robot perceives (its own state, its teammates and the target, with noise and only inside its
field of view), and turns an estimated robot state and target position into the parameters of that robot's
approach action, whose learned model predicts the time it would take. Who should go is decided elsewhere
(tailor.refinement.evaluation.coordination), from these numbers only.

A robot's state is the scene's to declare (`TeamScene.state`: the quantities of its columns, e.g. position,
heading and speed); the target is a point in the plane of the state's first two columns, the robot's position.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np


@dataclass(frozen=True)
class Perception:
    """How well each robot knows itself, its teammates and the target (Sec. 7.4.1), and how it talks.

    Standard deviations of the Gaussian estimation noise of positions (m), and of headings (rad) and speeds
    (m/s) where the scene's robots have them (its `observe` applies what its state has); the field of view
    (degrees, 0 = blind, 360 = omnidirectional) inside which teammates and target are perceived; the share of
    packets the channel delivers (0..1) and the mean length of an outage (s); how long an estimate is kept
    without being renewed (s), and how fast its uncertainty grows meanwhile (m/s: a teammate may drive on, a
    target barely moves).
    """

    self_noise: float = 0.09
    teammate_noise: float = 0.25
    target_noise: float = 0.22
    self_heading_noise: float = math.radians(3.0)
    teammate_heading_noise: float = math.radians(10.0)
    speed_noise: float = 0.05
    field_of_view: float = 90.0
    communication: float = 1.0
    mean_outage: float = 1.0
    memory: float = 2.0
    target_memory: float = 30.0
    drift: float = 1.0
    target_drift: float = 0.05

    def __post_init__(self) -> None:
        if not 0.0 <= self.field_of_view <= 360.0:
            raise ValueError(f"field of view must lie in [0, 360] degrees, got {self.field_of_view}")
        if not 0.0 <= self.communication <= 1.0:
            raise ValueError(f"communication quality must lie in [0, 1], got {self.communication}")
        for name in ("self_noise", "teammate_noise", "target_noise", "self_heading_noise",
                     "teammate_heading_noise", "speed_noise", "memory", "target_memory", "drift", "target_drift"):
            if not getattr(self, name) >= 0.0:
                raise ValueError(f"{name} must not be negative, got {getattr(self, name)}")


@dataclass(frozen=True, eq=False)
class TeamLog:
    """The true course of a team scene, sampled every `period` seconds: robot states (T, N, d) in the order of
    the scene's `state`, the target position (T, 2), and each robot's kind."""

    period: float
    states: np.ndarray
    target: np.ndarray
    kinds: tuple[str, ...]

    @property
    def ticks(self) -> int:
        return len(self.states)

    def at(self, ticks: np.ndarray | slice) -> TeamLog:
        return TeamLog(self.period, self.states[ticks], self.target[ticks], self.kinds)


@dataclass(frozen=True, eq=False)
class Observations:
    """What each robot perceives every tick: its own state estimate (T, N, d); robot i's estimate of robot j
    (T, N, N, d), NaN where j is outside i's field of view (and on the diagonal); its estimate of the
    target (T, N, 2), NaN where outside its field of view."""

    own: np.ndarray
    others: np.ndarray
    target: np.ndarray


@dataclass(frozen=True)
class StaticSituation:
    """Fig. 7.7: the team's course to its waiting places (the last tick is when they decide) and the time each
    robot then took to approach the target from there, alone (None where its approach failed); `repeated`: the
    same approaches again under other noise, one tuple per repeat (how certain "the quickest" is in the
    simulator itself, and what an oracle of the expected times could choose)."""

    log: TeamLog
    measured: tuple[float | None, ...]
    repeated: tuple[tuple[float | None, ...], ...] = ()


@runtime_checkable
class TeamScene(Protocol):
    """What a robot package provides for coordination experiments."""

    kinds: Mapping[str, str]  # robot kind -> the action it approaches the target with (its utility)
    bounds: tuple[float, float, float, float]  # (xmin, xmax, ymin, ymax) of the scene, for pictures
    state: tuple[str, ...]  # the quantities of a robot's state columns, its position (in the target's plane) first
    perturbed: tuple[str, ...]  # those of them the estimation noise added in Q4 perturbs (in each one's unit)

    def team(self, robots: int, heterogeneous: bool) -> tuple[str, ...]:
        """The kinds of a team of `robots`; heterogeneous: one of them of another kind."""

    def dynamic(self, kinds: tuple[str, ...], duration: float, seed: int) -> TeamLog:
        """Robots moving about for `duration` seconds around a target lying still (Fig. 7.6)."""

    def static(self, kinds: tuple[str, ...], seed: int, repeats: int = 1) -> StaticSituation:
        """Robots move to random places and wait; then each approaches the target in turn (Fig. 7.7), and again
        `repeats` times under other noise."""

    def approach_time(self, kind: str, state: tuple[float, ...], target: tuple[float, float],
                      seed: int) -> float | None:
        """Fig. 7.7b: the time a robot of `kind` takes from `state` (standing) to `target`, alone; None if it
        fails."""

    def observe(self, log: TeamLog, perception: Perception, rng: np.random.Generator) -> Observations:
        """Noisy, field-of-view limited perception of every robot at every tick of `log`. The noise drawn does
        not depend on the field of view (only what is masked does), so settings can be compared pairwise."""

    def utility_parameters(self, kind: str, states: np.ndarray, target: np.ndarray) -> np.ndarray:
        """(M, p) parameters of the approach action of `kind` from robot states (M, d) to targets (M, 2)."""

    def distance(self, states: np.ndarray, target: np.ndarray) -> np.ndarray:
        """(M,) distance from each robot to the target (the baseline utility of Q3)."""

    def example(self) -> tuple[np.ndarray, tuple[str, ...], np.ndarray]:
        """Fig. 7.11: robot states (N, d) standing still, their kinds, and target positions (K, 2) along a line."""
