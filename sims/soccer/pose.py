"""Table 4.1's pose row, the features of a navigation to a pose seen from the robot, in one place.

A navigation (x, y, phi, v -> xg, yg, phig, vg) maps to v, vg, the distance to the goal, the angle the goal lies
off the heading (angle_to) and the goal heading seen from the line to it (angle_at), signed so that mirroring the
scene changes nothing. The soccer robot's feature spaces all start from it: "pose" (the row), "pose_delta" (with
the turn from start to goal heading), "position" (goToPosition's row: no goal heading), and those that add what
the pose row cannot see (the path its controllers plan, sims.soccer.features; the walls, sims.soccer.walls).

Every feature is piecewise affine in each heading and speed (only wraps (norm), absolute values and sign flips of
them appear, never products or trigonometry), so refinement minimizes over the headings and speeds at subgoals
analytically (App. C.3.4).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from tailor.sims.protocol import FeatureSpace

POSE_PARAMETERS = ("x", "y", "phi", "v", "xg", "yg", "phig", "vg")
POSE = ("v", "vg", "dist", "angle_to", "angle_at")
POSE_DELTA = POSE + ("delta_angle",)
POSITION = ("v", "dist", "angle_to")  # Table 4.1's goToPosition row: no goal heading, arrival speed fixed


def norm(angle: np.ndarray) -> np.ndarray:
    """Wrap angles (rad) to [-pi, pi) by adding or subtracting 2 pi (norm() of Table 4.1)."""
    return np.mod(np.asarray(angle, dtype=float) + np.pi, 2.0 * np.pi) - np.pi


def sgn(a: np.ndarray) -> np.ndarray:
    """Sign with sgn(0) = +1, so that a feature keeps its information when the goal lies dead ahead."""
    return np.where(a < 0.0, -1.0, 1.0)


def pose_parts(params: np.ndarray) -> dict[str, np.ndarray]:
    """The pose row's features of each row of `params` (M, 8 in POSE_PARAMETERS' order), and delta_angle."""
    x, y, phi, v, xg, yg, phig, vg = params.T
    dx, dy = xg - x, yg - y
    bearing = np.arctan2(dy, dx)  # direction from the robot to the goal position; constant for fixed positions
    angle_to_signed = norm(bearing - phi)
    return {
        "v": v,
        "vg": vg,
        "dist": np.hypot(dx, dy),
        "angle_to": np.abs(angle_to_signed),
        "angle_at": sgn(angle_to_signed) * norm(phig - bearing),
        "delta_angle": np.abs(norm(phig - phi)),
    }


def pose_row(params: np.ndarray) -> np.ndarray:
    """(M, 5) the pose row, columns in POSE's order."""
    parts = pose_parts(params)
    return np.column_stack([parts[name] for name in POSE])


def rigid_motion(params: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A navigation's parameters (x, y, phi, v, xg, yg, phig, vg) with the scene rotated, translated and (half
    the time) mirrored about the x axis."""
    angle, (sx, sy), mirror = rng.uniform(-np.pi, np.pi), rng.uniform(-5, 5, 2), rng.random() < 0.5
    out = params.copy()
    c, s = np.cos(angle), np.sin(angle)
    for ix, iy, iphi in ((0, 1, 2), (4, 5, 6)):
        x, y = params[:, ix], params[:, iy]
        out[:, ix], out[:, iy] = c * x - s * y + sx, s * x + c * y + sy
        out[:, iphi] = params[:, iphi] + angle
        if mirror:
            out[:, iy], out[:, iphi] = -out[:, iy], -out[:, iphi]
    return out


def _selection(names: tuple[str, ...]) -> Callable[[np.ndarray], np.ndarray]:
    def compute(params: np.ndarray) -> np.ndarray:
        parts = pose_parts(params)
        return np.column_stack([parts[name] for name in names])

    return compute


RIGID = "translation, rotation and mirroring of the scene"
POSE_SPACE = FeatureSpace("pose", POSE_PARAMETERS, POSE, _selection(POSE), RIGID, rigid_motion)
POSE_DELTA_SPACE = FeatureSpace("pose_delta", POSE_PARAMETERS, POSE_DELTA, _selection(POSE_DELTA), RIGID,
                                rigid_motion)
POSITION_SPACE = FeatureSpace("position", POSE_PARAMETERS, POSITION, _selection(POSITION), RIGID, rigid_motion)
