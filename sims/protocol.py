"""The simulator protocol and the declaration of executable actions (Table 2.1).

A robot package provides a `SimulatorEntry`: its executable actions (each with an observed parameter group,
read from the world, and an internal one, the subgoal, each group with its own quantities), a factory of
simulators that follow `Simulator`, the experience scenarios its actions are learned from, and the random
situations of its problems that evaluations draw; and, as data, what its quantities are (a unit, whether an
angle) and which pictures of it can be drawn. The core finds entries in the registry (`tailor.sims.registry`)
and never imports a robot by name: it asks these declarations, never guesses from a name.
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
    the same quantities of the goal object; a manipulator's reach to a point: observed the robot's own
    quantities, internal the point's.
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


@runtime_checkable
class Observable(Protocol):
    """A simulator the closed loop can run (tailor.execution): besides `Simulator`, what the robot measures now,
    between two actions. Both read the believed (noisy) state, as the robot's own sensors would."""

    def observe(self, action: str) -> tuple[float, ...]:
        """The observed parameter group of `action` (its ActionSpec's `observed`, in order) as measured now: what
        `run(ActionCall(action, ...))` would log as the first values of `Episode.params`."""

    def scene(self) -> dict[str, tuple[float, ...]]:
        """Every scene object's measured values now, in the form `reset` takes (so `reset(scene())` places the
        world as the robot believes it to be)."""


@dataclass(frozen=True)
class Quantity:
    """What a simulator's quantity (or logged state column) is: its unit ("m", "rad", "m/s"; "" where none is
    declared) and whether it is an angle (a value on the circle: shown in degrees, drawn on polar axes where its
    range spans the full circle)."""

    unit: str = ""
    angle: bool = False


UNDECLARED = Quantity()  # what a quantity a simulator says nothing about is: no unit, not an angle


@dataclass(frozen=True)
class DurationCurve:
    """A picture of learned duration models a simulator can draw (Fig. 4.7): the predicted duration in one
    situation, parameter `varied` swept over the full circle (an angle), every other parameter at its value in
    `situation` (0 where not given). Drawn for each model whose feature space reads `varied` and every parameter
    of `situation`; `label` names the swept value on the axes (what it means in this situation, e.g. the angle
    of approach where the goal lies straight ahead), `meaning` says it in words, `description` the situation."""

    varied: str
    label: str
    situation: Mapping[str, float]
    description: str
    meaning: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "situation", MappingProxyType(dict(self.situation)))

    @property
    def parameters(self) -> frozenset[str]:
        """The action parameters the picture sets: a model must read them all."""
        return frozenset((self.varied, *self.situation))


@dataclass(frozen=True)
class SuccessRegion:
    """A picture of learned success classifiers a simulator can draw (Fig. 4.8): where a classifier predicts
    failure, over starts on a square grid of parameters `x` and `y` within `half_size` of the goal at the
    origin; parameter `heading` points from each start toward the origin, turned by each of `turns` (rad, with
    the panel's title); every other parameter at its value in `situation` (0 where not given). Drawn for each
    classifier whose feature space reads them all. `goal` labels the origin in the legend, `goal_heading` (a
    parameter of `situation`, or "") is drawn there as an arrow; `description` titles the picture, "{action}"
    replaced by the classifier's action."""

    x: str
    y: str
    heading: str
    half_size: float
    turns: tuple[tuple[float, str], ...]
    situation: Mapping[str, float]
    description: str
    goal: str = "goal"
    goal_heading: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "situation", MappingProxyType(dict(self.situation)))

    @property
    def parameters(self) -> frozenset[str]:
        return frozenset((self.x, self.y, self.heading, *self.situation))


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
    # a guaranteed enclosure of the features over boxes of parameters, for the certified optimizer: (low, high),
    # each (k, len(parameters)), -> (feature_low, feature_high), each (k, len(names)); None: the space has none
    bounds: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]] | None = None

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
    # create(seed, noise=None, disturbance=None, variant=None): noise None is the simulator's default noise;
    # disturbance / variant name one of `disturbances` / `variants` below (None: none, the robot as modelled)
    create: Callable[..., Simulator]
    scenarios: Mapping[str, Scenario] = field(default_factory=dict)
    situations: Mapping[str, Situation] = field(default_factory=dict)
    subgoal_episode: SubgoalEpisode | None = None
    # trajectory columns worth drawing: pairs ("x", "y") or layers (("x", "y", "phi"), ...), a layer's third
    # column a heading drawn as arrows
    views: tuple = ()
    feature_spaces: tuple[FeatureSpace, ...] = ()  # feature spaces of its own (Table 4.1 rows)
    scene_objects: tuple[str, ...] = ()  # the objects reset(scene) places; () = not declared (not checked)
    # draw_scene(ax, sequence, values): draws the static world of an instantiated sequence (its scene, its
    # free parameters' ranges and their chosen `values` by id) under the first view's trajectories in pictures
    draw_scene: Callable[[Any, Any, Mapping[str, float]], None] | None = None
    description: str = ""
    extras: Mapping[str, Any] = field(default_factory=dict)
    team: Any = None  # a tailor.sims.team.TeamScene for the coordination experiments (Ch. 7), or None
    # quantity or state column -> its unit and whether it is an angle (pictures and printed values ask it);
    # one not declared is UNDECLARED
    units: Mapping[str, Quantity] = field(default_factory=dict)
    # pictures of its learned models it can draw, besides the learning curves every simulator gets: Fig. 4.7's
    # DurationCurve, Fig. 4.8's SuccessRegion
    model_pictures: tuple[DurationCurve | SuccessRegion, ...] = ()
    # seeded disturbances of the world it can add to a run (name -> what happens, in words; Ch. 8.1: an object
    # pushed by someone else while the robot works): part of the scene, never known to refinement in advance
    disturbances: Mapping[str, str] = field(default_factory=dict)
    # changed robots it can simulate (name -> what changed, in words; Ch. 8.1: weaker motors, a payload): the
    # learned models do not know them; learning in operation adapts to them
    variants: Mapping[str, str] = field(default_factory=dict)

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
        for name, quantity in self.units.items():
            if not isinstance(quantity, Quantity):
                raise ValueError(f"simulator {self.name}: units[{name!r}] must be a Quantity, got "
                                 f"{type(quantity).__name__}")
        object.__setattr__(self, "units", MappingProxyType(dict(self.units)))
        object.__setattr__(self, "disturbances", MappingProxyType(dict(self.disturbances)))
        object.__setattr__(self, "variants", MappingProxyType(dict(self.variants)))

    def unknown_option(self, disturbance: str | None = None, variant: str | None = None) -> str | None:
        """What is wrong with a disturbance or variant name this simulator does not declare (None: nothing); the
        API, the command line and `simulator` each raise it as their own error."""
        for kind, name, known in (("disturbance", disturbance, self.disturbances),
                                  ("variant", variant, self.variants)):
            if name is not None and name not in known:
                return f"simulator {self.name!r} has no {kind} {name!r} (known: {', '.join(known) or 'none'})"
        return None

    def simulator(self, seed: int, noise=None, disturbance: str | None = None, variant: str | None = None
                  ) -> Simulator:
        """A new simulator: `create` with a disturbance and a variant checked against those declared."""
        from tailor.errors import SimError

        wrong = self.unknown_option(disturbance, variant)
        if wrong is not None:
            raise SimError(wrong)
        if disturbance is None and variant is None:
            return self.create(seed, noise)
        return self.create(seed, noise, disturbance=disturbance, variant=variant)

    @property
    def quantities(self) -> tuple[str, ...]:
        """Every quantity its actions take, without repeats."""
        return tuple(dict.fromkeys(q for spec in self.actions.values() for q in spec.quantities))

    def quantity(self, name: str) -> Quantity:
        """What quantity `name` is (its unit, whether it is an angle), as this simulator declares it. `name` may
        be a quantity or state column ("phi"), a parameter id, which ends in its quantity ("pos2.phi"), or an
        action's parameter name ("phig", the goal's phi). UNDECLARED where the simulator says nothing of it."""
        if name in self.units:
            return self.units[name]
        if "." in name:
            return self.units.get(name.rpartition(".")[2], UNDECLARED)
        meant = {quantity for spec in self.actions.values() for parameter, quantity
                 in zip(spec.parameters, spec.observed_quantities + spec.internal_quantities) if parameter == name}
        return self.units.get(meant.pop(), UNDECLARED) if len(meant) == 1 else UNDECLARED

    def action(self, name: str) -> ActionSpec:
        from tailor.errors import SimError

        try:
            return self.actions[name]
        except KeyError:
            raise SimError(f"simulator {self.name!r} has no action {name!r} (known: {', '.join(self.actions)})") from None
