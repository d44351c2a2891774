"""The arm's own feature space: its reach in joint space described by the ramps its controller plans.

"ramps": per joint the distance to go and the start and goal velocities signed toward the goal (as the generic
"joints" space), plus the longer of the two joints' time-optimal ramps under the arm's limits (the synchronized
ramps take at least that long). One ramp feature, not one per joint: an M5 leaf's linear model may only use the
features tested above it, and the larger ramp is the one the tree splits on. Invariant to shifting each joint's start and goal together
and to mirroring each joint, like "joints". Table 4.1's reach row (the generic "reach" space) describes a reach
by Euclidean joint-space distances and angles, which the synchronized ramps of independent joints do not follow.
"""

from __future__ import annotations

import numpy as np

from tailor.sims.arm import world as W
from tailor.sims.arm.profile import EPS
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


def _shift_mirror(params: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Each joint's start and goal shifted by one offset, and (half the time) each joint mirrored."""
    return shift_mirror_axes(params, rng, ((0, 1), (2, 3)), goal_offset=4)


RAMPS = FeatureSpace("ramps", PARAMETERS, NAMES, _ramps, "translation and mirroring of each joint", _shift_mirror)
