"""The executable action sequence (Sec. 5.3): each continuous parameter BOUND to a value or FREE in a range.

A parameter's id names the object and quantity it stands for ("pos2.phi"), so the goal pose of one action and
the start pose of the next share one free parameter and are optimized once (Fig. 5.6).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from types import MappingProxyType

import numpy as np

from tailor.errors import EmptyRangeError, TailorError

SCHEMA = 1
RANGE_TOLERANCE = 1e-9  # values this far outside a range (rounding) are clipped into it, not rejected

_NO_ASSIGNMENT: Mapping[str, float] = MappingProxyType({})


@dataclass(frozen=True)
class Parameter:
    """One continuous action parameter; free iff `value` is None, always within [low, high]."""

    id: str
    name: str
    value: float | None
    low: float
    high: float

    @property
    def free(self) -> bool:
        return self.value is None

    def to_json(self) -> dict:
        return {"id": self.id, "name": self.name, "value": self.value, "low": self.low, "high": self.high}

    @classmethod
    def from_json(cls, data: Mapping) -> "Parameter":
        value = data["value"]
        return cls(str(data["id"]), str(data["name"]), None if value is None else float(value),
                   float(data["low"]), float(data["high"]))


@dataclass(frozen=True)
class ExecutableAction:
    """Plan step `step` (`pddl`, e.g. "(move p0 p1)") as executable `action` with its params.

    `guard` names a success classifier whose predicted-success region the parameters must lie in (Alg. 6: the
    duration term is invalid outside); `origin` says why subgoal assertion inserted or replaced the action
    (empty for an action the plan step maps to as it is). Several actions may serve one plan step.
    """

    step: int
    pddl: str
    action: str
    params: tuple[Parameter, ...]  # in the ActionSpec's order: observed then internal (x, y, phi, v, xg, ...)
    guard: str = ""
    origin: str = ""
    guard_margin: float = 0.0  # share of each free range around a choice where the guard must predict success

    def free_parameters(self) -> tuple[Parameter, ...]:
        return tuple(p for p in self.params if p.free)

    def values(self, assignment: Mapping[str, float] = _NO_ASSIGNMENT) -> np.ndarray:
        """The parameter vector, free parameters taken from `assignment` by id."""
        out = np.empty(len(self.params))
        for i, p in enumerate(self.params):
            if p.value is not None:
                out[i] = p.value
            elif p.id in assignment:
                out[i] = assignment[p.id]
            else:
                raise TailorError(f"no value for free parameter '{p.id}' ({p.name} of {self.action}, "
                                  f"step {self.step})")
        return out

    def to_json(self) -> dict:
        data = {"step": self.step, "pddl": self.pddl, "action": self.action,
                "params": [p.to_json() for p in self.params]}
        data.update({k: v for k, v in (("guard", self.guard), ("origin", self.origin),
                                       ("guard_margin", self.guard_margin)) if v})
        return data

    @classmethod
    def from_json(cls, data: Mapping) -> "ExecutableAction":
        return cls(int(data["step"]), str(data["pddl"]), str(data["action"]),
                   tuple(Parameter.from_json(p) for p in data["params"]), str(data.get("guard", "")),
                   str(data.get("origin", "")), float(data.get("guard_margin", 0.0)))


@dataclass(frozen=True)
class ActionSequence:
    """The instantiated plan: executable actions in step order, and the scene objects' initial values."""

    domain: str
    problem: str
    actions: tuple[ExecutableAction, ...]
    scene: Mapping[str, tuple[float, ...]]  # e.g. {"robot": (x, y, phi, v), "box": (x, y)}
    simulator: str = ""  # the registered simulator its actions run in

    def free_parameters(self) -> tuple[Parameter, ...]:
        """The free parameters, unique by id, in order of first use."""
        seen: dict[str, Parameter] = {}
        for action in self.actions:
            for p in action.free_parameters():
                seen.setdefault(p.id, p)
        return tuple(seen.values())

    def bind(self, assignment: Mapping[str, float], *, partial: bool = False) -> "ActionSequence":
        """A copy with the free parameters bound to `assignment` (by id); every one of them unless `partial`.

        A value within RANGE_TOLERANCE of its range is clipped into it; further out is an EmptyRangeError.
        Ids that are not free parameters of this sequence are an error (a typo must not pass silently).
        """
        free = {p.id: p for p in self.free_parameters()}
        for key in assignment:
            if key not in free:
                raise TailorError(f"cannot bind '{key}': not a free parameter of this sequence "
                                  f"(free: {', '.join(free) or 'none'})")
        if not partial:
            missing = [key for key in free if key not in assignment]
            if missing:
                raise TailorError(f"no value for free parameter(s) {', '.join(missing)}")
        values = {key: _checked(free[key], value) for key, value in assignment.items()}
        actions = tuple(
            replace(a, params=tuple(replace(p, value=values[p.id]) if p.free and p.id in values else p
                                    for p in a.params))
            for a in self.actions
        )
        return replace(self, actions=actions)

    def to_json(self) -> dict:
        return {"schema": SCHEMA, "domain": self.domain, "problem": self.problem,
                "actions": [a.to_json() for a in self.actions],
                "scene": {name: list(values) for name, values in self.scene.items()}, "simulator": self.simulator}

    @classmethod
    def from_json(cls, data: Mapping) -> "ActionSequence":
        if data.get("schema") != SCHEMA:
            raise TailorError(f"action sequence of schema {data.get('schema')!r} (expected {SCHEMA})")
        try:
            return cls(str(data["domain"]), str(data["problem"]),
                       tuple(ExecutableAction.from_json(a) for a in data["actions"]),
                       MappingProxyType({k: tuple(float(v) for v in vs) for k, vs in data["scene"].items()}),
                       str(data.get("simulator", "")))
        except (KeyError, TypeError, ValueError) as exc:
            raise TailorError(f"malformed action sequence JSON: {exc!r}") from None


def _checked(p: Parameter, value: float) -> float:
    value = float(value)
    if not math.isfinite(value):
        raise EmptyRangeError(f"value {value} for '{p.id}' is not a finite number")
    if not (p.low - RANGE_TOLERANCE <= value <= p.high + RANGE_TOLERANCE):
        raise EmptyRangeError(f"value {value:g} for '{p.id}' lies outside its range [{p.low:g}, {p.high:g}]")
    return min(max(value, p.low), p.high)
