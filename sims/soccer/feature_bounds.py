"""Guaranteed enclosures of the soccer robot's feature spaces (FeatureSpace.bounds) for the certified optimizer:
the pose row, the Dubins words its controllers plan, and goToPose's lure, over boxes of parameters.

Interval arithmetic through the same formulas the features evaluate (sims.soccer.pose, sims.soccer.features:
Shkel & Lumelsky's normalized frame), in the same order, every operation bounded by sims.intervals and widened
for its rounding. Where a box meets a jump (an arc's length wrapping at a full turn, the shortest word
changing, a word coming into existence), the bound is the hull of what the box may hold: the shortest word's
length lies between the least lower length of the words that may exist and the least upper length of those that
surely do; its arcs and the shortest exact word's length are the hull over every word that may be the shortest.
At a single point every test is decided and the bounds are the features, but for one case: where the planned
word must be chosen among words leaving the walls' box (shortest_word_inside's "hard" case, a path near a wall),
the bounds are the hull over every word that may exist, sound but not tight (their path bounds are not enclosed).
"""

from __future__ import annotations

import numpy as np
from tailor.sims import intervals as I
from tailor.sims.soccer.dubins import TANGENT_SLACK
from tailor.sims.soccer.pose import pose_parts
from tailor.sims.soccer.world import BALL_POINT_OFFSET

TWO_PI, PI = 2.0 * np.pi, np.pi
FULL = TWO_PI - 1e-9  # an arc of (almost) a full turn is numerically zero (sims.soccer.features.dubins_words)
SLACK = 1e-12  # absolute widening of the normalized quantities (radius units, rad): rounding


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


def modulo(lo: np.ndarray, hi: np.ndarray) -> I.Pair:
    """np.mod(x, 2 pi) over [lo, hi]: the shifted interval where it stays within one turn clear of the seam,
    else [0, 2 pi]."""
    with np.errstate(invalid="ignore"):
        k = np.floor(lo / TWO_PI)
        a, b = lo - TWO_PI * k, hi - TWO_PI * k
        slack = 1e3 * I.EPS * (np.abs(lo) + np.abs(hi) + 1.0)
        inside = (a - slack > 0.0) & (b + slack < TWO_PI)
    return np.where(inside, a, 0.0), np.where(inside, b, TWO_PI)


def norm_bounds(lo: np.ndarray, hi: np.ndarray) -> I.Pair:
    """pose.norm (wrap to [-pi, pi)) over [lo, hi]: shifted where clear of the seam, else [-pi, pi]."""
    a, b = modulo(lo + PI, hi + PI)
    return a - PI, b - PI


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


# --- the pose row -----------------------------------------------------------------------------------------------
def pose_bounds(columns: list[I.Pair]) -> dict[str, I.Pair]:
    """pose.pose_parts over boxes of (x, y, phi, v, xg, yg, phig, vg)."""
    x, y, phi, v, xg, yg, phig, vg = columns
    dx, dy = _sub(xg, x), _sub(yg, y)
    bearing = I.direction(dx, dy)
    signed = norm_bounds(*_slack(_sub(bearing, phi)))
    # where the start pose and the goal position are points, the side the goal lies on is the features' own
    # (a goal dead ahead is on the +1 side, which no enclosure of the angle could tell)
    point = np.all([a[0] == a[1] for a in (x, y, phi, xg, yg)], axis=0)
    if point.any():
        with np.errstate(invalid="ignore"):
            exact = np.mod(np.arctan2(yg[0] - y[0], xg[0] - x[0]) - phi[0] + PI, TWO_PI) - PI
        signed = (np.where(point, exact, signed[0]), np.where(point, exact, signed[1]))
    at = norm_bounds(*_slack(_sub(phig, bearing)))
    ahead, behind = signed[0] >= 0.0, signed[1] < 0.0  # sgn(angle_to_signed) is +1, or -1, over the whole box
    angle_at = (np.where(ahead, at[0], np.where(behind, -at[1], np.minimum(at[0], -at[1]))),
                np.where(ahead, at[1], np.where(behind, -at[0], np.maximum(at[1], -at[0]))))
    out = {"v": v, "vg": vg, "dist": I.hypot(dx, dy), "angle_to": I.abs_wrapped(*_sub(bearing, phi)),
           "angle_at": angle_at, "delta_angle": I.abs_wrapped(*_sub(phig, phi))}
    # a box that is a point: the features themselves (a wrapped angle at its seam is -pi, which no interval
    # around it could tell from pi)
    point = np.all([a[0] == a[1] for a in columns], axis=0)
    if point.any():
        parts = pose_parts(np.column_stack([a[0][point] for a in columns]))
        for name, (lo, hi) in out.items():
            lo, hi = np.array(lo, dtype=float), np.array(hi, dtype=float)
            lo[point], hi[point] = parts[name], parts[name]
            out[name] = (lo, hi)
    return out


def pose_row_bounds(columns: list[I.Pair], names: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    parts = pose_bounds(columns)
    return np.column_stack([parts[n][0] for n in names]), np.column_stack([parts[n][1] for n in names])


def _wall_bounds(x: I.Pair, y: I.Pair, phi: I.Pair, wall_x: float, wall_y: float) -> list[I.Pair]:
    """walls.wall_features over boxes: the clearances, and the heading's turn from each nearer wall's direction
    (the hull of both walls' where the box holds points on either side)."""
    ax, ay = I.absolute(*x), I.absolute(*y)

    def turn(side_lo: np.ndarray, side_hi: np.ndarray, positive: float, negative: float) -> I.Pair:
        ahead = I.abs_wrapped(phi[0] - positive, phi[1] - positive)  # the wall of coordinates >= 0
        behind = I.abs_wrapped(phi[0] - negative, phi[1] - negative)
        upper, lower = side_lo >= 0.0, side_hi < 0.0
        return (np.where(upper, ahead[0], np.where(lower, behind[0], np.minimum(ahead[0], behind[0]))),
                np.where(upper, ahead[1], np.where(lower, behind[1], np.maximum(ahead[1], behind[1]))))

    return [I.widen(wall_x - ax[1], wall_x - ax[0]), I.widen(wall_y - ay[1], wall_y - ay[0]),
            turn(*x, 0.0, PI), turn(*y, 0.5 * PI, -0.5 * PI)]


def pose_walls_bounds(low: np.ndarray, high: np.ndarray, wall_x: float, wall_y: float
                      ) -> tuple[np.ndarray, np.ndarray]:
    """A guaranteed enclosure of the "pose_walls" space (sims.soccer.walls) over boxes of parameters: the pose
    row, and the walls' clearances and turns at the start and at the goal."""
    low, high = np.atleast_2d(np.asarray(low, dtype=float)), np.atleast_2d(np.asarray(high, dtype=float))
    columns = [(low[:, k], high[:, k]) for k in range(low.shape[1])]
    pose = pose_bounds(columns)
    x, y, phi, _, xg, yg, phig, _ = columns
    pairs = ([pose[n] for n in ("v", "vg", "dist", "angle_to", "angle_at")]
             + _wall_bounds(x, y, phi, wall_x, wall_y) + _wall_bounds(xg, yg, phig, wall_x, wall_y))
    return np.column_stack([p[0] for p in pairs]), np.column_stack([p[1] for p in pairs])


# --- Dubins words ---------------------------------------------------------------------------------------------
Pose = tuple[I.Pair, I.Pair, I.Pair]  # x, y, heading (unwrapped) intervals


def axle_pose_bounds(columns: list[I.Pair], final: float) -> tuple[Pose, Pose]:
    """features.axle_poses over boxes: the axle at the start, its pre-pose `final` behind the axle at the goal."""
    x, y, phi, _, xg, yg, phig, _ = columns
    s, c = I.sin_cos(*phi)
    start = (_slack(_sub(x, _scale(c, BALL_POINT_OFFSET))), _slack(_sub(y, _scale(s, BALL_POINT_OFFSET))), phi)
    back = BALL_POINT_OFFSET + final
    s, c = I.sin_cos(*phig)
    return start, (_slack(_sub(xg, _scale(c, back))), _slack(_sub(yg, _scale(s, back))), phig)


def _meet(a: I.Pair, b: I.Pair) -> I.Pair:
    """The intersection of two enclosures of one quantity (the hull where rounding leaves them disjoint)."""
    lo, hi = np.maximum(a[0], b[0]), np.minimum(a[1], b[1])
    apart = lo > hi
    return np.where(apart, np.minimum(a[0], b[0]), lo), np.where(apart, np.maximum(a[1], b[1]), hi)


class Words:
    """Enclosures of dubins_words over k boxes of start and goal poses: per word (k, 6) lower and upper total
    length (m; inf where it surely does not exist), its arcs' length, whether it surely / may exist, and whether
    it is surely / may be exact."""

    def __init__(self, start: Pose, goal: Pose, radius: float):
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
        self.p2: dict[int, I.Pair] = {}
        # the same squared distances in the plane: the turning circles' centres (left 0, right 1) at both ends,
        # a box each, their distances squared in radii (no dependency between the terms, and never below 0)
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
        two, six = _const(2.0, d[0]), _const(6.0, d[0])

        def word(w: int, segments: list[I.Pair], arcs: tuple[bool, bool, bool], exists: tuple) -> None:
            """Record word w from its three normalized segment intervals and its existence (surely, maybe)."""
            lo = sum(s[0] for s in segments) * radius
            hi = sum(s[1] for s in segments) * radius
            lo, hi = _slack((lo, hi), 1e-9)
            self.lo[:, w], self.hi[:, w] = np.where(exists[1], lo, np.inf), hi
            self.arcs_lo[:, w] = sum(s[0] for s, a in zip(segments, arcs) if a) * radius
            self.arcs_hi[:, w] = sum(s[1] for s, a in zip(segments, arcs) if a) * radius
            self.surely[:, w], self.maybe[:, w] = exists
            for j, segment in enumerate(segments):
                self.seg_lo[:, w, j], self.seg_hi[:, w, j] = _slack(_scale(segment, radius), 1e-9)

        # LSL, RSR: p2 = 2 + d^2 - 2 cab +- 2 d (sa - sb)
        for w, sign in ((0, 1.0), (1, -1.0)):
            diff = _sub(sa, sb) if sign > 0 else _sub(sb, sa)
            p2 = _slack(_add(_sub(_add(two, dd), _scale(cab, 2.0)), _scale(I.product(d, diff), 2.0)))
            p2 = _meet(p2, centres[(w, w)])  # the squared distance of the circles' centres
            self.p2[w] = p2
            p = (np.sqrt(np.maximum(p2[0], 0.0)), np.sqrt(np.maximum(p2[1], 0.0)))
            if sign > 0:  # th = atan2(cb - ca, d + sa - sb)
                th = I.direction(_slack(_add(d, _sub(sa, sb))), _slack(_sub(cb, ca)))
                t, q = _arc(*_sub(th, alpha)), _arc(*_sub(beta, th))
            else:  # th = atan2(ca - cb, d - sa + sb)
                th = I.direction(_slack(_add(d, _sub(sb, sa))), _slack(_sub(ca, cb)))
                t, q = _arc(*_sub(alpha, th)), _arc(*_sub(th, beta))
            word(w, [t, p, q], (True, False, True), (p2[0] >= 0.0, p2[1] >= 0.0))
        # LSR, RSL: p2 = -2 + d^2 + 2 cab +- 2 d (sa + sb); exact where p2 >= 0, exist within TANGENT_SLACK
        for w, sign in ((2, 1.0), (3, -1.0)):
            total = _add(sa, sb)
            p2 = _slack(_add(_sub(_add(dd, _scale(cab, 2.0)), two), _scale(I.product(d, total), 2.0 * sign)))
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
            word(w, [t, p, q], (True, False, True), (p2[0] >= -TANGENT_SLACK, p2[1] >= -TANGENT_SLACK))
            self.exact_surely[:, w], self.exact_maybe[:, w] = p2[0] >= 0.0, p2[1] >= 0.0
        # RLR, LRL: c = (6 - d^2 + 2 cab +- 2 d (sa - sb)) / 8, p = mod(2 pi - arccos(c)), t and q through p / 2
        for w, sign in ((4, 1.0), (5, -1.0)):
            diff = _sub(sa, sb) if sign > 0 else _sub(sb, sa)
            c = _slack(_scale(_add(_add(_sub(six, dd), _scale(cab, 2.0)), _scale(I.product(d, diff), 2.0)), 0.125))
            outer = self.p2[1 if sign > 0 else 0]  # c = 1 - (the outer circles' centres' distance)^2 / 8
            c = _meet(c, _slack((1.0 - outer[1] / 8.0, 1.0 - outer[0] / 8.0)))
            ac = (np.arccos(np.clip(c[1], -1.0, 1.0)), np.arccos(np.clip(c[0], -1.0, 1.0)))  # arccos decreasing
            raw = _slack((TWO_PI - ac[1], TWO_PI - ac[0]))
            if sign > 0:  # t = mod(alpha - atan2(ca - cb, d - sa + sb) + p/2), q = mod(th - beta + p/2)
                th = I.direction(_slack(_add(d, _sub(sb, sa))), _slack(_sub(ca, cb)))
            else:  # t = mod(-alpha + atan2(-ca + cb, d + sa - sb) + p/2), q = mod(beta - th + p/2)
                th = I.direction(_slack(_add(d, _sub(sa, sb))), _slack(_sub(cb, ca)))
            branches = [raw]
            wraps = raw[1] >= TWO_PI  # p = mod(2 pi - arccos) may be 0: t and q through p = 0 as well
            segments = None
            for p_raw in branches + [(np.zeros_like(raw[0]), np.zeros_like(raw[0]))]:
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


def shortest_bounds(words: Words, final: float, choices: np.ndarray | None = None
                    ) -> tuple[I.Pair, I.Pair, I.Pair]:
    """shortest_word's (path, arcs, exact_path) over the boxes: the shortest word among those that may exist, its
    arcs the hull over the words that may be the shortest, the shortest exact word's length likewise. With
    `choices` (k, 6) the words the planner may choose instead (the hard case of shortest_word_inside): the hull
    over them."""
    lo = words.lo
    upper = np.where(words.surely, words.hi, np.inf).min(axis=1)  # no longer than a word surely there ...
    # ... or than the longer of LSL and RSR where the ends lie apart: the larger of their circles' centres'
    # distances is then at least half the ends' (normalized) distance, and one of them is there
    apart = words.d[0] ** 2 / 4.0 > 1e-6
    upper = np.where(apart, np.minimum(upper, words.hi[:, :2].max(axis=1)), upper)
    may_be = words.maybe & (lo <= upper[:, None])
    path = (lo.min(axis=1), upper)
    arcs = (np.where(may_be, words.arcs_lo, np.inf).min(axis=1),
            np.where(may_be, words.arcs_hi, -np.inf).max(axis=1))
    exact_lo = np.where(words.exact_maybe & words.maybe, words.lo, np.inf).min(axis=1)
    exact_hi = np.where(words.exact_surely & words.surely, words.hi, np.inf).min(axis=1)
    if choices is not None:  # (rows without choices keep the shortest word's bounds)
        some = choices.any(axis=1)
        path = (np.minimum(path[0], np.where(choices, words.lo, np.inf).min(axis=1)),
                np.maximum(path[1], np.where(choices, words.hi, -np.inf).max(axis=1)))
        arcs = (np.minimum(arcs[0], np.where(choices, words.arcs_lo, np.inf).min(axis=1)),
                np.maximum(arcs[1], np.where(choices, words.arcs_hi, -np.inf).max(axis=1)))
        exact_lo = np.where(some, np.minimum(exact_lo, path[0]), exact_lo)
        exact_hi = np.where(some, np.maximum(exact_hi, path[1]), exact_hi)
    return (path[0] + final, path[1] + final), arcs, (exact_lo + final, exact_hi + final)


def _within(pose: Pose, box: tuple[float, float, float, float], margin: float) -> np.ndarray:
    """Whether the position surely lies within the box less `margin` on every side."""
    (x_lo, x_hi), (y_lo, y_hi) = pose[0], pose[1]
    return ((box[0] + margin <= x_lo) & (x_hi <= box[1] - margin)
            & (box[2] + margin <= y_lo) & (y_hi <= box[3] - margin))


SIGNS = ((1, 0, 1), (-1, 0, -1), (1, 0, -1), (-1, 0, 1), (-1, 1, -1), (1, -1, 1))  # WORDS' turn senses


def word_extent(start: Pose, words: Words, w: int, radius: float) -> tuple[I.Pair, I.Pair]:
    """An outer box (x, y intervals) holding every point of word w's path from every start pose of the box, for
    every segment length its enclosure allows: per arc, its circle's centre box grown by the radius times the
    range of cos and sin over the angles it may sweep; per straight, its ends."""
    x, y, h = start
    x_ext, y_ext = x, y
    for j, sign in enumerate(SIGNS[w]):
        length = (words.seg_lo[:, w, j], words.seg_hi[:, w, j])
        if sign == 0:  # a straight: its points lie between its ends
            s, c = I.sin_cos(*h)
            x, y = _slack(_add(x, I.product(length, c))), _slack(_add(y, I.product(length, s)))
            x_ext = (np.minimum(x_ext[0], x[0]), np.maximum(x_ext[1], x[1]))
            y_ext = (np.minimum(y_ext[0], y[0]), np.maximum(y_ext[1], y[1]))
            continue
        s, c = I.sin_cos(*h)  # the centre: to the left (sign 1) or right of the heading, a radius away
        cx, cy = _slack(_sub(x, _scale(s, sign * radius))), _slack(_add(y, _scale(c, sign * radius)))
        first = (h[0] - sign * 0.5 * PI, h[1] - sign * 0.5 * PI)  # the angle of the start seen from the centre
        turn = _scale(length, sign / radius)
        end = _add(first, turn)
        swept = (np.minimum(first[0], end[0]), np.maximum(first[1], end[1]))
        sweep_s, sweep_c = I.sin_cos(*swept)
        x_ext = (np.minimum(x_ext[0], cx[0] + radius * sweep_c[0]),
                 np.maximum(x_ext[1], cx[1] + radius * sweep_c[1]))
        y_ext = (np.minimum(y_ext[0], cy[0] + radius * sweep_s[0]),
                 np.maximum(y_ext[1], cy[1] + radius * sweep_s[1]))
        end_s, end_c = I.sin_cos(*end)
        x, y = _slack(_add(cx, _scale(end_c, radius))), _slack(_add(cy, _scale(end_s, radius)))
        h = _add(h, turn)
    return _slack(x_ext, 1e-9), _slack(y_ext, 1e-9)


def shortest_inside_bounds(start: Pose, goal: Pose, radius: float, final: float,
                           box: tuple[float, float, float, float]) -> tuple[I.Pair, I.Pair, I.Pair]:
    """shortest_word_inside over the boxes: as shortest_word where both ends surely lie 4 radii inside the box (2
    where no CCC word may exist), where every word stays inside; elsewhere the hull over every word that may
    exist (the planner may choose any by the words' bounds, which are not enclosed here)."""
    words = Words(start, goal, radius)
    far = _within(start, box, 4.0 * radius) & _within(goal, box, 4.0 * radius)
    near = _within(start, box, 2.0 * radius) & _within(goal, box, 2.0 * radius) & ~words.maybe[:, 4:].any(axis=1)
    simple = far | near
    # elsewhere, as the planner: where every word that may be the shortest, or the shortest exact one, surely
    # stays inside the box, they are the choice
    upper = np.where(words.surely, words.hi, np.inf).min(axis=1)
    exact_upper = np.where(words.surely & words.exact_surely, words.hi, np.inf).min(axis=1)
    candidate = words.maybe & ((words.lo <= upper[:, None])
                               | (words.exact_maybe & (words.lo <= exact_upper[:, None])))
    inside = np.ones(candidate.shape, dtype=bool)
    for w in range(6):
        rows = np.flatnonzero(~simple & candidate[:, w])
        if len(rows):
            sub = tuple((a[rows], b[rows]) for a, b in start)
            part = Words.__new__(Words)
            part.seg_lo, part.seg_hi = words.seg_lo[rows], words.seg_hi[rows]
            (x_lo, x_hi), (y_lo, y_hi) = word_extent(sub, part, w, radius)
            inside[rows, w] = (box[0] <= x_lo) & (x_hi <= box[1]) & (box[2] <= y_lo) & (y_hi <= box[3])
    simple |= (inside | ~candidate).all(axis=1)
    return shortest_bounds(words, final, np.where(simple[:, None], False, words.maybe))


def detour_bounds(path: I.Pair, start: Pose, pre: Pose, final: float) -> I.Pair:
    """goto_path_features' detour: the word's length (its `final` straight left out) over the straight line."""
    straight = I.hypot(_sub(pre[0], start[0]), _sub(pre[1], start[1]))
    return _slack((path[0] - final - straight[1], path[1] - final - straight[0]), 1e-9)


# --- goToPose's lure ------------------------------------------------------------------------------------------
def lure_bounds(columns: list[I.Pair], box: tuple[float, float, float, float], lure_min: float, lure_gain: float,
                lure_max: float) -> tuple[I.Pair, I.Pair, I.Pair]:
    """features.lure_features over boxes: (length through the IP, turn toward it, turn at it)."""
    start, goal = axle_pose_bounds(columns, 0.0)
    s, c = (_slack(q) for q in I.sin_cos(*goal[2]))
    along = _slack(_add(I.product(_sub(start[0], goal[0]), c), I.product(_sub(start[1], goal[1]), s)))
    behind = (np.maximum(0.0, -along[1]), np.maximum(0.0, -along[0]))
    d = _slack((np.minimum(lure_max, lure_min + lure_gain * behind[0]),
                np.minimum(lure_max, lure_min + lure_gain * behind[1])))
    ix = _slack(_sub(goal[0], I.product(d, c)))
    iy = _slack(_sub(goal[1], I.product(d, s)))
    ix = (np.clip(ix[0], box[0], box[1]), np.clip(ix[1], box[0], box[1]))
    iy = (np.clip(iy[0], box[2], box[3]), np.clip(iy[1], box[2], box[3]))
    to_ip = I.direction(_sub(ix, start[0]), _sub(iy, start[1]))
    length = _slack(_add(I.hypot(_sub(ix, start[0]), _sub(iy, start[1])),
                         I.hypot(_sub(goal[0], ix), _sub(goal[1], iy))))
    onto = I.direction(_sub(goal[0], ix), _sub(goal[1], iy))
    return length, I.abs_wrapped(*_sub(to_ip, start[2])), I.abs_wrapped(*_sub(onto, to_ip))
