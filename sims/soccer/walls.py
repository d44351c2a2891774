"""The soccer robot's own feature space: the pose features plus what they are invariant to by design, the walls.

"pose_walls": Table 4.1's pose row (v, vg, dist, angle_to, angle_at) and, for the start and for the goal, the
clearance to the side walls and to the end walls and the heading's angle from each of those walls (0: heading
straight at it, pi: away). The pose row sees the goal only relative to the robot, so it cannot tell an approach
that has room behind the goal from one squeezed against a wall. A success classifier needs that (Sec. 4.2.2;
the ball is bumped where the robot's final arc has no room), a duration model does not, so only classifiers use
it. Each feature depends on one parameter once the position is fixed (clearances on x or y, angles on the
heading), so refinement still minimizes analytically over headings at a ball lying anywhere.
Invariant to mirroring the field about either axis (the walls are symmetric), not to moving the scene.
"""

from __future__ import annotations

import numpy as np
from tailor.sims.protocol import FeatureSpace
from tailor.sims.soccer.feature_bounds import pose_walls_bounds
from tailor.sims.soccer.pose import POSE, POSE_PARAMETERS, norm, pose_row, sgn
from tailor.sims.soccer.world import FIELD_HALF_LENGTH, FIELD_HALF_WIDTH, WALL_RUNOFF

WALLS = ("wall_x", "wall_y", "heading_x", "heading_y")
NAMES = POSE + tuple(f"start_{n}" for n in WALLS) + tuple(f"goal_{n}" for n in WALLS)
WALL_X = FIELD_HALF_LENGTH + WALL_RUNOFF  # m, the end walls stand at x = +-WALL_X
WALL_Y = FIELD_HALF_WIDTH + WALL_RUNOFF  # m, the side walls at y = +-WALL_Y


def wall_features(x: np.ndarray, y: np.ndarray, phi: np.ndarray) -> list[np.ndarray]:
    """Clearance to the nearer end wall and side wall, and the heading's angle from each wall's direction."""
    return [WALL_X - np.abs(x), WALL_Y - np.abs(y),
            np.abs(norm(phi - np.where(x < 0.0, np.pi, 0.0))),
            np.abs(norm(phi - sgn(y) * 0.5 * np.pi))]


def _pose_walls(params: np.ndarray) -> np.ndarray:
    x, y, phi, _, xg, yg, phig, _ = params.T
    return np.column_stack([pose_row(params), *wall_features(x, y, phi), *wall_features(xg, yg, phig)])


def mirror_field(params: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The scene mirrored about the x axis, the y axis, or both (a half turn), one of the three at random."""
    out = params.copy()
    flip_y, flip_x = ((True, False), (False, True), (True, True))[int(rng.integers(3))]
    for ix, iy, iphi in ((0, 1, 2), (4, 5, 6)):
        if flip_y:
            out[:, iy], out[:, iphi] = -out[:, iy], -out[:, iphi]
        if flip_x:
            out[:, ix], out[:, iphi] = -out[:, ix], np.pi - out[:, iphi]
    return out


POSE_WALLS = FeatureSpace("pose_walls", POSE_PARAMETERS, NAMES, _pose_walls,
                          "mirroring the field about either axis", mirror_field,
                          lambda low, high: pose_walls_bounds(low, high, WALL_X, WALL_Y))
