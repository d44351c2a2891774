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
from tailor.sims.protocol import FeatureSpace

PARAMETERS = ("theta_a", "omega_a", "theta_b", "omega_b", "theta_ga", "omega_ga", "theta_gb", "omega_gb")
NAMES = ("dist_a", "v_a", "vg_a", "dist_b", "v_b", "vg_b", "ramp")


def ramp_durations(x0: np.ndarray, v0: np.ndarray, xg: np.ndarray, vg: np.ndarray,
                   v_max: float = W.OMEGA_MAX, a_max: float = W.ALPHA_MAX) -> np.ndarray:
    """The time-optimal ramp's duration per row: profile.optimal vectorized (its boundary profiles: every
    candidate cruise speed, the fastest one that needs no negative cruise time)."""
    v0, vg = np.clip(v0, -v_max, v_max), np.clip(vg, -v_max, v_max)
    d = xg - x0
    candidates = [np.full_like(d, v_max), np.full_like(d, -v_max), v0, vg]
    for s1, s3 in ((1.0, -1.0), (-1.0, 1.0)):  # no cruise: d = s1 (vc^2 - v0^2) / 2a + s3 (vg^2 - vc^2) / 2a
        sq = (2.0 * a_max * d + s1 * v0 * v0 - s3 * vg * vg) / (s1 - s3)
        root = np.where(sq >= -EPS, np.sqrt(np.maximum(sq, 0.0)), np.nan)
        candidates += [root, -root]
    best = np.full_like(d, np.inf)
    for vc in candidates:
        vc = np.clip(vc, -v_max, v_max)  # NaN stays NaN: no such candidate
        t1, t3 = np.abs(vc - v0) / a_max, np.abs(vg - vc) / a_max
        rest = d - 0.5 * (v0 + vc) * t1 - 0.5 * (vc + vg) * t3
        with np.errstate(divide="ignore", invalid="ignore"):
            tc = np.where(vc != 0.0, rest / vc, np.where(np.abs(rest) <= EPS, 0.0, -np.inf))  # vc = 0: wait
        total = np.where(tc >= -EPS, t1 + np.maximum(tc, 0.0) + t3, np.inf)
        best = np.fmin(best, np.where(np.isnan(total), np.inf, total))
    return best


def _ramps(params: np.ndarray) -> np.ndarray:
    ta, wa, tb, wb, tga, wga, tgb, wgb = params.T
    sa, sb = np.where(tga - ta < 0, -1.0, 1.0), np.where(tgb - tb < 0, -1.0, 1.0)
    ramp = np.maximum(ramp_durations(ta, wa, tga, wga), ramp_durations(tb, wb, tgb, wgb))
    return np.column_stack([np.abs(tga - ta), wa * sa, wga * sa, np.abs(tgb - tb), wb * sb, wgb * sb, ramp])


def _shift_mirror(params: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Each joint's start and goal shifted by one offset, and (half the time) each joint mirrored."""
    return shift_mirror_axes(params, rng, ((0, 1), (2, 3)), goal_offset=4)


RAMPS = FeatureSpace("ramps", PARAMETERS, NAMES, _ramps, "translation and mirroring of each joint", _shift_mirror)
