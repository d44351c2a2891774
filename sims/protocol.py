"""The simulator protocol and the declaration of executable actions (Table 2.1).

A robot package provides a `SimulatorEntry`: its executable actions (each with an observed parameter group,
read from the world, and an internal one, the subgoal, each group with its own quantities), a factory of
simulators that follow `Simulator`, the experience scenarios its actions are learned from, and the random
situations of its problems that evaluations draw. The core finds entries in the registry (`tailor.sims.registry`)
and never imports a robot by name.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Protocol, runtime_checkable

import numpy as np

from tailor.sims.episode import ActionCall, Episode, SequenceResult

GROUPS = ("observed", "internal")  # parameter groups of an action, in parameter order

Scene = Mapping[str, Sequence[float]]  # scene object -> its values, e.g. {"robot": (x, y, phi, v)}


@dataclass(frozen=True)
class ActionSpec:
    """An executable action: its parameter names per group and the object quantity each one takes.

    a navigation to a pose: observed (x, y, phi, v) of quantities (x, y, phi, v), internal (xg, yg, phig, vg) of
    the same quantities of the goal object; a manipulator grasp: observed base pose, internal gripper target.
    """

    name: str
    simulator: str
    observed: tuple[str, ...]
    internal: tuple[str, ...]
    observed_quantities: tuple[str, ...]
    internal_quantities: tuple[str, ...]

    def __post_init__(self) -> None:
        for group in GROUPS:
            names, quantities = self.group(group)
            if len(names) != len(quantities):
                raise ValueError(f"action {self.name}: {group} has {len(names)} names but {len(quantities)} quantities")
        if len(set(self.parameters)) != len(self.parameters):
            raise ValueError(f"action {self.name}: parameter names must be distinct: {self.parameters}")

    @property
    def parameters(self) -> tuple[str, ...]:
        return self.observed + self.internal

    @property
    def quantities(self) -> tuple[str, ...]:
        """Every quantity either group takes, without repeats."""
        return tuple(dict.fromkeys(self.observed_quantities + self.internal_quantities))

    def group(self, group: str) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """(parameter names, quantities) of group "observed" or "internal"."""
        if group == "observed":
            return self.observed, self.observed_quantities
        if group == "internal":
            return self.internal, self.internal_quantities
        raise ValueError(f"unknown parameter group {group!r} (expected one of {', '.join(GROUPS)})")


@runtime_checkable
class Simulator(Protocol):
    """A headless simulator of one robot: reset to a scene, execute actions, log named state columns."""

    state_columns: tuple[str, ...]  # names of the Episode.state columns (believed state)

    def reset(self, scene: Scene) -> None:
        """Place the scene objects (as the belief state's binding names them) at rest or at their speeds."""

    def run(self, call: ActionCall) -> Episode:
        """Execute one action from the current state until success or failure."""

    def run_sequence(self, calls: Sequence[ActionCall]) -> SequenceResult:
        """Execute actions one after the other without stopping between them; stop at the first failure."""


@dataclass(frozen=True)
class Scenario:
    """An experience scenario (Sec. 4.1): `run(seed)` executes one episode of `action` from a random initial
    and goal state drawn from documented ranges; the episode depends only on the seed."""

    name: str
    action: str
    run: Callable[[int], Episode]
    description: str = ""


@dataclass(frozen=True)
class FeatureSpace:
    """A row of Table 4.1: the action parameters it reads (in order), its feature names, the map between
    them, and a random change of the parameters its features are invariant to (described in words): its
    invariance test. The generic spaces live in tailor.refinement.models.features; a robot may bring its own
    in its SimulatorEntry."""

    name: str
    parameters: tuple[str, ...]
    names: tuple[str, ...]
    compute: Callable[[np.ndarray], np.ndarray]  # (n, len(parameters)) -> (n, len(names))
    invariance: str
    transform: Callable[[np.ndarray, np.random.Generator], np.ndarray] | None = None

    def __call__(self, params: np.ndarray) -> np.ndarray:
        params = np.atleast_2d(np.asarray(params, dtype=float))
        if params.ndim != 2 or params.shape[1] != len(self.parameters):
            raise ValueError(f"feature space {self.name!r} takes parameters of shape (n, {len(self.parameters)}) "
                             f"({', '.join(self.parameters)}), got {params.shape}")
        return self.compute(params)


Situation = Callable[[np.random.Generator], tuple[str, dict[str, dict[str, float]]]]
"""A random situation for an evaluation: rng -> (problem name, belief values per object)."""

SubgoalEpisode = Callable[[str, np.ndarray, int], Episode]
"""(action, its parameter vector at a refined subgoal, seed) -> an episode from there (Sec. 8.1 experience)."""


@dataclass(frozen=True)
class SimulatorEntry:
    """What a robot package registers: its name, actions, simulator factory, scenarios and situations."""

    name: str
    actions: Mapping[str, ActionSpec]
    create: Callable[..., Simulator]  # create(seed, noise=None): noise None is the simulator's default noise
    scenarios: Mapping[str, Scenario] = field(default_factory=dict)
    situations: Mapping[str, Situation] = field(default_factory=dict)
    subgoal_episode: SubgoalEpisode | None = None
    views: tuple = ()  # trajectory columns worth drawing: pairs ("x", "y") or layers (("x", "y", "phi"), ...)
    feature_spaces: tuple[FeatureSpace, ...] = ()  # feature spaces of its own (Table 4.1 rows)
    scene_objects: tuple[str, ...] = ()  # the objects reset(scene) places; () = not declared (not checked)
    # draw_scene(ax, sequence, values): draws the static world of an instantiated sequence (its scene, its
    # free parameters' ranges and their chosen `values` by id) under the first view's trajectories in pictures
    draw_scene: Callable[[Any, Any, Mapping[str, float]], None] | None = None
    description: str = ""
    extras: Mapping[str, Any] = field(default_factory=dict)
    team: Any = None  # a tailor.sims.team.TeamScene for the coordination experiments (Ch. 7), or None

    def __post_init__(self) -> None:
        for key, spec in self.actions.items():
            if spec.name != key or spec.simulator != self.name:
                raise ValueError(f"simulator {self.name}: action {key!r} declares name {spec.name!r} and "
                                 f"simulator {spec.simulator!r}")
        for key, scenario in self.scenarios.items():
            if scenario.action not in self.actions:
                raise ValueError(f"simulator {self.name}: scenario {key!r} runs unknown action {scenario.action!r}")
        object.__setattr__(self, "actions", MappingProxyType(dict(self.actions)))
        object.__setattr__(self, "scenarios", MappingProxyType(dict(self.scenarios)))
        object.__setattr__(self, "situations", MappingProxyType(dict(self.situations)))

    @property
    def quantities(self) -> tuple[str, ...]:
        """Every quantity its actions take, without repeats."""
        return tuple(dict.fromkeys(q for spec in self.actions.values() for q in spec.quantities))

    def action(self, name: str) -> ActionSpec:
        from tailor.errors import SimError

        try:
            return self.actions[name]
        except KeyError:
            raise SimError(f"simulator {self.name!r} has no action {name!r} (known: {', '.join(self.actions)})") from None
