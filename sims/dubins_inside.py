"""The shortest Dubins path that stays inside an axis-aligned region (a vehicle in a walled workspace), over many
rows at once, and guaranteed enclosures of its length and arcs over boxes of poses.

A vehicle that plans its words inside a region (its walls, less a clearance) drives the shortest word of the six
(sims.dubins) whose path stays inside; where none does, the shortest of those that leave it least. Far from the
region's edges that is the free shortest word: every word's path lies within 4 radii of its ends (a word of two
arcs and a straight within 2: the circles at its ends and a tangent between them; the middle circle of a
three-arc word touches both), so where both ends lie that far inside, the free shortest word is taken without
computing the words' extents. Near the edges each word's extent (its ends and its arcs' extreme points) decides.

The enclosures: where both ends surely lie far inside, the free shortest word's (sims.dubins.shortest_bounds);
where every word that may be the shortest surely stays inside (its extent enclosed over the box), likewise;
elsewhere the hull over the words that may be the choice, told by each word's outer extent (all the points it may
reach) and inner one (the points it surely reaches): no longer than a word that surely stays inside, else among
those that may leave least. Sound everywhere; exact at a point; close on small boxes but where two words leave the
region within TIE of each other somewhere in the box (their tie decides).
"""

from __future__ import annotations

import numpy as np
from tailor.sims import intervals as I
from tailor.sims.dubins import ARC, SIGN, TWO_PI, WORDS, Pose, WordBounds, shortest_of, totals, words
from tailor.sims.dubins import _add, _rows, _scale, _scale_by, _slack, _stack, _sub

PI = np.pi
Region = tuple[float, float, float, float]  # xmin, xmax, ymin, ymax
FAR, NEAR = 4.0, 2.0  # radii: no word strays further from its ends; no word of two arcs and a straight
TIE = 1e-6  # m: words that leave the region by this much more than the least are as good (well above the
# widths of the extents enclosed at a point, so that such ties are told there)
EXTENT_SLACK = 1e-11  # m: widening of enclosed extents for the rounding of numpy's (far below TIE: ties are told)
_COMPASS = np.array([0.0, 0.5 * np.pi, np.pi, 1.5 * np.pi])  # east, north, west, south on an arc's circle
_EAST_X, _NORTH_Y = np.array([1.0, 0.0, -1.0, 0.0]), np.array([0.0, 1.0, 0.0, -1.0])


def extents(start: np.ndarray, lengths: np.ndarray, signs: np.ndarray, radius: float) -> np.ndarray:
    """(N, 4) the bounding box (xmin, xmax, ymin, ymax) of N paths driven from `start` (N, 3), segment lengths
    `lengths` (N, 3; NaN read as 0) and turn senses `signs` (N, 3: 1 left arc, -1 right arc, 0 straight): the
    segments' ends and the points of their arcs furthest east, north, west and south that they pass."""
    x, y, h = start[:, 0], start[:, 1], start[:, 2]
    xmin, xmax, ymin, ymax = x, x, y, y
    for s in range(3):
        length, sign = np.nan_to_num(lengths[:, s]), signs[:, s]
        arc = sign != 0.0
        k = np.where(arc, sign, 1.0) / radius
        sin_h, cos_h = np.sin(h), np.cos(h)
        eh = np.where(arc, h + k * length, h)
        ex = np.where(arc, x + (np.sin(eh) - sin_h) / k, x + length * cos_h)
        ey = np.where(arc, y - (np.cos(eh) - cos_h) / k, y + length * sin_h)
        cx, cy = x - sin_h / k, y + cos_h / k  # the arc's centre
        theta0 = np.arctan2(y - cy, x - cx)
        passed = (arc & (length > 0.0))[:, None] & (
            np.mod(np.sign(k)[:, None] * (_COMPASS - theta0[:, None]), TWO_PI) <= (np.abs(k) * length)[:, None])
        px = np.where(passed, cx[:, None] + radius * _EAST_X, ex[:, None])  # (the end point where not passed)
        py = np.where(passed, cy[:, None] + radius * _NORTH_Y, ey[:, None])
        xmin, xmax = np.minimum(xmin, px.min(axis=1)), np.maximum(xmax, px.max(axis=1))
        ymin, ymax = np.minimum(ymin, py.min(axis=1)), np.maximum(ymax, py.max(axis=1))
        x, y, h = ex, ey, eh
    return np.column_stack([xmin, xmax, ymin, ymax])


def _excess(bounds: np.ndarray, region: Region) -> np.ndarray:
    """How far paths with these bounding boxes (..., 4) leave the region (<= 0: inside)."""
    return np.max(np.stack([region[0] - bounds[..., 0], bounds[..., 1] - region[1], region[2] - bounds[..., 2],
                            bounds[..., 3] - region[3]]), axis=0)


def _within(x: np.ndarray, y: np.ndarray, region: Region, margin: float) -> np.ndarray:
    return (region[0] + margin <= x) & (x <= region[1] - margin) & (region[2] + margin <= y) & (y <= region[3] - margin)


def shortest_inside(start: np.ndarray, goal: np.ndarray, radius: float, region: Region
                    ) -> tuple[np.ndarray, np.ndarray]:
    """The length (m) of the shortest Dubins path of turning radius `radius` from the poses `start` (M, 3) to `goal`
    (M, 3) that stays inside `region`, else of the shortest of those that leave it least, and the length of its
    arcs. Where both ends lie FAR radii inside (NEAR where no word of three arcs exists), the free shortest word;
    where rounding leaves no word (the poses coincide), the straight-line distance and no arc, as
    sims.dubins.shortest."""
    segments, _ = words(start, goal, radius)
    total = totals(segments)
    rows = np.arange(len(start))
    best = np.argmin(total, axis=1)
    ends = [_within(p[:, 0], p[:, 1], region, FAR * radius) for p in (start, goal)]
    near = [_within(p[:, 0], p[:, 1], region, NEAR * radius) for p in (start, goal)]
    simple = (ends[0] & ends[1]) | (near[0] & near[1] & np.isnan(segments[:, 4:]).all(axis=(1, 2)))
    hard = np.flatnonzero(~simple)
    if len(hard):
        m = len(hard)
        box = extents(np.repeat(start[hard], len(WORDS), axis=0), segments[hard].reshape(-1, 3),
                      np.tile(SIGN, (m, 1)), radius).reshape(m, len(WORDS), 4)
        excess = np.where(np.isfinite(total[hard]), _excess(box, region), np.inf)
        inside = np.where(excess <= 0.0, total[hard], np.inf)
        least = np.where(excess <= excess.min(axis=1, keepdims=True) + TIE, total[hard], np.inf)
        best[hard] = np.where(np.isfinite(inside.min(axis=1)), np.argmin(inside, axis=1), np.argmin(least, axis=1))
    length = total[rows, best]
    arcs = (np.nan_to_num(segments[rows, best]) * ARC[best]).sum(axis=1)
    none = ~np.isfinite(length)
    return (np.where(none, np.hypot(goal[:, 0] - start[:, 0], goal[:, 1] - start[:, 1]), length),
            np.where(none, 0.0, arcs))


# --- enclosures over boxes of poses -----------------------------------------------------------------------------
def _surely_within(pose: Pose, region: Region, margin: float) -> np.ndarray:
    """Whether the position surely lies within the region less `margin` on every side (_within at every point)."""
    (x_lo, x_hi), (y_lo, y_hi) = pose[0], pose[1]
    return ((region[0] + margin <= x_lo) & (x_hi <= region[1] - margin)
            & (region[2] + margin <= y_lo) & (y_hi <= region[3] - margin))


def extent_bounds(start: Pose, seg_lo: np.ndarray, seg_hi: np.ndarray, which: np.ndarray, radius: float,
                  slack: float = EXTENT_SLACK, inner: bool = True) -> tuple[I.Pair, I.Pair, np.ndarray | None]:
    """Per (start box, word) pair, an outer box (x, y intervals) holding every point of the word's path from every
    start pose of the box (`start` intervals, (P,)), for every segment length its enclosure allows ((P, 3) lower
    and upper, m; `which` (P,) the words' indices in WORDS): per arc, its circle's centre box grown by the radius
    times the range of cos and sin over the angles it may sweep; per straight, its ends. And (P, 4) an inner one
    (the least east, greatest west, least north, greatest south the path surely reaches, in the order xmax, xmin,
    ymax, ymin): its segments' ends and the extreme points of its circles that each arc surely passes (None
    without `inner`). The outer box is widened by `slack`."""
    sign = SIGN[which]
    x, y, h = start
    x_ext, y_ext = x, y
    reached = np.stack([x[0], x[1], y[0], y[1]], axis=1) if inner else None  # east, west, north, south surely
    # reached (the start)
    s, c = I.sin_cos(*h)
    for j in range(3):
        sg = sign[:, j]
        arc = sg != 0.0
        length = (seg_lo[:, j], seg_hi[:, j])
        sx, sy = _slack(_add(x, I.product(length, c))), _slack(_add(y, I.product(length, s)))  # a straight's end
        cx, cy = _slack(_sub(x, _scale_by(s, sg * radius))), _slack(_add(y, _scale_by(c, sg * radius)))  # a centre
        first = (h[0] - sg * 0.5 * PI, h[1] - sg * 0.5 * PI)  # the angle of the start seen from the centre
        turn = _scale_by(length, sg / radius)
        end = _add(first, turn)
        swept = (np.minimum(first[0], end[0]), np.maximum(first[1], end[1]))
        h = (np.where(arc, h[0] + turn[0], h[0]), np.where(arc, h[1] + turn[1], h[1]))
        angles = _stack(swept, end, h) if j < 2 else _stack(swept, end)
        sines, cosines = I.sin_cos(*angles)
        (sweep_s, end_s), (sweep_c, end_c) = ([_rows(q, 0), _rows(q, 1)] for q in (sines, cosines))
        x_ext = (np.minimum(x_ext[0], np.where(arc, cx[0] + radius * sweep_c[0], sx[0])),
                 np.maximum(x_ext[1], np.where(arc, cx[1] + radius * sweep_c[1], sx[1])))
        y_ext = (np.minimum(y_ext[0], np.where(arc, cy[0] + radius * sweep_s[0], sy[0])),
                 np.maximum(y_ext[1], np.where(arc, cy[1] + radius * sweep_s[1], sy[1])))
        ax, ay = _slack(_add(cx, _scale(end_c, radius))), _slack(_add(cy, _scale(end_s, radius)))
        x = (np.where(arc, ax[0], sx[0]), np.where(arc, ax[1], sx[1]))
        y = (np.where(arc, ay[0], sy[0]), np.where(arc, ay[1], sy[1]))
        # the segment's end, and the compass points an arc surely passes: an angle phase + 2 pi n strictly
        # between every start angle and every end angle of its sweep (left: first < end; right: end < first)
        if not inner:
            if j < 2:
                s, c = _rows(sines, 2), _rows(cosines, 2)
            continue
        reached[:, 0], reached[:, 1] = np.maximum(reached[:, 0], x[0]), np.minimum(reached[:, 1], x[1])
        reached[:, 2], reached[:, 3] = np.maximum(reached[:, 2], y[0]), np.minimum(reached[:, 3], y[1])
        a, b = np.where(sg > 0, first[1], end[1]), np.where(sg > 0, end[0], first[0])
        margin = 1e-9 + 1e3 * I.EPS * (np.abs(a) + np.abs(b))
        for phase, q, point in ((0.0, 0, cx[0] + radius), (PI, 1, cx[1] - radius), (0.5 * PI, 2, cy[0] + radius),
                                (1.5 * PI, 3, cy[1] - radius)):  # east, west, north, south of the circle
            with np.errstate(invalid="ignore"):
                passed = arc & (phase + TWO_PI * np.ceil((a + margin - phase) / TWO_PI) <= b - margin)
            better = np.maximum if q in (0, 2) else np.minimum
            reached[:, q] = np.where(passed, better(reached[:, q], point), reached[:, q])
        if j < 2:
            s, c = _rows(sines, 2), _rows(cosines, 2)
    return _slack(x_ext, slack), _slack(y_ext, slack), (reached if inner else None)


def shortest_inside_bounds(start: Pose, goal: Pose, radius: float, region: Region) -> tuple[I.Pair, I.Pair]:
    """shortest_inside's (length, arcs) enclosed over k boxes of poses (see the module's docstring). The length is
    never below the free shortest word's; near the edges it is at most the longest of the words that may exist and
    are no longer than a word that surely exists and surely stays inside (the choice is never longer than that
    one), and the arcs the hull over those words."""
    with np.errstate(invalid="ignore", over="ignore"):  # (unbounded boxes: NaN tests decide nothing, as wanted)
        bounds = WordBounds(start, goal, radius)
        free = shortest_of(bounds, start, goal, radius)
        far = _surely_within(start, region, FAR * radius) & _surely_within(goal, region, FAR * radius)
        near = (_surely_within(start, region, NEAR * radius) & _surely_within(goal, region, NEAR * radius)
                & ~bounds.maybe[:, 4:].any(axis=1))
        simple = far | near
        excess = _excess_bounds(start, bounds, ~simple, radius, region)
        stays, leaves = excess[1] <= 0.0, excess[0] > 0.0
        # where every word that may be the shortest surely stays inside, the shortest is the choice
        upper = np.where(bounds.surely, bounds.hi, np.inf).min(axis=1)
        candidate = bounds.maybe & (bounds.lo <= upper[:, None])
        simple |= (stays | ~candidate).all(axis=1) & candidate.any(axis=1)
        # where a word surely exists and surely stays inside, the choice is an inside word no longer than it;
        # elsewhere a word that may stay inside, or one that may leave least (no more than TIE beyond a word that
        # surely exists leaves at most)
        chosen_upper = np.where(bounds.surely & stays, bounds.hi, np.inf).min(axis=1)
        inside_only = np.isfinite(chosen_upper)[:, None]
        least = np.where(bounds.surely, excess[1], np.inf).min(axis=1)
        choices = bounds.maybe & np.where(inside_only, ~leaves & (bounds.lo <= chosen_upper[:, None]),
                                          ~leaves | (excess[0] <= least[:, None] + TIE))
        # where every word that may exist surely leaves, the choice is the shortest of those leaving least: no
        # longer than a word that surely exists and surely leaves within TIE of the least any word may leave
        outside = (leaves | ~bounds.maybe).all(axis=1)
        least_possible = np.where(bounds.maybe, excess[0], np.inf).min(axis=1)
        tied = bounds.surely & (excess[1] <= least_possible[:, None] + TIE - 1e-12)
        tie_upper = np.where(tied & outside[:, None], bounds.hi, np.inf).min(axis=1)
        choices &= bounds.lo <= tie_upper[:, None]
        fallback = ~bounds.surely.any(axis=1)  # (where no word surely exists: the straight line with no arc)
        straight = I.hypot(_sub(goal[0], start[0]), _sub(goal[1], start[1]))
        longest = np.where(choices, bounds.hi, -np.inf).max(axis=1)
        longest = np.where(fallback, np.maximum(longest, straight[1]), longest)
        arcs_lo = np.where(choices, bounds.arcs_lo, np.inf).min(axis=1)
        arcs_hi = np.where(choices, bounds.arcs_hi, -np.inf).max(axis=1)
        arcs_lo = np.where(fallback, np.minimum(arcs_lo, 0.0), arcs_lo)
        arcs_hi = np.where(fallback, np.maximum(arcs_hi, 0.0), arcs_hi)
        unbounded = ~np.all([np.isfinite(end) for pose in (start, goal) for pair in pose[:2] for end in pair], axis=0)
        # (no choice left only where rounding decided every test: then the free shortest word's bounds too)
        none = ~choices.any(axis=1)
        hull_upper = np.where(unbounded, np.inf, np.where(none, np.maximum(longest, free[0][1]), longest))
        hull_arcs = _slack((np.where(unbounded, 0.0, np.where(none, np.minimum(arcs_lo, free[1][0]), arcs_lo)),
                            np.where(unbounded, np.inf, np.where(none, np.maximum(arcs_hi, free[1][1]), arcs_hi))),
                           1e-9)
        shortest_choice = np.where(choices, bounds.lo, np.inf).min(axis=1)
        hull_lower = np.where(fallback | unbounded, free[0][0], np.maximum(free[0][0], shortest_choice))
        length = (np.where(simple, free[0][0], hull_lower), np.where(simple, free[0][1], hull_upper))
        arcs = (np.where(simple, free[1][0], hull_arcs[0]), np.where(simple, free[1][1], hull_arcs[1]))
    # at a single point (every interval of no width) the value itself: the certified optimizer splits boxes down
    # to points and needs the enclosure to shrink to the value there
    k = len(simple)
    point = np.all([np.broadcast_to(a == b, (k,)) for pose in (start, goal) for a, b in pose], axis=0)
    if point.any():
        ends = [np.column_stack([np.broadcast_to(a, (k,))[point] for a, _ in pose]) for pose in (start, goal)]
        value, value_arcs = shortest_inside(*ends, radius, region)
        length[0][point], length[1][point] = value, value
        arcs[0][point], arcs[1][point] = value_arcs, value_arcs
    return length, arcs


def _excess_bounds(start: Pose, bounds: WordBounds, rows: np.ndarray, radius: float, region: Region
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(k, 6) each: lower and upper bounds of how far each word that may exist leaves the region (_excess, <= 0:
    inside) from the start poses of the box, through its inner and outer extent; on the boxes `rows` only
    (-inf and inf elsewhere)."""
    k = bounds.lo.shape[0]
    at, which = np.nonzero(bounds.maybe & rows[:, None])
    low, high = np.full((k, len(WORDS)), -np.inf), np.full((k, len(WORDS)), np.inf)
    if len(at):
        sub = tuple((np.broadcast_to(a, (k,))[at], np.broadcast_to(b, (k,))[at]) for a, b in start)
        (x_lo, x_hi), (y_lo, y_hi), reached = extent_bounds(sub, bounds.seg_lo[at, which], bounds.seg_hi[at, which],
                                                          which, radius)
        outer = np.max([region[0] - x_lo, x_hi - region[1], region[2] - y_lo, y_hi - region[3]], axis=0)
        inner = np.max([reached[:, 0] - region[1], region[0] - reached[:, 1], reached[:, 2] - region[3],
                        region[2] - reached[:, 3]], axis=0)
        slack = EXTENT_SLACK + 1e3 * I.EPS * np.abs(reached).max(axis=1)  # (the inner points' rounding)
        low[at, which], high[at, which] = inner - slack, outer
    return low, high
