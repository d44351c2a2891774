"""The soccer robot's own feature space for approachBall (a Table 4.1 row of its own): the pose features and
the path its approach controller plans.

approachBall follows a Dubins path of turning radius R_APPROACH from the wheel axle to a pre-pose behind the
ball (sims.soccer.approach). Its duration is nearly linear in that path's length and in how much of it is arc
(arcs are driven slower than straights), but a discontinuous function of dist, angle_to and angle_at: where
the shortest word changes (a loop instead of a turn and a straight), the time jumps by seconds. A model tree on
the pose features alone must cut such a boundary out of scattered examples; from the team's standing starts a
metre or two from the ball it erred by up to 3 s there (`tailor coordinate`, README). With the planned length
and arc length as features, the boundary is in the features; the shortest exact word's length beside it flags
where the shortest word only nearly exists (a turn and a straight whose circles overlap a little: the robot
cannot quite follow it and may end up driving the loop).

Vectorized (numpy), Dubins (1957) in the normalized frame of Shkel & Lumelsky (2001) as in sims.soccer.dubins,
whose scalar candidates() it reproduces (tests): coordination predicts millions of approach times per run.
Walls and the ball's clearance are left out, so that the features stay invariant to moving the whole scene.
"""

from __future__ import annotations

import numpy as np
from tailor.sims.invariances import rigid_motion
from tailor.sims.protocol import FeatureSpace
from tailor.sims.soccer.approach import PRE_DISTANCE, R_APPROACH
from tailor.sims.soccer.dubins import TANGENT_SLACK, WORDS
from tailor.sims.soccer.world import BALL_POINT_OFFSET

TWO_PI = 2.0 * np.pi
POSE_PARAMETERS = ("x", "y", "phi", "v", "xg", "yg", "phig", "vg")
# Table 4.1's pose row (as the generic space "pose" computes it), then the planned path's length and its arcs'
APPROACH_FEATURES = ("v", "vg", "dist", "angle_to", "angle_at", "path", "arcs", "exact_path")


def _mod(a: np.ndarray) -> np.ndarray:
    return np.mod(a, TWO_PI)


def dubins_words(start: np.ndarray, goal: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """(M, 6, 3) segment lengths (m) of each word of WORDS from the poses `start` (M, 3) to `goal` (M, 3), NaN
    where a word does not exist (mixed words within TANGENT_SLACK of touching exist, as in candidates()), and
    (M, 6) whether each is exact (not such a near-touching mixed word)."""
    dx, dy = goal[:, 0] - start[:, 0], goal[:, 1] - start[:, 1]
    d = np.hypot(dx, dy) / radius
    th0 = np.where(d > 1e-9, np.arctan2(dy, dx), 0.0)
    alpha, beta = _mod(start[:, 2] - th0), _mod(goal[:, 2] - th0)
    sa, ca, sb, cb = np.sin(alpha), np.cos(alpha), np.sin(beta), np.cos(beta)
    cab = np.cos(alpha - beta)
    out = np.full((len(d), 6, 3), np.nan)
    exact = np.ones((len(d), 6), dtype=bool)
    with np.errstate(invalid="ignore"):
        p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sa - sb)  # LSL
        th = np.arctan2(cb - ca, d + sa - sb)
        out[:, 0] = np.where((p2 >= 0.0)[:, None], np.column_stack([_mod(th - alpha), np.sqrt(p2), _mod(beta - th)]),
                             np.nan)
        p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sb - sa)  # RSR
        th = np.arctan2(ca - cb, d - sa + sb)
        out[:, 1] = np.where((p2 >= 0.0)[:, None], np.column_stack([_mod(alpha - th), np.sqrt(p2), _mod(th - beta)]),
                             np.nan)
        p2 = -2.0 + d * d + 2.0 * cab + 2.0 * d * (sa + sb)  # LSR
        p = np.sqrt(np.maximum(p2, 0.0))
        th = np.arctan2(-ca - cb, d + sa + sb) - np.arctan2(-2.0, p)
        exact[:, 2] = p2 >= 0.0
        out[:, 2] = np.where((p2 >= -TANGENT_SLACK)[:, None], np.column_stack([_mod(th - alpha), p, _mod(th - beta)]),
                             np.nan)
        p2 = -2.0 + d * d + 2.0 * cab - 2.0 * d * (sa + sb)  # RSL
        p = np.sqrt(np.maximum(p2, 0.0))
        th = np.arctan2(ca + cb, d - sa - sb) - np.arctan2(2.0, p)
        exact[:, 3] = p2 >= 0.0
        out[:, 3] = np.where((p2 >= -TANGENT_SLACK)[:, None], np.column_stack([_mod(alpha - th), p, _mod(beta - th)]),
                             np.nan)
        c = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sa - sb)) / 8.0  # RLR
        p = _mod(TWO_PI - np.arccos(np.clip(c, -1.0, 1.0)))
        t = _mod(alpha - np.arctan2(ca - cb, d - sa + sb) + p / 2.0)
        out[:, 4] = np.where((np.abs(c) <= 1.0)[:, None], np.column_stack([t, p, _mod(alpha - beta - t + p)]), np.nan)
        c = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sb - sa)) / 8.0  # LRL
        p = _mod(TWO_PI - np.arccos(np.clip(c, -1.0, 1.0)))
        t = _mod(-alpha + np.arctan2(-ca + cb, d + sa - sb) + p / 2.0)
        out[:, 5] = np.where((np.abs(c) <= 1.0)[:, None], np.column_stack([t, p, _mod(beta - alpha - t + p)]), np.nan)
    full = TWO_PI - 1e-9  # an arc of (almost) a full turn is numerically zero, as in candidates()
    arc = np.array([[w[0] != "S", w[1] != "S", w[2] != "S"] for w in WORDS])
    out = np.where((out > full) & arc[None], 0.0, out)
    return out * radius, exact


def planned_path(params: np.ndarray) -> np.ndarray:
    """(M, 3): length (m) of the shortest Dubins path (R_APPROACH) from the axle to approachBall's pre-pose,
    plus the final straight; the length of its arcs; the length of the shortest exact one, plus the final
    straight (longer where the shortest is a near-touching mixed word the robot cannot quite follow)."""
    x, y, phi, _, xg, yg, phig, _ = params.T
    start = np.column_stack([x - BALL_POINT_OFFSET * np.cos(phi), y - BALL_POINT_OFFSET * np.sin(phi), phi])
    back = BALL_POINT_OFFSET + PRE_DISTANCE
    pre = np.column_stack([xg - back * np.cos(phig), yg - back * np.sin(phig), phig])
    words, exact = dubins_words(start, pre, R_APPROACH)
    total = np.where(np.isnan(words).any(axis=2), np.inf, words.sum(axis=2))
    best = np.argmin(total, axis=1)
    rows = np.arange(len(params))
    arc = np.array([[w[0] != "S", w[1] != "S", w[2] != "S"] for w in WORDS])
    arcs = (words[rows, best] * arc[best]).sum(axis=1)
    return np.column_stack([total[rows, best] + PRE_DISTANCE, arcs,
                            np.where(exact, total, np.inf).min(axis=1) + PRE_DISTANCE])


def _norm(angle: np.ndarray) -> np.ndarray:
    return np.mod(angle + np.pi, TWO_PI) - np.pi


def _approach(params: np.ndarray) -> np.ndarray:
    x, y, phi, v, xg, yg, phig, vg = params.T
    bearing = np.arctan2(yg - y, xg - x)
    angle_to = _norm(bearing - phi)
    sign = np.where(angle_to < 0.0, -1.0, 1.0)
    return np.column_stack([v, vg, np.hypot(xg - x, yg - y), np.abs(angle_to), sign * _norm(phig - bearing),
                            planned_path(params)])


APPROACH = FeatureSpace("approach", POSE_PARAMETERS, APPROACH_FEATURES, _approach,
                        "translation, rotation and mirroring of the scene", rigid_motion)
