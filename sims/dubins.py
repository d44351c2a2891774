"""Dubins paths over many rows at once: the shortest forward path of bounded curvature between two poses (Dubins
1957), the way a vehicle that cannot turn on the spot gets from one pose to another, and guaranteed enclosures of
its length over boxes of poses.

A path is one of six words of three segments, each a left arc (L), a right arc (R) or a straight (S): LSL, RSR,
LSR, RSL, RLR, LRL; arcs have the turning radius. The formulas are Shkel & Lumelsky's (2001) in the normalized
frame where the start lies at the origin heading alpha, the goal at (d, 0) heading beta, lengths in radii.
Numpy, row-wise: a robot's own feature space and the automatic features' `dubins` operator
(refinement.models.expression_maths) compute them for every example and every candidate of an optimizer.

The enclosures (WordBounds, shortest_bounds) are interval arithmetic through the same formulas in the same order
(sims.intervals, every step widened for its rounding). Where a box meets a jump (an arc's length wrapping at a
full turn, the shortest word changing, a word coming into existence) they are the hull of what the box may hold;
at a single point every test is decided and they shrink to the value.
"""

from __future__ import annotations

import numpy as np
from tailor.sims import intervals as I

TWO_PI, PI = 2.0 * np.pi, np.pi
WORDS = ("LSL", "RSR", "LSR", "RSL", "RLR", "LRL")
ARC = np.array([[kind != "S" for kind in word] for word in WORDS])  # (6, 3): which segments of each word are arcs
SIGN = np.array([[{"L": 1.0, "R": -1.0, "S": 0.0}[kind] for kind in word] for word in WORDS])  # (6, 3) turn sense
FULL = TWO_PI - 1e-9  # an arc of (almost) a full turn is numerically zero: it is zero
SLACK = 1e-12  # absolute widening of the normalized quantities (radius units, rad): rounding
LOOP = 2.0 + 2.0 * TWO_PI  # radii: LSL is never longer than the ends' distance plus this (two full turns, and
# its straight, the distance of the left circles' centres, at most the ends' distance plus two radii)


def _mod(a: np.ndarray) -> np.ndarray:
    return np.mod(a, TWO_PI)


def words(start: np.ndarray, goal: np.ndarray, radius: float, tangent_slack: float = 0.0
          ) -> tuple[np.ndarray, np.ndarray]:
    """(M, 6, 3) segment lengths (m) of each word of WORDS from the poses `start` (M, 3: x, y, heading) to `goal`,
    NaN where a word does not exist, and (M, 6) whether each is exact. A mixed word (LSR, RSL) whose circles
    overlap by up to `tangent_slack` (radius units squared) is taken as touching: it exists, not exact (a robot
    following a path drifts across that boundary; the true Dubins path has `tangent_slack` 0)."""
    dx, dy = goal[:, 0] - start[:, 0], goal[:, 1] - start[:, 1]
    d = np.hypot(dx, dy) / radius
    th0 = np.where(d > 1e-9, np.arctan2(dy, dx), 0.0)
    alpha, beta = _mod(start[:, 2] - th0), _mod(goal[:, 2] - th0)
    sa, ca, sb, cb = np.sin(alpha), np.cos(alpha), np.sin(beta), np.cos(beta)
    cab = np.cos(alpha - beta)
    out = np.empty((len(d), 6, 3))
    exact = np.ones((len(d), 6), dtype=bool)
    exists = np.empty((len(d), 6), dtype=bool)
    with np.errstate(invalid="ignore"):
        p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sa - sb)  # LSL
        th = np.arctan2(cb - ca, d + sa - sb)
        exists[:, 0] = p2 >= 0.0
        out[:, 0, 0], out[:, 0, 1], out[:, 0, 2] = _mod(th - alpha), np.sqrt(p2), _mod(beta - th)
        p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sb - sa)  # RSR
        th = np.arctan2(ca - cb, d - sa + sb)
        exists[:, 1] = p2 >= 0.0
        out[:, 1, 0], out[:, 1, 1], out[:, 1, 2] = _mod(alpha - th), np.sqrt(p2), _mod(th - beta)
        p2 = -2.0 + d * d + 2.0 * cab + 2.0 * d * (sa + sb)  # LSR
        p = np.sqrt(np.maximum(p2, 0.0))
        th = np.arctan2(-ca - cb, d + sa + sb) - np.arctan2(-2.0, p)
        exact[:, 2], exists[:, 2] = p2 >= 0.0, p2 >= -tangent_slack
        out[:, 2, 0], out[:, 2, 1], out[:, 2, 2] = _mod(th - alpha), p, _mod(th - beta)
        p2 = -2.0 + d * d + 2.0 * cab - 2.0 * d * (sa + sb)  # RSL
        p = np.sqrt(np.maximum(p2, 0.0))
        th = np.arctan2(ca + cb, d - sa - sb) - np.arctan2(2.0, p)
        exact[:, 3], exists[:, 3] = p2 >= 0.0, p2 >= -tangent_slack
        out[:, 3, 0], out[:, 3, 1], out[:, 3, 2] = _mod(alpha - th), p, _mod(beta - th)
        c = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sa - sb)) / 8.0  # RLR
        p = _mod(TWO_PI - np.arccos(np.clip(c, -1.0, 1.0)))
        t = _mod(alpha - np.arctan2(ca - cb, d - sa + sb) + p / 2.0)
        exists[:, 4] = np.abs(c) <= 1.0
        out[:, 4, 0], out[:, 4, 1], out[:, 4, 2] = t, p, _mod(alpha - beta - t + p)
        c = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sb - sa)) / 8.0  # LRL
        p = _mod(TWO_PI - np.arccos(np.clip(c, -1.0, 1.0)))
        t = _mod(-alpha + np.arctan2(-ca + cb, d + sa - sb) + p / 2.0)
        exists[:, 5] = np.abs(c) <= 1.0
        out[:, 5, 0], out[:, 5, 1], out[:, 5, 2] = t, p, _mod(beta - alpha - t + p)
    out[~exists] = np.nan
    out = np.where((out > FULL) & ARC[None], 0.0, out)
    return out * radius, exact


def totals(segments: np.ndarray) -> np.ndarray:
    """(M, 6) total length of each word of `segments` (M, 6, 3); inf where the word does not exist."""
    return np.where(np.isnan(segments).any(axis=2), np.inf, segments.sum(axis=2))


def shortest(start: np.ndarray, goal: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """The length (m) of the shortest Dubins path of turning radius `radius` from the poses `start` (M, 3) to
    `goal` (M, 3), and the length of its arcs (the rest is straight). Where rounding leaves no word (the poses
    coincide), the straight-line distance and no arc."""
    segments, _ = words(start, goal, radius)
    total = totals(segments)
    best = np.argmin(total, axis=1)
    rows = np.arange(len(start))
    length = total[rows, best]
    arcs = (np.nan_to_num(segments[rows, best]) * ARC[best]).sum(axis=1)
    none = ~np.isfinite(length)
    return (np.where(none, np.hypot(goal[:, 0] - start[:, 0], goal[:, 1] - start[:, 1]), length),
            np.where(none, 0.0, arcs))


# --- enclosures over boxes of poses -----------------------------------------------------------------------------
Pose = tuple[I.Pair, I.Pair, I.Pair]  # x, y, heading (unwrapped) intervals


def _add(a: I.Pair, b: I.Pair) -> I.Pair:
    return a[0] + b[0], a[1] + b[1]


def _sub(a: I.Pair, b: I.Pair) -> I.Pair:
    return a[0] - b[1], a[1] - b[0]


def _scale(a: I.Pair, c: float) -> I.Pair:
    return (a[0] * c, a[1] * c) if c >= 0 else (a[1] * c, a[0] * c)


def _slack(a: I.Pair, absolute: float = SLACK) -> I.Pair:
    return I.widen(a[0], a[1], absolute)


def modulo(lo: np.ndarray, hi: np.ndarray) -> I.Pair:
    """np.mod(x, 2 pi) over [lo, hi]: the shifted interval where it stays within one turn clear of the seam,
    else [0, 2 pi]."""
    with np.errstate(invalid="ignore"):
        k = np.floor(lo / TWO_PI)
        a, b = lo - TWO_PI * k, hi - TWO_PI * k
        slack = 1e3 * I.EPS * (np.abs(lo) + np.abs(hi) + 1.0)
        inside = (a - slack > 0.0) & (b + slack < TWO_PI)
    return np.where(inside, a, 0.0), np.where(inside, b, TWO_PI)


def _arc(lo: np.ndarray, hi: np.ndarray) -> I.Pair:
    """An arc's length (rad): x mod 2 pi over [lo, hi], an arc of more than FULL being 0 (words). Across a
    multiple of 2 pi whose values below lie within 2 pi - FULL of it (a numerically full turn), [0, the values
    above]."""
    a, b = modulo(lo, hi)
    a, b = np.where(a > FULL, 0.0, a), np.where(a > FULL, 0.0, np.minimum(b, FULL))
    a = np.where(b >= FULL, 0.0, a)
    seam = TWO_PI * np.ceil(lo / TWO_PI)  # the first multiple of 2 pi at or above lo
    slack = 1e3 * I.EPS * (np.abs(lo) + np.abs(hi) + 1.0)
    near = (lo - seam > FULL - TWO_PI + slack) & (hi - seam < FULL - slack)
    return np.where(near, 0.0, a), np.where(near, np.maximum(hi - seam, 0.0) + slack, b)


def _meet(a: I.Pair, b: I.Pair) -> I.Pair:
    """The intersection of two enclosures of one quantity (the hull where rounding leaves them disjoint)."""
    lo, hi = np.maximum(a[0], b[0]), np.minimum(a[1], b[1])
    apart = lo > hi
    return np.where(apart, np.minimum(a[0], b[0]), lo), np.where(apart, np.maximum(a[1], b[1]), hi)


class WordBounds:
    """Enclosures of `words` over k boxes of start and goal poses: per word (k, 6) the lower and upper total length
    (m; lower inf where it surely does not exist), its arcs' length, whether it surely / may exist, whether it is
    surely / may be exact, and (k, 6, 3) its segments' lengths; `d` the ends' distance in radii."""

    def __init__(self, start: Pose, goal: Pose, radius: float, tangent_slack: float = 0.0):
        dx, dy = _sub(goal[0], start[0]), _sub(goal[1], start[1])
        d = _slack(_scale(I.hypot(dx, dy), 1.0 / radius))
        th0 = I.direction(dx, dy)
        tiny = d[0] <= 1e-9  # th0 may be the 0 of a goal at the start
        th0 = (np.where(tiny, -PI - SLACK, th0[0]), np.where(tiny, PI + SLACK, th0[1]))
        alpha, beta = _sub(start[2], th0), _sub(goal[2], th0)
        (sa, ca), (sb, cb) = I.sin_cos(*alpha), I.sin_cos(*beta)
        sa, ca, sb, cb = (_slack(q) for q in (sa, ca, sb, cb))
        cab = _slack(I.sin_cos(*_sub(start[2], goal[2]))[1])  # cos(alpha - beta): th0 cancels
        dd = I.square(*d)
        k = len(d[0])
        self.d = d
        # the same squared distances in the plane: the turning circles' centres (left 0, right 1) at both ends, a
        # box each, their distances squared in radii (no dependency between the terms, and never below 0)
        ends = []
        for x, y, h in (start, goal):
            sh, ch = I.sin_cos(*h)
            ends.append([(_slack(_sub(x, _scale(sh, side * radius))), _slack(_add(y, _scale(ch, side * radius))))
                         for side in (1.0, -1.0)])
        centres = {(a, b): _slack(_scale(I.square(*I.hypot(_sub(ends[1][b][0], ends[0][a][0]),
                                                           _sub(ends[1][b][1], ends[0][a][1]))), radius ** -2))
                   for a in (0, 1) for b in (0, 1)}
        self.lo, self.hi = np.full((k, 6), np.inf), np.full((k, 6), np.inf)
        self.arcs_lo, self.arcs_hi = np.zeros((k, 6)), np.zeros((k, 6))
        self.surely, self.maybe = np.zeros((k, 6), bool), np.zeros((k, 6), bool)
        self.exact_surely, self.exact_maybe = np.ones((k, 6), bool), np.ones((k, 6), bool)
        self.seg_lo, self.seg_hi = np.zeros((k, 6, 3)), np.zeros((k, 6, 3))  # m
        p2s: dict[int, I.Pair] = {}
        two, six = np.full(k, 2.0), np.full(k, 6.0)

        def word(w: int, segments: list[I.Pair], arcs: tuple[bool, bool, bool], exists: tuple) -> None:
            """Record word w from its three normalized segment intervals and its existence (surely, maybe)."""
            lo, hi = _slack((sum(s[0] for s in segments) * radius, sum(s[1] for s in segments) * radius), 1e-9)
            self.lo[:, w], self.hi[:, w] = np.where(exists[1], lo, np.inf), hi
            self.arcs_lo[:, w] = sum(s[0] for s, a in zip(segments, arcs) if a) * radius
            self.arcs_hi[:, w] = sum(s[1] for s, a in zip(segments, arcs) if a) * radius
            self.surely[:, w], self.maybe[:, w] = exists
            for j, segment in enumerate(segments):
                self.seg_lo[:, w, j], self.seg_hi[:, w, j] = _slack(_scale(segment, radius), 1e-9)

        # LSL, RSR: p2 = 2 + d^2 - 2 cab +- 2 d (sa - sb), the squared distance of the circles' centres
        for w, sign in ((0, 1.0), (1, -1.0)):
            diff = _sub(sa, sb) if sign > 0 else _sub(sb, sa)
            p2 = _slack(_add(_sub(_add((two, two), dd), _scale(cab, 2.0)), _scale(I.product(d, diff), 2.0)))
            p2 = p2s[w] = _meet(p2, centres[(w, w)])
            p = (np.sqrt(np.maximum(p2[0], 0.0)), np.sqrt(np.maximum(p2[1], 0.0)))
            if sign > 0:  # th = atan2(cb - ca, d + sa - sb)
                th = I.direction(_slack(_add(d, _sub(sa, sb))), _slack(_sub(cb, ca)))
                t, q = _arc(*_sub(th, alpha)), _arc(*_sub(beta, th))
            else:  # th = atan2(ca - cb, d - sa + sb)
                th = I.direction(_slack(_add(d, _sub(sb, sa))), _slack(_sub(ca, cb)))
                t, q = _arc(*_sub(alpha, th)), _arc(*_sub(th, beta))
            word(w, [t, p, q], (True, False, True), (p2[0] >= 0.0, p2[1] >= 0.0))
        # LSR, RSL: p2 = -2 + d^2 + 2 cab +- 2 d (sa + sb); exact where p2 >= 0, exist within tangent_slack
        for w, sign in ((2, 1.0), (3, -1.0)):
            total = _add(sa, sb)
            p2 = _slack(_add(_sub(_add(dd, _scale(cab, 2.0)), (two, two)), _scale(I.product(d, total), 2.0 * sign)))
            between = centres[(0, 1) if sign > 0 else (1, 0)]  # less the circles' touching distance squared
            p2 = _meet(p2, (between[0] - 4.0, between[1] - 4.0))
            p = (np.sqrt(np.maximum(p2[0], 0.0)), np.sqrt(np.maximum(p2[1], 0.0)))
            if sign > 0:  # th = atan2(-ca - cb, d + sa + sb) - atan2(-2, p): atan2(-2, p) increasing in p >= 0
                corner = (np.arctan2(-2.0, p[0]), np.arctan2(-2.0, p[1]))
                th = _sub(I.direction(_slack(_add(d, total)), _slack(_scale(_add(ca, cb), -1.0))), _slack(corner))
                t, q = _arc(*_sub(th, alpha)), _arc(*_sub(th, beta))
            else:  # th = atan2(ca + cb, d - sa - sb) - atan2(2, p): atan2(2, p) decreasing in p >= 0
                corner = (np.arctan2(2.0, p[1]), np.arctan2(2.0, p[0]))
                th = _sub(I.direction(_slack(_sub(d, total)), _slack(_add(ca, cb))), _slack(corner))
                t, q = _arc(*_sub(alpha, th)), _arc(*_sub(beta, th))
            word(w, [t, p, q], (True, False, True), (p2[0] >= -tangent_slack, p2[1] >= -tangent_slack))
            self.exact_surely[:, w], self.exact_maybe[:, w] = p2[0] >= 0.0, p2[1] >= 0.0
        # RLR, LRL: c = (6 - d^2 + 2 cab +- 2 d (sa - sb)) / 8, p = mod(2 pi - arccos(c)), t and q through p / 2
        for w, sign in ((4, 1.0), (5, -1.0)):
            diff = _sub(sa, sb) if sign > 0 else _sub(sb, sa)
            c = _slack(_scale(_add(_add(_sub((six, six), dd), _scale(cab, 2.0)), _scale(I.product(d, diff), 2.0)),
                              0.125))
            outer = p2s[1 if sign > 0 else 0]  # c = 1 - (the outer circles' centres' distance)^2 / 8
            c = _meet(c, _slack((1.0 - outer[1] / 8.0, 1.0 - outer[0] / 8.0)))
            ac = (np.arccos(np.clip(c[1], -1.0, 1.0)), np.arccos(np.clip(c[0], -1.0, 1.0)))  # arccos decreasing
            raw = _slack((TWO_PI - ac[1], TWO_PI - ac[0]))
            if sign > 0:  # t = mod(alpha - atan2(ca - cb, d - sa + sb) + p/2), q = mod(th - beta + p/2)
                th = I.direction(_slack(_add(d, _sub(sb, sa))), _slack(_sub(ca, cb)))
            else:  # t = mod(-alpha + atan2(-ca + cb, d + sa - sb) + p/2), q = mod(beta - th + p/2)
                th = I.direction(_slack(_add(d, _sub(sa, sb))), _slack(_sub(cb, ca)))
            wraps = raw[1] >= TWO_PI  # p = mod(2 pi - arccos) may be 0: t and q through p = 0 as well
            segments = None
            for p_raw in (raw, (np.zeros(k), np.zeros(k))):
                p = _arc(*p_raw)
                half = _scale(p_raw, 0.5) if p_raw is raw else p_raw
                if sign > 0:
                    t, q = _arc(*_add(_sub(alpha, th), half)), _arc(*_add(_sub(th, beta), half))
                else:
                    t, q = _arc(*_add(_sub(th, alpha), half)), _arc(*_add(_sub(beta, th), half))
                if segments is None:
                    segments = [t, p, q]
                else:  # the hull with the p = 0 branch where p may wrap
                    segments = [(np.where(wraps, np.minimum(a[0], b[0]), a[0]),
                                 np.where(wraps, np.maximum(a[1], b[1]), a[1])) for a, b in zip(segments, [t, p, q])]
            word(w, segments, (True, True, True), ((c[0] >= -1.0) & (c[1] <= 1.0), (c[1] >= -1.0) & (c[0] <= 1.0)))


def shortest_bounds(start: Pose, goal: Pose, radius: float) -> tuple[I.Pair, I.Pair]:
    """`shortest`'s (length, arcs) enclosed over k boxes of poses. The length lies between the least lower length
    of the words that may exist and the least upper length of those that surely do; it is never below the ends'
    distance nor above it plus LOOP radii (LSL's bound). The arcs: the hull over the words that may be the
    shortest."""
    with np.errstate(invalid="ignore", over="ignore"):  # (unbounded boxes: NaN tests decide nothing, as wanted)
        bounds = WordBounds(start, goal, radius)
        straight = I.hypot(_sub(goal[0], start[0]), _sub(goal[1], start[1]))
    upper = np.where(bounds.surely, bounds.hi, np.inf).min(axis=1)  # no longer than a word surely there ...
    # ... or than the longer of LSL and RSR where the ends lie apart: the larger of their circles' centres'
    # distances is then at least half the ends' (normalized) distance, and one of them is there
    apart = bounds.d[0] ** 2 / 4.0 > 1e-6
    upper = np.where(apart, np.minimum(upper, bounds.hi[:, :2].max(axis=1)), upper)
    upper = np.minimum(upper, straight[1] + LOOP * radius * (1.0 + 1e-12))
    least = bounds.lo.min(axis=1)  # (the ends' distance widened for the rounding of a straight word's length)
    lower = np.maximum(np.where(np.isfinite(least), least, 0.0), straight[0] * (1.0 - 1e-12) - 1e-9)
    lower = np.maximum(lower, 0.0)
    may_be = bounds.maybe & (bounds.lo <= upper[:, None])
    arcs = (np.where(may_be, bounds.arcs_lo, np.inf).min(axis=1), np.where(may_be, bounds.arcs_hi, -np.inf).max(axis=1))
    # where no word may be the shortest (only rounding could say so), any arcs a path of that length may have
    none = ~may_be.any(axis=1)
    arcs = (np.where(none, 0.0, arcs[0]), np.minimum(np.where(none, upper, arcs[1]), upper))  # (part of it)
    # a box of positions not bounded in every direction: no test through its NaNs (inf - inf) is to be trusted;
    # the ends' distance, and three arcs of less than a turn each (an unbounded heading is any heading: sound)
    unbounded = ~np.all([np.isfinite(end) for pose in (start, goal) for pair in pose[:2] for end in pair], axis=0)
    lower = np.where(unbounded, np.maximum(straight[0] * (1.0 - 1e-12) - 1e-9, 0.0), lower)
    upper = np.where(unbounded, np.inf, upper)
    arcs = (np.where(unbounded, 0.0, arcs[0]), np.where(unbounded, 3.0 * FULL * radius, arcs[1]))
    return (lower, upper), _slack(arcs, 1e-9)
