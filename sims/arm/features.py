"""The arm's own feature space: its reach in joint space described by the ramps its controller plans.

"ramps": per joint the distance to go and the start and goal velocities signed toward the goal (as the generic
"joints" space), plus the longer of the two joints' time-optimal ramps under the arm's limits (the synchronized
ramps take at least that long). One ramp feature, not one per joint: an M5 leaf's linear model may only use the
features tested above it, and the larger ramp is the one the tree splits on. Invariant to shifting each joint's start and goal together
and to mirroring each joint, like "joints". Table 4.1's reach row (the generic "reach" space) describes a reach
by Euclidean joint-space distances and angles, which the synchronized ramps of independent joints do not follow.

Its bounds (for the certified optimizer) are exact over boxes on one side of each joint's jumps: the distance
and signed speeds as the "line" space's, the ramp as the larger of the joints' transfer-time enclosures
(sims.intervals.transfer_time_bounds: the time is monotone in each argument on either side of the direct ramp).
"""

from __future__ import annotations

import numpy as np
from tailor.sims.arm import world as W
from tailor.sims.arm.profile import EPS
from tailor.sims.intervals import axis, transfer_time_bounds
from tailor.sims.invariances import shift_mirror_axes
from tailor.sims.kinematics import transfer_time
from tailor.sims.protocol import FeatureSpace

PARAMETERS = ("theta_a", "omega_a", "theta_b", "omega_b", "theta_ga", "omega_ga", "theta_gb", "omega_gb")
NAMES = ("dist_a", "v_a", "vg_a", "dist_b", "v_b", "vg_b", "ramp")


def ramp_durations(x0: np.ndarray, v0: np.ndarray, xg: np.ndarray, vg: np.ndarray,
                   v_max: float = W.OMEGA_MAX, a_max: float = W.ALPHA_MAX) -> np.ndarray:
    """The time-optimal ramp's duration per row: profile.optimal vectorized (its boundary profiles: every
    candidate cruise speed, the fastest one that needs no negative cruise time)."""
    return transfer_time(xg - x0, v0, vg, v_max, a_max, EPS)


def _ramps(params: np.ndarray) -> np.ndarray:
    ta, wa, tb, wb, tga, wga, tgb, wgb = params.T
    sa, sb = np.where(tga - ta < 0, -1.0, 1.0), np.where(tgb - tb < 0, -1.0, 1.0)
    ramp = np.maximum(ramp_durations(ta, wa, tga, wga), ramp_durations(tb, wb, tgb, wgb))
    return np.column_stack([np.abs(tga - ta), wa * sa, wga * sa, np.abs(tgb - tb), wb * sb, wgb * sb, ramp])


def _ramps_bounds(low: np.ndarray, high: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A guaranteed enclosure of `_ramps` over boxes of parameters (FeatureSpace.bounds): both joints' rows
    stacked through one call of each enclosure."""
    low, high = np.atleast_2d(low), np.atleast_2d(high)
    k = len(low)
    x, v, xg, vg = ((np.concatenate([low[:, a], low[:, b]]), np.concatenate([high[:, a], high[:, b]]))
                    for a, b in ((0, 2), (1, 3), (4, 6), (5, 7)))
    dist, speed, goal_speed = axis(x, v, xg, vg)
    ramp = transfer_time_bounds((xg[0] - x[1], xg[1] - x[0]), v, vg, W.OMEGA_MAX, W.ALPHA_MAX, EPS)
    bounds = []
    for side in (0, 1):
        a, b = (np.column_stack([q[side][rows] for q in (dist, speed, goal_speed)]) for rows in (slice(k), slice(k, None)))
        bounds.append(np.column_stack([a, b, np.maximum(ramp[side][:k], ramp[side][k:])]))
    return bounds[0], bounds[1]


def _shift_mirror(params: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Each joint's start and goal shifted by one offset, and (half the time) each joint mirrored."""
    return shift_mirror_axes(params, rng, ((0, 1), (2, 3)), goal_offset=4)


RAMPS = FeatureSpace("ramps", PARAMETERS, NAMES, _ramps, "translation and mirroring of each joint", _shift_mirror,
                     _ramps_bounds)
