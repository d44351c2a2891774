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


CHUNK = 2048  # rows: WordBounds encloses more boxes in chunks of this many (5% less CPU than 512 on the bundled
# evaluation windows)


def _add(a: I.Pair, b: I.Pair) -> I.Pair:
    return a[0] + b[0], a[1] + b[1]


def _sub(a: I.Pair, b: I.Pair) -> I.Pair:
    return a[0] - b[1], a[1] - b[0]


def _scale(a: I.Pair, c: float) -> I.Pair:
    return (a[0] * c, a[1] * c) if c >= 0 else (a[1] * c, a[0] * c)


def _const(c: float, like: np.ndarray) -> I.Pair:
    return np.full_like(like, c), np.full_like(like, c)


def _slack(a: I.Pair, absolute: float = SLACK) -> I.Pair:
    return I.widen(a[0], a[1], absolute)


def _stack(*pairs: I.Pair) -> I.Pair:
    """Intervals of one shape stacked along a new first axis: one interval operation for them all (every
    operation here is elementwise, so each row gets the bits it would get alone)."""
    return np.stack([p[0] for p in pairs]), np.stack([p[1] for p in pairs])


def _rows(a: I.Pair, rows) -> I.Pair:
    return a[0][rows], a[1][rows]


def _scale_by(a: I.Pair, c: np.ndarray) -> I.Pair:
    """_scale with a factor per element (broadcast): the same products."""
    return np.where(c >= 0, a[0] * c, a[1] * c), np.where(c >= 0, a[1] * c, a[0] * c)


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
    """An arc's length (rad): x mod 2 pi over [lo, hi], an arc of more than FULL being 0 (dubins_words). Across
    a multiple of 2 pi whose values below lie within 2 pi - FULL of it (a numerically full turn), [0, the
    values above]."""
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
    """Enclosures of `words` over k boxes of start and goal poses: per word (k, 6) lower and upper total
    length (m; inf where it surely does not exist), its arcs' length, whether it surely / may exist, and whether
    it is surely / may be exact, and (k, 6, 3) its segments' lengths (m). The words' formulas run stacked: a
    pair of mirror words (LSL and RSR, LSR and RSL, RLR and LRL) is one operation, and every sine, direction
    and arc of all six words one call (an enclosure call costs more in calls than in rows)."""

    def __init__(self, start: Pose, goal: Pose, radius: float, tangent_slack: float = 0.0):
        k = max(len(np.atleast_1d(end)) for pose in (start, goal) for pair in pose for end in pair)
        if k > CHUNK:  # in chunks: the stacked arrays of many rows outgrow the cache
            parts = []
            for at in range(0, k, CHUNK):
                rows = slice(at, at + CHUNK)
                parts.append(WordBounds(*(tuple(tuple(np.broadcast_to(end, (k,))[rows] for end in pair) for pair in pose)
                                       for pose in (start, goal)), radius, tangent_slack))
            for name in ("lo", "hi", "arcs_lo", "arcs_hi", "surely", "maybe", "exact_surely", "exact_maybe", "seg_lo",
                         "seg_hi"):
                setattr(self, name, np.concatenate([getattr(part, name) for part in parts]))
            self.d = tuple(np.concatenate([part.d[j] for part in parts]) for j in (0, 1))
            return
        dx, dy = _sub(goal[0], start[0]), _sub(goal[1], start[1])
        d = _slack(_scale(I.hypot(dx, dy), 1.0 / radius))
        th0 = I.direction(dx, dy)
        tiny = d[0] <= 1e-9  # th0 may be the 0 of a goal at the start
        th0 = (np.where(tiny, -PI - SLACK, th0[0]), np.where(tiny, PI + SLACK, th0[1]))
        alpha, beta = _sub(start[2], th0), _sub(goal[2], th0)
        headings = [(np.broadcast_to(h[0], d[0].shape), np.broadcast_to(h[1], d[0].shape)) for h in (start[2], goal[2])]
        # alpha, beta, alpha - beta (cos(alpha - beta): th0 cancels), and both headings
        s, c = I.sin_cos(*_stack(alpha, beta, _sub(start[2], goal[2]), *headings))
        sa, sb = _slack(_rows(s, 0)), _slack(_rows(s, 1))
        ca, cb, cab = _slack(_rows(c, 0)), _slack(_rows(c, 1)), _slack(_rows(c, 2))
        dd = I.square(*d)
        self.d = d
        # the same squared distances in the plane: the turning circles' centres (left, right) at both ends, a box
        # each (rows: start left, start right, goal left, goal right), their distances squared in radii (no
        # dependency between the terms, and never below 0)
        end = [0, 0, 1, 1]
        side = np.array([1.0, -1.0, 1.0, -1.0])[:, None] * radius
        x, y = _stack(start[0], start[0], goal[0], goal[0]), _stack(start[1], start[1], goal[1], goal[1])
        ex = _slack(_sub(x, _scale_by(_rows(s, [3 + e for e in end]), side)))
        ey = _slack(_add(y, _scale_by(_rows(c, [3 + e for e in end]), side)))
        at, to = [0, 0, 1, 1], [2, 3, 2, 3]  # centres (start side, goal side): LL, LR, RL, RR
        centres = _slack(_scale(I.square(*I.hypot(_sub(_rows(ex, to), _rows(ex, at)),
                                                   _sub(_rows(ey, to), _rows(ey, at)))), radius ** -2))
        two, six = _const(2.0, d[0]), _const(6.0, d[0])
        diff = _sub(_stack(sa, sb), _stack(sb, sa))  # sa - sb, sb - sa
        spread = I.product(d, diff)
        total = _add(sa, sb)
        # LSL, RSR: p2 = 2 + d^2 - 2 cab +- 2 d (sa - sb), the squared distance of the circles' centres
        p2 = _slack(_add(_sub(_add(two, dd), _scale(cab, 2.0)), _scale(spread, 2.0)))
        straight = _meet(p2, _rows(centres, [0, 3]))
        # LSR, RSL: p2 = -2 + d^2 + 2 cab +- 2 d (sa + sb) less the touching distance squared of their circles
        p2 = _slack(_add(_sub(_add(dd, _scale(cab, 2.0)), two),
                         _scale_by(I.product(d, total), np.array([2.0, -2.0])[:, None])))
        between = _rows(centres, [1, 2])
        mixed = _meet(p2, (between[0] - 4.0, between[1] - 4.0))
        root = (np.sqrt(np.maximum(np.concatenate([straight[0], mixed[0]]), 0.0)),
                np.sqrt(np.maximum(np.concatenate([straight[1], mixed[1]]), 0.0)))
        # the directions: LSL's atan2(cb - ca, d + sa - sb), RSR's atan2(ca - cb, d - sa + sb), and LSR's and RSL's
        # atan2(-ca - cb, d + sa + sb), atan2(ca + cb, d - sa - sb) (less atan2(-+2, p), increasing resp.
        # decreasing in p >= 0)
        both = _add(ca, cb)
        dx_th = _slack(_stack(_add(d, _rows(diff, 0)), _add(d, _rows(diff, 1)), _add(d, total), _sub(d, total)))
        dy_th = _slack(_stack(_sub(cb, ca), _sub(ca, cb), _scale(both, -1.0), both))
        th = I.direction(dx_th, dy_th)
        corner = (np.arctan2(np.array([[-2.0], [2.0]]), np.stack([root[0][2], root[1][3]])),
                  np.arctan2(np.array([[-2.0], [2.0]]), np.stack([root[1][2], root[0][3]])))
        th_mixed = _sub(_rows(th, [2, 3]), _slack(corner))
        # RLR, LRL: c = (6 - d^2 + 2 cab +- 2 d (sa - sb)) / 8 = 1 - (the outer circles' centres' distance)^2 / 8,
        # p = mod(2 pi - arccos(c)), t and q through p / 2, their directions RSR's and LSL's
        cc = _slack(_scale(_add(_add(_sub(six, dd), _scale(cab, 2.0)), _scale(spread, 2.0)), 0.125))
        outer = _rows(straight, [1, 0])
        cc = _meet(cc, _slack((1.0 - outer[1] / 8.0, 1.0 - outer[0] / 8.0)))
        ac = (np.arccos(np.clip(cc[1], -1.0, 1.0)), np.arccos(np.clip(cc[0], -1.0, 1.0)))  # arccos decreasing
        raw = _slack((TWO_PI - ac[1], TWO_PI - ac[0]))
        half, zero = _scale(raw, 0.5), (np.zeros((2, k)), np.zeros((2, k)))
        # t and q: LSL's th - alpha and beta - th, RSR's alpha - th and th - beta, LSR's th - alpha and th - beta,
        # RSL's alpha - th and beta - th; RLR's alpha - th + p/2 and th - beta + p/2 (th RSR's), LRL's th - alpha +
        # p/2 and beta - th + p/2 (th LSL's), through the raw p and through p = 0; and p itself: one call
        th_lsl, th_rsr = _rows(th, 0), _rows(th, 1)
        t_straight = _sub(_stack(th_lsl, alpha), _stack(alpha, th_rsr))
        q_straight = _sub(_stack(beta, th_rsr), _stack(th_lsl, beta))
        t_mixed = _sub(_stack(_rows(th_mixed, 0), alpha), _stack(alpha, _rows(th_mixed, 1)))
        q_mixed = _sub(_stack(_rows(th_mixed, 0), beta), _stack(beta, _rows(th_mixed, 1)))
        t_curl = _sub(_stack(alpha, th_lsl), _stack(th_rsr, alpha))
        q_curl = _sub(_stack(th_rsr, beta), _stack(beta, th_lsl))
        angles = [t_straight, t_mixed, q_straight, q_mixed, raw, zero, _add(t_curl, half), _add(q_curl, half),
                  _add(t_curl, zero), _add(q_curl, zero)]
        arcs = _arc(np.concatenate([a[0] for a in angles]), np.concatenate([a[1] for a in angles]))
        t, q = _rows(arcs, slice(0, 4)), _rows(arcs, slice(4, 8))  # LSL, RSR, LSR, RSL
        p_raw, p_zero, t_raw, q_raw, t_zero, q_zero = (_rows(arcs, slice(8 + 2 * i, 10 + 2 * i)) for i in range(6))
        wraps = raw[1] >= TWO_PI  # p = mod(2 pi - arccos) may be 0: t and q through p = 0 as well, the hull

        def hull(a: I.Pair, b: I.Pair) -> I.Pair:
            return (np.where(wraps, np.minimum(a[0], b[0]), a[0]), np.where(wraps, np.maximum(a[1], b[1]), a[1]))

        curl = [hull(t_raw, t_zero), hull(p_raw, p_zero), hull(q_raw, q_zero)]
        seg = [(np.concatenate([a[0], b[0]]), np.concatenate([a[1], b[1]])) for a, b in zip((t, root, q), curl)]
        # per word (6, k): the sums of its segments (as sum() adds them, from 0), existence and exactness
        length = _slack(((0 + seg[0][0] + seg[1][0] + seg[2][0]) * radius,
                         (0 + seg[0][1] + seg[1][1] + seg[2][1]) * radius), 1e-9)
        arc_lo = np.concatenate([0 + t[0] + q[0], 0 + curl[0][0] + curl[1][0] + curl[2][0]])
        arc_hi = np.concatenate([0 + t[1] + q[1], 0 + curl[0][1] + curl[1][1] + curl[2][1]])
        surely = np.concatenate([straight[0] >= 0.0, mixed[0] >= -tangent_slack, (cc[0] >= -1.0) & (cc[1] <= 1.0)])
        maybe = np.concatenate([straight[1] >= 0.0, mixed[1] >= -tangent_slack, (cc[1] >= -1.0) & (cc[0] <= 1.0)])
        self.lo, self.hi = np.where(maybe, length[0], np.inf).T, length[1].T
        self.arcs_lo, self.arcs_hi = (arc_lo * radius).T, (arc_hi * radius).T
        self.surely, self.maybe = surely.T, maybe.T
        self.exact_surely, self.exact_maybe = np.ones((k, 6), bool), np.ones((k, 6), bool)
        self.exact_surely[:, 2:4], self.exact_maybe[:, 2:4] = (mixed[0] >= 0.0).T, (mixed[1] >= 0.0).T
        scaled = [_slack(_scale(x, radius), 1e-9) for x in seg]
        self.seg_lo = np.stack([x[0] for x in scaled], axis=2).transpose(1, 0, 2)  # (6, k, 3) -> (k, 6, 3)
        self.seg_hi = np.stack([x[1] for x in scaled], axis=2).transpose(1, 0, 2)


def shortest_bounds(start: Pose, goal: Pose, radius: float) -> tuple[I.Pair, I.Pair]:
    """`shortest`'s (length, arcs) enclosed over k boxes of poses. The length lies between the least lower length
    of the words that may exist and the least upper length of those that surely do; it is never below the ends'
    distance nor above it plus LOOP radii (LSL's bound). The arcs: the hull over the words that may be the
    shortest."""
    with np.errstate(invalid="ignore", over="ignore"):
        bounds = WordBounds(start, goal, radius)
    return shortest_of(bounds, start, goal, radius)


def shortest_of(bounds: WordBounds, start: Pose, goal: Pose, radius: float) -> tuple[I.Pair, I.Pair]:
    """shortest_bounds from the words' enclosures `bounds` of these boxes (computed once by a caller that needs
    them for more)."""
    with np.errstate(invalid="ignore", over="ignore"):  # (unbounded boxes: NaN tests decide nothing, as wanted)
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
        arcs = (np.where(may_be, bounds.arcs_lo, np.inf).min(axis=1),
                np.where(may_be, bounds.arcs_hi, -np.inf).max(axis=1))
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


