"""A guaranteed enclosure of the `route` features (length, turn at the start, turn at the goal, turning at the
corners) over boxes of start and goal positions and headings, for the certified optimizer.

The route a RouteMap gives is the straight line where nothing blocks it, else the shortest of the candidate
routes start -> node i -> (shortest path) -> node j -> goal over the nodes each end sees. Over a box, each of
these is decided where it can be: a family of segments from one box to a point or another box is certainly
clear when the convex hull of both misses every obstacle (grown by CLEAR_MARGIN: separating-axis test over the
obstacles' axes, the boxes' axes and the hull's bridging edges), certainly blocked when the segments between
all corners cross one obstacle shrunk by BLOCK_MARGIN and no end lies in it (the points from which a segment to
a fixed point crosses a convex obstacle form a convex set, so the corners decide). Undecided, a candidate is
kept as possible but not certain. The length lies between the least lower length of the possible candidates
(and at least the straight distance) and the least upper length of the certain ones; every candidate whose
lower length is below that upper length may be the one chosen, and the angle features are the hull of theirs,
each an interval arithmetic of directions between boxes (sims.intervals). At a single point every test is
decided (but within the margins of grazing an obstacle's corner) and one candidate is chosen: the bounds are
the features.

The margins are far above the rounding of the tests and below anything a route notices: a segment that crosses
an obstacle shrunk by BLOCK_MARGIN overlaps the obstacle as `blocked` tests it (shrunk by its EPS) over a
length of about 2 BLOCK_MARGIN, far above its 1e-9 of the segment.
"""

from __future__ import annotations

import numpy as np
from tailor.sims import intervals as I
from tailor.sims.kitchen.navigation import EPS, RouteMap, blocked

CLEAR_MARGIN = 1e-6  # m, obstacles grown by this for "certainly clear"
BLOCK_MARGIN = 1e-4  # m, and shrunk by this for "certainly blocked"
SHORT = 1e-3  # m: a route shorter than this has no leg to face (kitchen.features._route)
Box2 = tuple[I.Pair, I.Pair]  # (x, y) intervals of k boxes


def _corners(box: Box2) -> np.ndarray:
    """(k, 4, 2) corners of k axis-aligned boxes."""
    (x_lo, x_hi), (y_lo, y_hi) = box
    return np.stack([np.column_stack([x_lo, y_lo]), np.column_stack([x_hi, y_lo]),
                     np.column_stack([x_hi, y_hi]), np.column_stack([x_lo, y_hi])], axis=1)


def _apart(points: np.ndarray, axes: np.ndarray, obstacles: np.ndarray, grow: float) -> np.ndarray:
    """(k, b) bool: the convex hull of each row's points (k, m, 2) lies apart from each obstacle (centre, half
    sizes, angle; grown by `grow`) along one of the row's axes (k, a, 2), the first two of them x and y, or one of
    the obstacle's own (separating axes: a superset of both polygons' edge normals decides exactly whether two
    convex polygons meet). The obstacle's extent along an axis in closed form, its centre's projection plus
    its half sizes times the axis' components along its sides."""
    centre, half, angle = obstacles[:, :2], obstacles[:, 2:4] + grow, obstacles[:, 4]
    u = np.column_stack([np.cos(angle), np.sin(angle)])
    w = np.column_stack([-u[:, 1], u[:, 0]])
    projected = np.matmul(points, axes.transpose(0, 2, 1))  # (k, m, a)
    lo, hi = projected.min(axis=1)[:, :, None], projected.max(axis=1)[:, :, None]
    mid = np.matmul(axes, centre.T)  # (k, a, b)
    reach = half[:, 0] * np.abs(np.matmul(axes, u.T)) + half[:, 1] * np.abs(np.matmul(axes, w.T))
    apart = ((hi < mid - reach) | (lo > mid + reach)).any(axis=1)
    if np.any(np.mod(angle, 0.5 * np.pi) != 0.0):  # a turned obstacle: its own axes are not x and y
        own = np.concatenate([u, w])  # (2b, 2)
        projected = np.matmul(points, own.T)  # (k, m, 2b)
        lo, hi = projected.min(axis=1), projected.max(axis=1)
        mid, reach = (own * np.concatenate([centre, centre])).sum(axis=1), np.concatenate([half[:, 0], half[:, 1]])
        side = (hi < mid - reach) | (lo > mid + reach)
        apart |= side[:, :len(angle)] | side[:, len(angle):]
    return apart


def _within(points: np.ndarray, obstacles: np.ndarray) -> np.ndarray:
    """(k, b) bool: every point of the convex hull of each row's points (k, m, 2) lies strictly inside each
    obstacle less EPS (and a little more for rounding), where `_inside` ignores it: all its corners do."""
    dx = points[:, :, None, 0] - obstacles[None, None, :, 0]
    dy = points[:, :, None, 1] - obstacles[None, None, :, 1]
    c, s = np.cos(obstacles[:, 4]), np.sin(obstacles[:, 4])
    u, w = c * dx + s * dy, -s * dx + c * dy
    margin = EPS + CLEAR_MARGIN
    return ((np.abs(u) < obstacles[:, 2] - margin) & (np.abs(w) < obstacles[:, 3] - margin)).all(axis=1)


def _normals(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(k, m * n, 2) normals of the segments between each row's points a (k, m, 2) and b (k, n, 2)."""
    d = (b[:, None, :, :] - a[:, :, None, :]).reshape(len(a), -1, 2)
    return np.stack([-d[..., 1], d[..., 0]], axis=-1)


def _crossed(routes: RouteMap, ends: np.ndarray, others: np.ndarray) -> np.ndarray:
    """(k, b) bool: every segment between a point of `ends` (k, 4, 2) and one of `others` (k, m, 2) crosses each
    obstacle shrunk by BLOCK_MARGIN (`blocked` shrinks by its EPS, so by BLOCK_MARGIN - EPS more)."""
    k, m = len(ends), others.shape[1]
    shrunk = routes.boxes.copy()
    shrunk[:, 2:4] -= BLOCK_MARGIN - EPS
    p = np.repeat(ends, m, axis=1).reshape(-1, 2)
    q = np.tile(others, (1, 4, 1)).reshape(-1, 2)
    return np.stack([blocked(p, q, shrunk[o:o + 1]).reshape(k, 4 * m).all(axis=1) for o in range(len(shrunk))],
                    axis=1)


def _eye(k: int) -> np.ndarray:
    return np.broadcast_to(np.eye(2), (k, 2, 2))


def _families(routes: RouteMap, ends: np.ndarray, others: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Whether every segment from the box with corners `ends` (k, 4, 2) to the box with corners `others` (k, 4, 2)
    is clear of every obstacle, and whether every one is blocked (k,) each."""
    k = len(ends)
    boxes = routes.boxes
    axes = np.concatenate([_eye(k), _normals(ends, others)], axis=1)
    # an obstacle an end lies in (as `_inside` tests it, strictly within its half sizes less EPS) is ignored
    ignored = _within(ends, boxes) | _within(others, boxes)
    clear = (_apart(np.concatenate([ends, others], axis=1), axes, boxes, CLEAR_MARGIN) | ignored).all(axis=1)
    # outside an obstacle (none of its points ignores it), and every corner pair crosses it
    outside = _apart(ends, _eye(k), boxes, 0.0) & _apart(others, _eye(k), boxes, 0.0)
    return clear, (_crossed(routes, ends, others) & outside).any(axis=1)


def _seen(routes: RouteMap, corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(k, v) each: whether every point of each box (its corners (k, 4, 2)) sees each node, and whether none
    does: _families from a box to a point, the tests of the box alone made once per box, and boxes alike (a
    fixed end of a route) tested once."""
    unique, inverse = np.unique(corners.reshape(len(corners), -1), axis=0, return_inverse=True)
    unique = unique.reshape(-1, 4, 2)
    u, v, boxes = len(unique), len(routes.nodes), routes.boxes
    ends = np.repeat(unique, v, axis=0)  # (u v, 4, 2)
    nodes = np.tile(routes.nodes, (u, 1))[:, None, :]  # (u v, 1, 2)
    axes = np.concatenate([_eye(u * v), _normals(ends, nodes)], axis=1)
    hull = np.concatenate([ends, nodes], axis=1)
    ignored = np.repeat(_within(unique, boxes), v, axis=0) | np.tile(_within(routes.nodes[:, None], boxes), (u, 1))
    clear = (_apart(hull, axes, boxes, CLEAR_MARGIN) | ignored).all(axis=1)
    outside = (np.repeat(_apart(unique, _eye(u), boxes, 0.0), v, axis=0)
               & np.tile(_apart(routes.nodes[:, None], _eye(v), boxes, 0.0), (u, 1)))
    blocked_ = (_crossed(routes, ends, nodes) & outside).any(axis=1)
    inverse = inverse.reshape(-1)
    return clear.reshape(u, v)[inverse], blocked_.reshape(u, v)[inverse]


def _to_point(box: Box2, point: np.ndarray, towards: bool) -> tuple[Box2, I.Pair]:
    """The box of differences point - box (towards) or box - point, and the interval of distances."""
    (x_lo, x_hi), (y_lo, y_hi) = box
    if towards:
        dx, dy = (point[0] - x_hi, point[0] - x_lo), (point[1] - y_hi, point[1] - y_lo)
    else:
        dx, dy = (x_lo - point[0], x_hi - point[0]), (y_lo - point[1], y_hi - point[1])
    return (dx, dy), I.hypot(dx, dy)


def route_bounds(routes: RouteMap, start: Box2, start_phi: I.Pair, goal: Box2, goal_phi: I.Pair
                 ) -> tuple[np.ndarray, np.ndarray]:
    """(low, high), each (k, 4): the enclosure of (length, turn_start, turn_goal, turning) over k boxes of start
    and goal positions (x, y intervals) and headings (unwrapped intervals)."""
    k, v = len(start[0][0]), len(routes.nodes)
    s_corners, g_corners = _corners(start), _corners(goal)
    direct_clear, direct_blocked = _families(routes, s_corners, g_corners)
    s_clear, s_blocked = _seen(routes, s_corners)
    g_clear, g_blocked = _seen(routes, g_corners)

    # the straight route: the box of differences goal - start
    (sx, sy), (gx, gy) = start, goal
    straight = (gx[0] - sx[1], gx[1] - sx[0]), (gy[0] - sy[1], gy[1] - sy[0])
    straight_length = I.hypot(*straight)
    straight_dir = I.direction(*straight)
    # the candidates via nodes i, j: their lengths (k, v, v)
    into, out, d_start, d_goal = [], [], [], []
    for i, node in enumerate(routes.nodes):
        diff, dist = _to_point(start, node, towards=True)
        into.append(I.direction(*diff))
        d_start.append(dist)
        diff, dist = _to_point(goal, node, towards=False)
        out.append(I.direction(*diff))
        d_goal.append(dist)
    into_lo, into_hi = (np.stack([a[e] for a in into], axis=1) for e in (0, 1))  # (k, v)
    out_lo, out_hi = (np.stack([a[e] for a in out], axis=1) for e in (0, 1))
    ds_lo, ds_hi = (np.stack([a[e] for a in d_start], axis=1) for e in (0, 1))
    dg_lo, dg_hi = (np.stack([a[e] for a in d_goal], axis=1) for e in (0, 1))
    finite = np.isfinite(routes.dist)[None]
    via_lo, via_hi = I.widen(ds_lo[:, :, None] + routes.dist[None] + dg_lo[:, None, :],
                             ds_hi[:, :, None] + routes.dist[None] + dg_hi[:, None, :])
    possible = ~s_blocked[:, :, None] & ~g_blocked[:, None, :] & finite
    certain = s_clear[:, :, None] & g_clear[:, None, :] & finite
    around_lo = np.where(possible, via_lo, np.inf).reshape(k, -1).min(axis=1)
    around_hi = np.where(certain, via_hi, np.inf).reshape(k, -1).min(axis=1)
    chosen = possible & (via_lo <= around_hi[:, None, None])
    chosen[:, 0, 0] |= ~certain.reshape(k, -1).any(axis=1)  # no route seen anywhere: argmin's first, length inf

    may_straight, may_around = ~direct_blocked, ~direct_clear
    length_lo = np.minimum(np.where(may_straight, straight_length[0], np.inf),
                           np.where(may_around, around_lo, np.inf))
    length_lo = np.maximum(length_lo, straight_length[0])  # no route is shorter than the straight line
    length_hi = np.maximum(np.where(may_straight, straight_length[1], -np.inf),
                           np.where(may_around, around_hi, -np.inf))

    # the angle features of each route that may be taken: the straight one, and every chosen candidate
    def hull(straight: I.Pair, around: I.Pair) -> I.Pair:
        lo = np.where(chosen & may_around[:, None, None], around[0], np.inf).reshape(k, -1).min(axis=1)
        hi = np.where(chosen & may_around[:, None, None], around[1], -np.inf).reshape(k, -1).max(axis=1)
        return (np.minimum(lo, np.where(may_straight, straight[0], np.inf)),
                np.maximum(hi, np.where(may_straight, straight[1], -np.inf)))

    def grid(a: np.ndarray, axis: int) -> np.ndarray:
        return np.broadcast_to(np.expand_dims(a, axis), (k, v, v))

    s_phi = (start_phi[0][:, None], start_phi[1][:, None])
    g_phi = (goal_phi[0][:, None], goal_phi[1][:, None])
    face = I.abs_wrapped(into_lo - s_phi[1], into_hi - s_phi[0])  # (k, v): turn to face node i
    arrive = I.abs_wrapped(g_phi[0] - out_hi, g_phi[1] - out_lo)  # (k, v): turn at the goal from node j
    turn_start = hull(I.abs_wrapped(straight_dir[0] - start_phi[1], straight_dir[1] - start_phi[0]),
                      (grid(face[0], 2), grid(face[1], 2)))
    turn_goal = hull(I.abs_wrapped(goal_phi[0] - straight_dir[1], goal_phi[1] - straight_dir[0]),
                     (grid(arrive[0], 1), grid(arrive[1], 1)))
    inner, out_dir, in_dir = routes._pair_tables()
    same = np.eye(v, dtype=bool)[None]
    leave = I.abs_wrapped(out_dir[None] - grid(into_hi, 2), out_dir[None] - grid(into_lo, 2))
    enter = I.abs_wrapped(grid(out_lo, 1) - in_dir[None], grid(out_hi, 1) - in_dir[None])
    pass_by = I.abs_wrapped(grid(out_lo, 1) - grid(into_hi, 2), grid(out_hi, 1) - grid(into_lo, 2))
    corners_lo = np.where(same, pass_by[0], leave[0] + inner[None] + enter[0])
    corners_hi = np.where(same, pass_by[1], leave[1] + inner[None] + enter[1])
    turning = hull((np.zeros(k), np.zeros(k)), I.widen(corners_lo, corners_hi, 1e-12))

    # a route shorter than SHORT: no turn at the start, the goal's turn from the start heading
    short = I.abs_wrapped(goal_phi[0] - start_phi[1], goal_phi[1] - start_phi[0])
    may_short, may_long = length_lo < SHORT, ~(length_hi < SHORT)
    turn_start = (np.where(may_short, 0.0, np.where(may_long, turn_start[0], np.inf)),
                  np.where(may_long, turn_start[1], 0.0))
    turn_goal = (np.minimum(np.where(may_short, short[0], np.inf), np.where(may_long, turn_goal[0], np.inf)),
                 np.maximum(np.where(may_short, short[1], -np.inf), np.where(may_long, turn_goal[1], -np.inf)))
    length = I.widen(length_lo, length_hi, 1e-12)
    low = np.column_stack([length[0], turn_start[0], turn_goal[0], turning[0]])
    high = np.column_stack([length[1], turn_start[1], turn_goal[1], turning[1]])
    return low, high
