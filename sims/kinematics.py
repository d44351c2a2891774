"""The least time of a one-dimensional move under speed and acceleration limits: a quantity many robots' actions
share (a joint's ramp, a base's run along a line), used by a robot's own feature space and by the automatic
features' `transfer` operator alike."""

from __future__ import annotations

import numpy as np


def transfer_time(d: np.ndarray, v0: np.ndarray, vg: np.ndarray, vmax: float, amax: float,
                  tol: float = 1e-12) -> np.ndarray:
    """Least duration of a move by displacement d from speed v0 to vg under |v| <= vmax, |a| <= amax: the fastest
    of the three-phase profiles (to a cruise speed vc, cruise, to vg) over every candidate vc (the limits, the
    boundary speeds, and the peaks of the profiles without cruise); `tol` admits a cruise phase of zero length."""
    d, v0, vg = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (d, v0, vg)))
    v0, vg = np.clip(v0, -vmax, vmax), np.clip(vg, -vmax, vmax)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        peaks = []
        for s1, s3 in ((1.0, -1.0), (-1.0, 1.0)):  # no cruise: d = s1 (vc^2 - v0^2)/2a + s3 (vg^2 - vc^2)/2a
            square = (2.0 * amax * d + s1 * v0 * v0 - s3 * vg * vg) / (s1 - s3)
            root = np.where(square >= -tol, np.sqrt(np.maximum(square, 0.0)), np.nan)
            peaks += [root, -root]
        # every candidate at once (one array operation each, not one per candidate); NaN stays NaN: no such one
        vc = np.clip(np.stack([np.full_like(d, vmax), np.full_like(d, -vmax), v0, vg, *peaks]), -vmax, vmax)
        t1, t3 = np.abs(vc - v0) / amax, np.abs(vg - vc) / amax
        rest = d - 0.5 * (v0 + vc) * t1 - 0.5 * (vc + vg) * t3
        tc = np.where(vc != 0.0, rest / np.where(vc != 0.0, vc, 1.0), np.where(np.abs(rest) <= tol, 0.0, -np.inf))
        total = np.where(tc >= -tol, t1 + np.maximum(tc, 0.0) + t3, np.inf)
        return np.where(np.isnan(total), np.inf, total).min(axis=0)
