"""Guaranteed interval enclosures of the quantities robots' feature spaces are made of (FeatureSpace.bounds):
given boxes of action parameters, (low, high) arrays, each returns bounds that hold for every point of the
box, as numpy computes the quantity there (rounding included: every bound is widened by a few units in the
last place, or by the tolerance the computation itself admits).

The certified optimizer needs more than soundness: at a single point an enclosure must shrink to the value,
and over a small box it should be close. Where a quantity is monotone in each argument over a box, its
bounds are its values at two corners (exact); where a box meets a jump or a change of formula, the bounds are
the hull of the pieces it may meet (sound, looser: the optimizer cuts such a box along the jump).
"""

from __future__ import annotations

import numpy as np

PI, TWO_PI = np.pi, 2.0 * np.pi
EPS = np.finfo(float).eps
ULPS = 16.0  # outward widening of computed bounds, in units of eps times their magnitude (1 - ULPS eps is exact)
ANGLE_SLACK = 1e-12  # rad: rounding of atan2 and of differences of angles
Pair = tuple[np.ndarray, np.ndarray]


def widen(lo: np.ndarray, hi: np.ndarray, absolute: float = 1e-300) -> Pair:
    """Outward by ULPS units in the last place (and `absolute`): the rounding of numpy's own evaluation. An
    infinite end stays (scaled, never inf - inf)."""
    step = ULPS * EPS
    return lo * (1.0 - step * np.sign(lo)) - absolute, hi * (1.0 + step * np.sign(hi)) + absolute


def distinct_rows(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(index of one occurrence of each distinct row, inverse): np.unique(rows, axis=0)'s, through a 64-bit hash
    of each row's bits (sorting numbers, not rows), every row checked equal to its representative."""
    rows = np.ascontiguousarray(rows, dtype=float)
    multipliers = (np.arange(rows.shape[1], dtype=np.uint64) * np.uint64(0x9E3779B97F4A7C15)) | np.uint64(1)
    with np.errstate(over="ignore"):
        keys = (rows.view(np.uint64) * multipliers).sum(axis=1, dtype=np.uint64)
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    if not np.array_equal(rows[first][inverse].view(np.uint64), rows.view(np.uint64)):  # a collision
        _, first, inverse = np.unique(rows, axis=0, return_index=True, return_inverse=True)
        inverse = inverse.reshape(-1)
    return first, inverse


def absolute(lo: np.ndarray, hi: np.ndarray) -> Pair:
    """|x| over [lo, hi]."""
    return np.where(lo >= 0.0, lo, np.where(hi <= 0.0, -hi, 0.0)), np.maximum(np.abs(lo), np.abs(hi))


def square(lo: np.ndarray, hi: np.ndarray) -> Pair:
    """x^2 over [lo, hi]."""
    a, b = absolute(lo, hi)
    return a * a, b * b


def product(a: Pair, b: Pair) -> Pair:
    """x y over the box: the least and largest product of ends (0 * inf as 0: the box's values are finite)."""
    with np.errstate(invalid="ignore"):
        corners = np.stack([a[0] * b[0], a[0] * b[1], a[1] * b[0], a[1] * b[1]])
    corners = np.where(np.isnan(corners), 0.0, corners)
    return corners.min(axis=0), corners.max(axis=0)


def axis(x: Pair, v: Pair, xg: Pair, vg: Pair) -> tuple[Pair, Pair, Pair]:
    """A move along one axis: the distance to go |xg - x| and the start and goal speeds signed toward the goal
    (the sign of 0 is +1), as the "line" space and a manipulator's joints compute them. Each subtraction rounds
    monotonically, so xg_lo - x_hi <= xg - x <= xg_hi - x_lo hold as computed; a speed times the sign where the
    sign is one over the box, the hull of both signs where the goal may lie on either side."""
    d_lo, d_hi = xg[0] - x[1], xg[1] - x[0]
    ahead, behind = d_lo >= 0, d_hi < 0  # the sign is +1 (also at 0), or -1, over the whole box

    def signed(lo: np.ndarray, hi: np.ndarray) -> Pair:
        return (np.where(ahead, lo, np.where(behind, -hi, np.minimum(lo, -hi))),
                np.where(ahead, hi, np.where(behind, -lo, np.maximum(hi, -lo))))

    return absolute(d_lo, d_hi), signed(*v), signed(*vg)


def hypot(x: Pair, y: Pair) -> Pair:
    """sqrt(x^2 + y^2) over the box: increasing in |x| and |y|."""
    (ax_lo, ax_hi), (ay_lo, ay_hi) = absolute(*x), absolute(*y)
    return widen(np.hypot(ax_lo, ay_lo), np.hypot(ax_hi, ay_hi))


def _reaches(lo: np.ndarray, hi: np.ndarray, phase: float) -> np.ndarray:
    """Whether [lo, hi] holds phase + 2 pi k for some integer k (with slack for the rounding of the test)."""
    slack = 1e3 * EPS * (np.abs(lo) + np.abs(hi) + 1.0)
    return phase + TWO_PI * np.ceil((lo - slack - phase) / TWO_PI) <= hi + slack


def sin_cos(lo: np.ndarray, hi: np.ndarray) -> tuple[Pair, Pair]:
    """(sin, cos) over [lo, hi]: the values at the ends, and +-1 where the interval holds an extreme."""
    ends_sin, ends_cos = np.stack([np.sin(lo), np.sin(hi)]), np.stack([np.cos(lo), np.cos(hi)])
    wide = ~(hi - lo < TWO_PI)
    out = []
    for ends, top, bottom in ((ends_sin, 0.5 * PI, -0.5 * PI), (ends_cos, 0.0, PI)):
        low = np.where(wide | _reaches(lo, hi, bottom), -1.0, ends.min(axis=0))
        high = np.where(wide | _reaches(lo, hi, top), 1.0, ends.max(axis=0))
        low, high = widen(low, high, 1e-15 * (1.0 + np.maximum(np.abs(lo), np.abs(hi))))  # (and of a wrapped lo)
        out.append((np.maximum(low, -1.0), np.minimum(high, 1.0)))
    return out[0], out[1]


def direction(x: Pair, y: Pair) -> Pair:
    """An interval of reals holding, up to multiples of 2 pi, every atan2(y, x) over the box (an arc; the whole
    circle where the box holds the origin). A box clear of the origin lies in an open half-plane through it, so
    its directions form an arc shorter than pi whose ends are directions of corners: taken relative to the
    direction of the box's centre, where no difference wraps."""
    full = (x[0] <= 0.0) & (x[1] >= 0.0) & (y[0] <= 0.0) & (y[1] >= 0.0)
    with np.errstate(invalid="ignore"):
        reference = np.arctan2(0.5 * (y[0] + y[1]), 0.5 * (x[0] + x[1]))
        turns = np.stack([np.arctan2(cy, cx) for cy in y for cx in x]) - reference
        turns = (turns + PI) % TWO_PI - PI
    lo = reference + turns.min(axis=0) - ANGLE_SLACK
    hi = reference + turns.max(axis=0) + ANGLE_SLACK
    return np.where(full, -PI - ANGLE_SLACK, lo), np.where(full, PI + ANGLE_SLACK, hi)


def abs_wrapped(lo: np.ndarray, hi: np.ndarray) -> Pair:
    """|wrap(x)| (the angle x as the turn of least size, in [0, pi]) over [lo, hi]: 0 where the interval holds a
    multiple of 2 pi, pi where it holds an odd multiple of pi, else the values at its ends (|wrap| is monotone
    between consecutive multiples of pi)."""
    def size(a):
        return np.abs(a - TWO_PI * np.round(a / TWO_PI))

    slack = ANGLE_SLACK + 1e3 * EPS * (np.abs(lo) + np.abs(hi))
    wide = ~(hi - lo < TWO_PI)
    low = np.where(wide | _reaches(lo, hi, 0.0), 0.0, np.minimum(size(lo), size(hi)))
    high = np.where(wide | _reaches(lo, hi, PI), PI, np.maximum(size(lo), size(hi)))
    return np.maximum(low - slack, 0.0), np.minimum(high + slack, PI + slack)


# --- the time-optimal transfer (sims.kinematics.transfer_time) ----------------------------------------------
def _stretch(x: np.ndarray, vmax: float, amax: float) -> np.ndarray:
    """G(X): twice the time from speed 0 to sqrt(X) at amax, or, beyond vmax, to vmax plus the cruise that covers
    the rest of the distance (X - vmax^2) / amax; increasing in X."""
    x = np.maximum(x, 0.0)
    cruise = 2.0 * vmax / amax + (x - vmax * vmax) / (amax * vmax)
    return np.where(x <= vmax * vmax, 2.0 * np.sqrt(x) / amax, cruise)


def transfer_time_bounds(d: Pair, v0: Pair, vg: Pair, vmax: float, amax: float, tol: float = 1e-12) -> Pair:
    """An enclosure of transfer_time(d, v0, vg, vmax, amax, tol) over boxes of (d, v0, vg).

    With the speeds clipped to +-vmax, the time-optimal transfer is one of two profiles, split by the direct
    ramp's displacement D0 = |vg - v0| (v0 + vg) / 2 amax: beyond it (d > D0) speed up, cruise at most at vmax,
    slow down, taking U = G(amax d + (v0^2 + vg^2) / 2) - (v0 + vg) / amax (`_stretch` is G); short of it the
    mirror image, L(d, v0, vg) = U(-d, -v0, -vg); at d = D0 the direct ramp, |vg - v0| / amax. U is increasing
    in d and decreasing in v0 and vg wherever it applies (dU/dv0 = (v0 / sqrt(X) - 1) / amax and sqrt(X) >= v0
    there), L the reverse. The time jumps at D0 where both speeds have the same sign (a joint that must arrive
    moving cannot undershoot without reversing). A box wholly on one side of D0: the bounds are the piece's
    values at two corners (exact). A box across D0: below, the speed change at amax and the distance at vmax
    (no profile beats either); above, the larger of both pieces' formulas bounded term by term and the direct
    ramp. `tol` is transfer_time's: it admits a cruise of length down to -tol, a profile that covers d to within
    tol * max(vmax, 1), so the lower bounds are taken over d widened by that much."""
    v0_lo, v0_hi = np.clip(v0[0], -vmax, vmax), np.clip(v0[1], -vmax, vmax)
    vg_lo, vg_hi = np.clip(vg[0], -vmax, vmax), np.clip(vg[1], -vmax, vmax)
    d_lo, d_hi = d
    slack = 2.0 * tol * max(vmax, 1.0) + 1e-15 * (1.0 + np.maximum(np.abs(d_lo), np.abs(d_hi)))
    near_lo, near_hi = d_lo - slack, d_hi + slack  # d as the tolerance may take it
    change = absolute(vg_lo - v0_hi, vg_hi - v0_lo)  # |vg - v0|
    # D0 over the box: the product form, within the separable form where vg - v0 keeps its sign over the box
    d0_lo, d0_hi = product(change, (v0_lo + vg_lo, v0_hi + vg_hi))
    up, down = vg_lo >= v0_hi, vg_hi <= v0_lo  # vg >= v0 (D0 = (vg^2 - v0^2)/2a), or vg <= v0, over the box
    (s0_lo, s0_hi), (sg_lo, sg_hi) = square(v0_lo, v0_hi), square(vg_lo, vg_hi)
    d0_lo = np.where(up, np.maximum(d0_lo, sg_lo - s0_hi), np.where(down, np.maximum(d0_lo, s0_lo - sg_hi), d0_lo))
    d0_hi = np.where(up, np.minimum(d0_hi, sg_hi - s0_lo), np.where(down, np.minimum(d0_hi, s0_hi - sg_lo), d0_hi))
    d0_lo, d0_hi = widen(d0_lo / (2.0 * amax), d0_hi / (2.0 * amax), 1e-15)
    beyond, short = near_lo > d0_hi, near_hi < d0_lo  # the whole box (d widened) on one side of D0
    # U's and L's values at the corners that bound them, and (across D0) their formulas bounded term by term:
    # each G(amax * distance + squares / 2) - speeds / amax, evaluated at once
    low_sq, high_sq = v0_lo * v0_lo + vg_lo * vg_lo, v0_hi * v0_hi + vg_hi * vg_hi
    low_sum, high_sum = v0_lo + vg_lo, v0_hi + vg_hi
    most = s0_hi + sg_hi
    distance = np.concatenate([near_lo, d_hi, -near_hi, -d_lo, d_hi, -d_lo])
    squares = np.concatenate([high_sq, low_sq, low_sq, high_sq, most, most])
    speeds = np.concatenate([high_sum, low_sum, -low_sum, -high_sum, low_sum, -high_sum])
    with np.errstate(invalid="ignore"):
        u_low, u_high, l_low, l_high, u_most, l_most = (
            _stretch(amax * distance + 0.5 * squares, vmax, amax) - speeds / amax).reshape(6, -1)
    # across D0: no profile is faster than its speed change or than covering |d| at vmax, nor slower than the
    # slower piece at its worst or the direct ramp
    floor = np.maximum(change[0] / amax, absolute(near_lo, near_hi)[0] / vmax)
    low = np.where(beyond, u_low, np.where(short, l_low, floor))
    worst = np.maximum(np.maximum(u_most, l_most), change[1] / amax)
    high = np.where(beyond, u_high, np.where(short, l_high, worst))
    low, high = widen(np.maximum(low, floor), high, 1e-12)
    return np.maximum(low, 0.0), high
