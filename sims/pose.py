"""Table 4.1's pose row, the features of a navigation to a pose seen from the robot, in one place.

A navigation (x, y, phi, v -> xg, yg, phig, vg) maps to v, vg, the distance to the goal, the angle the goal lies
off the heading (angle_to) and the goal heading seen from the line to it (angle_at), signed so that mirroring the
scene changes nothing. The generic spaces of tailor.refinement.models.features and a robot's own spaces (which
add what the pose row cannot see, e.g. the walls) all start from it; it lives in sims because sims never import
refinement.
"""

from __future__ import annotations

import numpy as np

POSE_PARAMETERS = ("x", "y", "phi", "v", "xg", "yg", "phig", "vg")
POSE = ("v", "vg", "dist", "angle_to", "angle_at")


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
