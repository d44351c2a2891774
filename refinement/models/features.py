"""Feature spaces of action models (Table 4.1), a registry chosen per action in the domain's data, and the
intermediate examples of an episode (Sec. 4.1.2).

Features exploit the invariances of an action: for a navigation to a pose only the goal pose relative to the robot
matters, so its 8 parameters map to a few features that do not change when the whole scene is translated, rotated
or mirrored. Each space declares the action parameters it reads and a random transform of them under which its
features must not change: its invariance test.

The rows of Table 4.1 that describe one kind of robot (a mobile base's pose, a manipulator's joints) come with
the robot package that has them (its SimulatorEntry's feature_spaces) and are found through the simulator
registry; the one here assumes no robot: "line", a move along one axis. Refinement minimizes over free
parameters analytically (App. C.3.4) where every feature is piecewise affine in each of them (wraps, absolute
values and sign flips, never products or trigonometry), as in "line"; elsewhere it falls back to the GA.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from tailor.errors import DataError
from tailor.sims import registry
from tailor.sims.episode import Episode
from tailor.sims.intervals import axis
from tailor.sims.invariances import shift_mirror_axes
from tailor.sims.protocol import FeatureSpace

Transform = Callable[[np.ndarray, np.random.Generator], np.ndarray]


# --- line: a move along one axis (x, v -> xg, vg) --------------------------------------------------------
def _line(params: np.ndarray) -> np.ndarray:
    """Distance to go and the start and goal velocities signed toward the goal (the sign of 0 is +1, so that the
    speeds keep their information at a goal where the move starts)."""
    x, v, xg, vg = params.T
    s = np.where(xg - x < 0.0, -1.0, 1.0)
    return np.column_stack([np.abs(xg - x), v * s, vg * s])


def _line_bounds(low: np.ndarray, high: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A guaranteed enclosure of `_line` over boxes of parameters (FeatureSpace.bounds): sims.intervals.axis."""
    columns = [(a, b) for a, b in zip(np.atleast_2d(low).T, np.atleast_2d(high).T)]
    pairs = axis(*columns)
    return np.column_stack([p[0] for p in pairs]), np.column_stack([p[1] for p in pairs])


def _line_shift_mirror(params: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    return shift_mirror_axes(params, rng, ((0, 1),), goal_offset=2, shift=5.0)


FEATURE_SPACES: dict[str, FeatureSpace] = {}  # the registered ones: the core's, and any added in-process
_BROUGHT: dict[str, FeatureSpace] = {}  # spaces the simulators bring, kept here once looked up


def register_feature_space(space: FeatureSpace, replace: bool = False) -> FeatureSpace:
    """Add a feature space to the registry (a robot package brings its own in its SimulatorEntry instead)."""
    if space.name in FEATURE_SPACES and FEATURE_SPACES[space.name] is not space and not replace:
        raise ValueError(f"a feature space named {space.name!r} is already registered")
    FEATURE_SPACES[space.name] = space
    return space


register_feature_space(FeatureSpace("line", ("x", "v", "xg", "vg"), ("dist", "v", "vg"), _line,
                                    "translation and mirroring of the axis", _line_shift_mirror, _line_bounds))


def feature_spaces() -> dict[str, FeatureSpace]:
    """Every feature space: the generic ones here and those the registered simulators bring."""
    spaces = dict(FEATURE_SPACES)
    for entry in registry.simulators().values():
        for space in entry.feature_spaces:
            spaces.setdefault(space.name, space)
    return spaces


def feature_space(name: str) -> FeatureSpace:
    """The feature space `name`; one a simulator brings is looked up once, then kept (every prediction asks for
    its space: the optimizers' hot path)."""
    space = FEATURE_SPACES.get(name) or _BROUGHT.get(name)
    if space is None:
        spaces = feature_spaces()
        if name not in spaces:
            raise DataError(f"unknown feature space {name!r} (known: {', '.join(sorted(spaces))})")
        space = _BROUGHT.setdefault(name, spaces[name])
    return space


def resolve(space: str | FeatureSpace) -> FeatureSpace:
    """A feature space given by name (registered, or brought by a simulator) or as itself (a generated one)."""
    return space if isinstance(space, FeatureSpace) else feature_space(space)


def feature_names(name: str | FeatureSpace) -> tuple[str, ...]:
    return resolve(name).names


def compute_features(name: str | FeatureSpace, params: np.ndarray) -> np.ndarray:
    """Map action parameters (n, p) (or one row (p,)) to the features (n, f) of feature space `name` (a name or
    the space itself)."""
    return resolve(name)(params)


def raw_space(parameters: Sequence[str]) -> FeatureSpace:
    """The action's parameters themselves as features (what a learner without features sees; Fig. 4.3's first
    column)."""
    return FeatureSpace("raw", tuple(parameters), tuple(parameters), lambda params: np.asarray(params, dtype=float),
                        "nothing", None,
                        lambda low, high: (np.asarray(low, dtype=float), np.asarray(high, dtype=float)))


def intermediate_examples(episodes: list[Episode], n_i: int, observed: Sequence[str]
                          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The first n_i logged rows of each episode as examples (Sec. 4.1.2).

    Row k of an episode gives the action parameters (the `observed` parameters read from the state logged at
    t_k, the episode's goal) and the remaining time duration - t_k. Returns params (m, p), targets (m,), and
    the episode index of each row. n_i = 1 yields the first example of each episode only (what tests use).
    """
    if n_i < 1:
        raise ValueError(f"n_i must be at least 1, got {n_i}")
    observed = tuple(observed)
    k = len(observed)
    params, targets, owner = [], [], []
    for index, episode in enumerate(episodes):
        rows = min(n_i, len(episode.t))
        if rows == 0:
            raise DataError(f"episode {index} (seed {episode.seed}) has no logged state")
        block = np.empty((rows, len(episode.params)))
        block[:, :k] = episode.columns_of(observed)[:rows]
        block[:, k:] = episode.params[k:]
        params.append(block)
        targets.append(episode.duration - episode.t[:rows])
        owner.append(np.full(rows, index))
    if not params:
        return np.empty((0, 0)), np.empty(0), np.empty(0, dtype=int)
    return np.concatenate(params), np.concatenate(targets), np.concatenate(owner)


def first_examples(episodes: list[Episode]) -> tuple[np.ndarray, np.ndarray]:
    """Test examples: the parameters each episode started with and its duration, (params (n, p), (n,))."""
    if not episodes:
        return np.empty((0, 0)), np.empty(0)
    return np.array([e.params for e in episodes], dtype=float), np.array([e.duration for e in episodes], dtype=float)
