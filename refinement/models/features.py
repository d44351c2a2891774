"""Derived feature spaces of action models (Table 4.1) and intermediate examples (Sec. 4.1.2).

Features exploit the invariances of an action: only the goal pose relative to the robot matters, so the
8 action parameters (x, y, phi, v, xg, yg, phig, vg) map to a few projective features that do not change
when the whole scene is translated, rotated or mirrored.

Refinement later minimizes over the headings and speeds at subgoals analytically (App. C.3.4), so with the
positions fixed every feature must be piecewise affine in each of phi, phig, v and vg: only wraps (norm),
absolute values and sign flips of headings appear here, never products or trigonometry of them.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from tailor.refinement.errors import DataError
from tailor.sims.episode import PARAMETER_NAMES, Episode

N_PARAMS = len(PARAMETER_NAMES)
X, Y, PHI, V, XG, YG, PHIG, VG = range(N_PARAMS)


def norm(angle: np.ndarray) -> np.ndarray:
    """Wrap angles (rad) to [-pi, pi) by adding or subtracting 2 pi (norm() of Table 4.1)."""
    return np.mod(np.asarray(angle, dtype=float) + np.pi, 2.0 * np.pi) - np.pi


def _sgn(a: np.ndarray) -> np.ndarray:
    """Sign with sgn(0) = +1, so that angle_at keeps its information when the goal lies dead ahead."""
    return np.where(a < 0.0, -1.0, 1.0)


def _pose_parts(params: np.ndarray) -> dict[str, np.ndarray]:
    """The quantities of Table 4.1 for goToPose-like actions, one value per row of params (n, 8)."""
    dx = params[:, XG] - params[:, X]
    dy = params[:, YG] - params[:, Y]
    bearing = np.arctan2(dy, dx)  # direction from the robot to the goal position; constant for fixed positions
    angle_to_signed = norm(bearing - params[:, PHI])
    return {
        "v": params[:, V],
        "vg": params[:, VG],
        "dist": np.hypot(dx, dy),
        "angle_to": np.abs(angle_to_signed),
        "angle_at": _sgn(angle_to_signed) * norm(params[:, PHIG] - bearing),
        "delta_angle": np.abs(norm(params[:, PHIG] - params[:, PHI])),
    }


def _selection(names: tuple[str, ...]) -> Callable[[np.ndarray], np.ndarray]:
    def compute(params: np.ndarray) -> np.ndarray:
        parts = _pose_parts(params)
        return np.column_stack([parts[name] for name in names])

    return compute


POSE = ("v", "vg", "dist", "angle_to", "angle_at")
POSE_DELTA = POSE + ("delta_angle",)

# name -> (feature names, function (n, 8) action parameters -> (n, f) features)
FEATURE_SETS: dict[str, tuple[tuple[str, ...], Callable[[np.ndarray], np.ndarray]]] = {
    "pose": (POSE, _selection(POSE)),
    "pose_delta": (POSE_DELTA, _selection(POSE_DELTA)),
}


def feature_names(feature_set: str) -> tuple[str, ...]:
    return _lookup(feature_set)[0]


def compute_features(feature_set: str, params: np.ndarray) -> np.ndarray:
    """Map action parameters (n, 8) (or one row (8,)) to the features (n, f) of `feature_set`."""
    params = np.atleast_2d(np.asarray(params, dtype=float))
    if params.ndim != 2 or params.shape[1] != N_PARAMS:
        raise ValueError(f"action parameters must have shape (n, {N_PARAMS}), got {params.shape}")
    return _lookup(feature_set)[1](params)


def _lookup(feature_set: str) -> tuple[tuple[str, ...], Callable[[np.ndarray], np.ndarray]]:
    try:
        return FEATURE_SETS[feature_set]
    except KeyError:
        known = ", ".join(sorted(FEATURE_SETS))
        raise DataError(f"unknown feature set {feature_set!r} (known: {known})") from None


def intermediate_examples(episodes: list[Episode], n_i: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The first n_i logged rows of each episode as examples (Sec. 4.1.2).

    Row k of an episode gives the action parameters (logged robot pose at t_k, the episode's goal) and the
    remaining time duration - t_k. Returns params (m, 8), targets (m,), and the episode index of each row.
    n_i = 1 yields the first example of each episode only (what test sets use).
    """
    if n_i < 1:
        raise ValueError(f"n_i must be at least 1, got {n_i}")
    params, targets, owner = [], [], []
    for index, episode in enumerate(episodes):
        rows = min(n_i, len(episode.t))
        if rows == 0:
            raise DataError(f"episode {index} (seed {episode.seed}) has no logged state")
        block = np.empty((rows, N_PARAMS))
        block[:, :4] = episode.robot[:rows]
        block[:, 4:] = episode.params[4:]
        params.append(block)
        targets.append(episode.duration - episode.t[:rows])
        owner.append(np.full(rows, index))
    if not params:
        return np.empty((0, N_PARAMS)), np.empty(0), np.empty(0, dtype=int)
    return np.concatenate(params), np.concatenate(targets), np.concatenate(owner)


def first_examples(episodes: list[Episode]) -> tuple[np.ndarray, np.ndarray]:
    """Test examples: the first example of each episode, (params (n, 8), durations (n,))."""
    params, targets, _ = intermediate_examples(episodes, 1)
    return params, targets
