"""Simulators and the executable actions of the action library (Table 2.1).

`ACTIONS` is the registry the action library binding refers to by name: each executable action declares
its parameter groups, observed (read from the world at dispatch) and internal (the subgoal), and the
quantities of a PDDL object each parameter takes (x, y, phi, v).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ActionSpec:
    name: str
    simulator: str
    observed: tuple[str, ...]  # parameter names, read from the belief / the world
    internal: tuple[str, ...]  # parameter names of the subgoal
    quantities: tuple[str, ...]  # the object quantity each group position stands for

    @property
    def parameters(self) -> tuple[str, ...]:
        return self.observed + self.internal


_POSE = dict(observed=("x", "y", "phi", "v"), internal=("xg", "yg", "phig", "vg"), quantities=("x", "y", "phi", "v"))

ACTIONS: dict[str, ActionSpec] = {
    "goToPose": ActionSpec("goToPose", "soccer", **_POSE),
    "approachBall": ActionSpec("approachBall", "soccer", **_POSE),
    "dribbleBall": ActionSpec("dribbleBall", "soccer", **_POSE),
}
