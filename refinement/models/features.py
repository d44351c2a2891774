"""Feature spaces of action models (Table 4.1), a registry chosen per action in the domain's data, and the
intermediate examples of an episode (Sec. 4.1.2).

Features exploit the invariances of an action: for a navigation to a pose only the goal pose relative to the robot
matters, so its 8 parameters (x, y, phi, v, xg, yg, phig, vg) map to a few features that do not change when
the whole scene is translated, rotated or mirrored. Each space declares the action parameters it reads and
a random transform of them under which its features must not change: its invariance test.

Refinement minimizes over the headings and speeds at subgoals analytically (App. C.3.4) where every feature
is piecewise affine in each free parameter: only wraps (norm), absolute values and sign flips of headings
and speeds appear in the pose, joint and line spaces, never products or trigonometry of them. The reach row
of Table 4.1 (angles between joint-space directions) is not: refinement falls back to the GA there.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from tailor.errors import DataError
from tailor.sims import registry
from tailor.sims.episode import Episode
from tailor.sims.invariances import rigid_motion, shift_mirror_axes
from tailor.sims.pose import POSE, POSE_PARAMETERS, pose_parts, sgn
from tailor.sims.protocol import FeatureSpace

Transform = Callable[[np.ndarray, np.random.Generator], np.ndarray]


# --- pose: navigation to a pose (x, y, phi, v -> xg, yg, phig, vg): Table 4.1's row, tailor.sims.pose ------
def _pose_selection(names: tuple[str, ...]) -> Callable[[np.ndarray], np.ndarray]:
    def compute(params: np.ndarray) -> np.ndarray:
        parts = pose_parts(params)
        return np.column_stack([parts[name] for name in names])

    return compute


POSE_DELTA = POSE + ("delta_angle",)
POSITION = ("v", "dist", "angle_to")  # Table 4.1's goToPosition row: no goal heading, arrival speed fixed


# --- joints: a reach in joint space (theta_a, omega_a, theta_b, omega_b -> the same at the goal) ----------
JOINT_PARAMETERS = ("theta_a", "omega_a", "theta_b", "omega_b", "theta_ga", "omega_ga", "theta_gb", "omega_gb")


def _joint_vectors(params: np.ndarray):
    ta, wa, tb, wb, tga, wga, tgb, wgb = params.T
    return np.column_stack([tga - ta, tgb - tb]), np.column_stack([wa, wb]), np.column_stack([wga, wgb])


def _angle_between(u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Angle (rad, in [0, pi]) between the rows of u and w; 0 where either is the zero vector."""
    cross = u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0]
    return np.abs(np.arctan2(cross, np.einsum("ij,ij->i", u, w)))


def _reach(params: np.ndarray) -> np.ndarray:
    """Table 4.1's reach row: joint-space distance, the angle between the direction to the goal and the
    current joint velocity, the same at the goal, and the two joint speeds."""
    delta, w, wg = _joint_vectors(params)
    return np.column_stack([np.hypot(delta[:, 0], delta[:, 1]), _angle_between(delta, w), _angle_between(delta, wg),
                            np.hypot(w[:, 0], w[:, 1]), np.hypot(wg[:, 0], wg[:, 1])])


def _joints(params: np.ndarray) -> np.ndarray:
    """Per joint: the distance to go and the start and goal velocities along it (signed toward the goal)."""
    delta, w, wg = _joint_vectors(params)
    s = sgn(delta)
    return np.column_stack([np.abs(delta[:, 0]), w[:, 0] * s[:, 0], wg[:, 0] * s[:, 0],
                            np.abs(delta[:, 1]), w[:, 1] * s[:, 1], wg[:, 1] * s[:, 1]])


def _joint_shift_mirror(params: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Each joint's start and goal shifted by one offset, and (half the time) each joint mirrored."""
    return shift_mirror_axes(params, rng, ((0, 1), (2, 3)), goal_offset=4)


def _joint_rotation(params: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Joint space rotated about any point (what the reach row's features assume away)."""
    angle, shift = rng.uniform(-np.pi, np.pi), rng.uniform(-1, 1, 2)
    c, s = np.cos(angle), np.sin(angle)
    out = params.copy()
    for a, b in ((0, 2), (1, 3), (4, 6), (5, 7)):
        out[:, a], out[:, b] = c * params[:, a] - s * params[:, b], s * params[:, a] + c * params[:, b]
    for a, b in ((0, 2), (4, 6)):
        out[:, a] += shift[0]
        out[:, b] += shift[1]
    return out


# --- line: a move along one axis (x, v -> xg, vg) --------------------------------------------------------
def _line(params: np.ndarray) -> np.ndarray:
    """Distance to go and the start and goal velocities signed toward the goal."""
    x, v, xg, vg = params.T
    s = sgn(xg - x)
    return np.column_stack([np.abs(xg - x), v * s, vg * s])


def _line_shift_mirror(params: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    return shift_mirror_axes(params, rng, ((0, 1),), goal_offset=2, shift=5.0)


FEATURE_SPACES: dict[str, FeatureSpace] = {}


def register_feature_space(space: FeatureSpace, replace: bool = False) -> FeatureSpace:
    """Add a feature space to the registry (a robot package may bring its own)."""
    if space.name in FEATURE_SPACES and FEATURE_SPACES[space.name] is not space and not replace:
        raise ValueError(f"a feature space named {space.name!r} is already registered")
    FEATURE_SPACES[space.name] = space
    return space


for _space in (
    FeatureSpace("pose", POSE_PARAMETERS, POSE, _pose_selection(POSE),
                 "translation, rotation and mirroring of the scene", rigid_motion),
    FeatureSpace("pose_delta", POSE_PARAMETERS, POSE_DELTA, _pose_selection(POSE_DELTA),
                 "translation, rotation and mirroring of the scene", rigid_motion),
    FeatureSpace("position", POSE_PARAMETERS, POSITION, _pose_selection(POSITION),
                 "translation, rotation and mirroring of the scene", rigid_motion),
    FeatureSpace("reach", JOINT_PARAMETERS, ("dist", "angle_to", "angle_at", "speed", "speed_g"), _reach,
                 "translation and rotation of joint space (Table 4.1)", _joint_rotation),
    FeatureSpace("joints", JOINT_PARAMETERS, ("dist_a", "v_a", "vg_a", "dist_b", "v_b", "vg_b"), _joints,
                 "translation and mirroring of each joint", _joint_shift_mirror),
    FeatureSpace("line", ("x", "v", "xg", "vg"), ("dist", "v", "vg"), _line,
                 "translation and mirroring of the axis", _line_shift_mirror),
):
    register_feature_space(_space)


def feature_spaces() -> dict[str, FeatureSpace]:
    """Every feature space: the generic ones here and those the registered simulators bring."""
    spaces = dict(FEATURE_SPACES)
    for entry in registry.simulators().values():
        for space in entry.feature_spaces:
            spaces.setdefault(space.name, space)
    return spaces


def feature_space(name: str) -> FeatureSpace:
    """The feature space `name`; one a simulator brings is looked up once, then kept with the generic ones
    (every prediction asks for its space: the optimizers' hot path)."""
    space = FEATURE_SPACES.get(name)
    if space is None:
        spaces = feature_spaces()
        if name not in spaces:
            raise DataError(f"unknown feature space {name!r} (known: {', '.join(sorted(spaces))})")
        space = FEATURE_SPACES.setdefault(name, spaces[name])
    return space


def feature_names(name: str) -> tuple[str, ...]:
    return feature_space(name).names


def compute_features(name: str, params: np.ndarray) -> np.ndarray:
    """Map action parameters (n, p) (or one row (p,)) to the features (n, f) of feature space `name`."""
    return feature_space(name)(params)


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
