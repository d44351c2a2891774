"""Routes round the furniture: shortest paths through a visibility graph of the grown obstacles.

Why a visibility graph: the kitchen's obstacles are a handful of boxes, so the graph of their grown corners
has a few dozen nodes and gives the exact shortest path in the configuration space of the round base (each
box grown by the base radius and a clearance); a grid would be coarser and slower. The same routes serve the
simulator's navigate (planned on the scene's actual furniture) and the `route` features of its action model
(on the nominal map), vectorized over many start/goal pairs for the optimizers.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from tailor.sims.kitchen import world as W

EPS = 1e-6
CORNER_MARGIN = 0.02  # m, graph nodes lie this far outside the grown boxes' corners


def _box_arrays(boxes: Sequence[W.Box], grow: float) -> np.ndarray:
    """(b, 5): centre x, y, half sizes grown, angle."""
    return np.array([(b.cx, b.cy, b.hx + grow, b.hy + grow, b.angle) for b in boxes], dtype=float).reshape(-1, 5)


def _inside(points: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """(n, b) bool: point strictly inside box."""
    dx = points[:, None, 0] - boxes[None, :, 0]
    dy = points[:, None, 1] - boxes[None, :, 1]
    c, s = np.cos(boxes[:, 4]), np.sin(boxes[:, 4])
    u, w = c * dx + s * dy, -s * dx + c * dy
    return (np.abs(u) < boxes[:, 2] - EPS) & (np.abs(w) < boxes[:, 3] - EPS)


def _rotated(dx: np.ndarray, dy: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """(2, ..., b): the vectors (dx, dy) (broadcast against the last axis, one per box) along each box's axes."""
    c, s = np.cos(boxes[:, 4]), np.sin(boxes[:, 4])
    return np.stack([c * dx + s * dy, -s * dx + c * dy])


def _crosses(origin: np.ndarray, delta: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """(..., b) bool: the segment from `origin` by `delta` (in each box's frame, from _rotated) passes through the
    box's interior (slab test, both slabs at once)."""
    h = (boxes[:, 2:4] - EPS).T.reshape((2,) + (1,) * (origin.ndim - 2) + (len(boxes),))
    with np.errstate(divide="ignore", invalid="ignore"):
        t1, t2 = (-h - origin) / delta, (h - origin) / delta
    flat, inside = np.abs(delta) < 1e-12, np.abs(origin) < h
    t_lo = np.where(flat, np.where(inside, -np.inf, np.inf), np.minimum(t1, t2))
    t_hi = np.where(flat, np.where(inside, np.inf, -np.inf), np.maximum(t1, t2))
    return np.maximum(t_lo.max(axis=0), 0.0) < np.minimum(t_hi.min(axis=0), 1.0) - 1e-9


def blocked(p: np.ndarray, q: np.ndarray, boxes: np.ndarray, ignore: np.ndarray | None = None) -> np.ndarray:
    """(n,) bool: segment p->q passes through the interior of a box (slab test in each box's frame);
    `ignore` (n, b) bool masks boxes out per segment."""
    origin = _rotated(p[:, None, 0] - boxes[None, :, 0], p[:, None, 1] - boxes[None, :, 1], boxes)
    delta = _rotated((q[:, 0] - p[:, 0])[:, None], (q[:, 1] - p[:, 1])[:, None], boxes)
    hit = _crosses(origin, delta, boxes)
    if ignore is not None:
        hit &= ~ignore
    return hit.any(axis=1)


class RouteMap:
    """The visibility graph of a set of obstacles grown by the base radius and CLEARANCE, with all-pairs
    shortest distances between its nodes."""

    def __init__(self, obstacles: Sequence[W.Box], grow: float = W.BASE_RADIUS + W.CLEARANCE):
        self.boxes = _box_arrays(obstacles, grow)
        corners = [c for b in obstacles for c in b.corners(grow + CORNER_MARGIN)]
        nodes = np.array(corners, dtype=float).reshape(-1, 2)
        keep = ~_inside(nodes, self.boxes).any(axis=1)
        keep &= (nodes[:, 0] > 0) & (nodes[:, 0] < W.ROOM_LENGTH) & (nodes[:, 1] > 0) & (nodes[:, 1] < W.ROOM_WIDTH)
        self.nodes = nodes[keep]
        v = len(self.nodes)
        i, j = np.triu_indices(v, 1)
        free = ~blocked(self.nodes[i], self.nodes[j], self.boxes)
        dist = np.full((v, v), np.inf)
        np.fill_diagonal(dist, 0.0)
        lengths = np.hypot(*(self.nodes[i] - self.nodes[j]).T)
        dist[i[free], j[free]] = lengths[free]
        dist[j[free], i[free]] = lengths[free]
        nxt = np.where(np.isfinite(dist), np.arange(v)[None, :], -1)
        for k in range(v):  # Floyd-Warshall, remembering the next node on each shortest path
            via = dist[:, k:k + 1] + dist[k:k + 1, :]
            better = via < dist
            dist = np.where(better, via, dist)
            nxt = np.where(better, nxt[:, k:k + 1], nxt)
        self.dist, self.next = dist, nxt

    def _visible(self, points: np.ndarray, inside: np.ndarray) -> np.ndarray:
        """(n, v) bool: node visible from each point, the boxes it lies in (`inside`, (n, b)) ignored: blocked() of
        every point-node segment, each point's offsets to the boxes computed once."""
        boxes = self.boxes
        origin = _rotated(points[:, None, 0] - boxes[None, :, 0], points[:, None, 1] - boxes[None, :, 1], boxes)
        ddx = self.nodes[None, :, 0] - points[:, None, 0]  # (n, v)
        ddy = self.nodes[None, :, 1] - points[:, None, 1]
        hit = _crosses(origin[:, :, None, :], _rotated(ddx[..., None], ddy[..., None], boxes), boxes)  # (n, v, b)
        hit &= ~inside[:, None, :]
        return ~hit.any(axis=2)

    def routes(self, start: np.ndarray, goal: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Vectorized shortest routes: (length, first node index or -1 if direct, last node index or -1,
        turning at the inner nodes in rad) for each start/goal row (n, 2). The graph is searched only for the
        rows whose straight segment is blocked."""
        start, goal = np.atleast_2d(start), np.atleast_2d(goal)
        n = len(start)
        inside = _inside(np.concatenate([start, goal]), self.boxes)
        ignore = inside[:n] | inside[n:]
        direct = ~blocked(start, goal, self.boxes, ignore)
        length = np.hypot(*(goal - start).T)
        first, last, turning = np.full(n, -1), np.full(n, -1), np.zeros(n)
        around = np.flatnonzero(~direct)
        if len(around):
            s, g = start[around], goal[around]
            # each end tested once where every row shares it (an optimizer's population shares the start of the
            # window's first action), both ends in one call
            points = np.concatenate([start, goal])
            ends = [rows[:1] if len(rows) > 1 and (points[rows] == points[rows[0]]).all() else rows
                    for rows in (around, n + around)]
            tested = np.concatenate(ends)
            vs, vg = np.split(self._visible(points[tested], inside[tested]), [len(ends[0])])  # (1, v): broadcast
            ds, dg = self._to_nodes(s, vs), self._to_nodes(g, vg)
            total = (ds[:, :, None] + self.dist[None, :, :] + dg[:, None, :]).reshape(len(around), -1)  # (m, v * v)
            flat = total.argmin(axis=1)
            first[around], last[around] = np.divmod(flat, len(self.nodes))
            length[around] = total[np.arange(len(around)), flat]
            turning[around] = self._turning(s, g, first[around], last[around])
        return length, first, last, turning

    def _to_nodes(self, points: np.ndarray, visible: np.ndarray) -> np.ndarray:
        """(n, v): each point's straight distance to each node it sees (`visible`), inf to the others."""
        dx, dy = points[:, None, 0] - self.nodes[None, :, 0], points[:, None, 1] - self.nodes[None, :, 1]
        return np.where(visible, np.hypot(dx, dy), np.inf)

    def _pair_tables(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per node pair (i, j) on a shortest path: the turning at its inner nodes, the direction of its first
        leg out of i and of its last leg into j (built once, on first use)."""
        if getattr(self, "_pairs", None) is None:
            v = len(self.nodes)
            inner, out_dir, in_dir = np.zeros((v, v)), np.zeros((v, v)), np.zeros((v, v))
            for i in range(v):
                for j in range(v):
                    if i == j or not np.isfinite(self.dist[i, j]):
                        continue
                    pts = self.path_points(self.nodes[i], self.nodes[j], i, j)[1:-1]
                    inner[i, j] = _turning(pts)
                    out_dir[i, j] = math.atan2(pts[1][1] - pts[0][1], pts[1][0] - pts[0][0])
                    in_dir[i, j] = math.atan2(pts[-1][1] - pts[-2][1], pts[-1][0] - pts[-2][0])
            self._pairs = (inner, out_dir, in_dir)
        return self._pairs

    def _turning(self, start, goal, first, last) -> np.ndarray:
        """Turning (rad) at the corners of routes through the graph from node `first` to node `last`, vectorized
        with the pair tables."""
        inner, out_dir, in_dir = self._pair_tables()
        vi, vj = self.nodes[first], self.nodes[last]
        into_i = np.arctan2(vi[:, 1] - start[:, 1], vi[:, 0] - start[:, 0])
        out_j = np.arctan2(goal[:, 1] - vj[:, 1], goal[:, 0] - vj[:, 0])
        same = first == last
        at_i = np.where(same, out_j, out_dir[first, last])
        at_j = np.where(same, 0.0, np.abs(_wrap(out_j - in_dir[first, last])))
        return np.abs(_wrap(at_i - into_i)) + np.where(same, 0.0, inner[first, last]) + at_j

    def path_points(self, start, goal, first: int, last: int) -> list[tuple[float, float]]:
        pts = [(float(start[0]), float(start[1]))]
        if first >= 0:
            k = first
            pts.append(tuple(self.nodes[k]))
            while k != last:
                k = int(self.next[k, last])
                pts.append(tuple(self.nodes[k]))
        pts.append((float(goal[0]), float(goal[1])))
        return pts

    def inside(self, point: tuple[float, float]) -> bool:
        """The point lies in an obstacle grown by the base radius and the clearance (the base cannot stand there)."""
        return bool(_inside(np.array([point], dtype=float), self.boxes).any())

    def path(self, start: tuple[float, float], goal: tuple[float, float]) -> list[tuple[float, float]]:
        """The shortest route from start to goal as way-points (start and goal included); a straight line
        where no route exists (the robot will then collide or time out: an outcome, not an error)."""
        s, g = np.array([start], dtype=float), np.array([goal], dtype=float)
        length, first, last, _ = self.routes(s, g)
        if not np.isfinite(length[0]):
            return [tuple(start), tuple(goal)]
        return self.path_points(s[0], g[0], int(first[0]), int(last[0]))


def leg_distance(path: Sequence[tuple[float, float]], k: int, x: float, y: float) -> float:
    """Distance from (x, y) to a route's leg k (the segment from path[k] to path[k + 1])."""
    (ax, ay), (bx, by) = path[k], path[k + 1]
    dx, dy = bx - ax, by - ay
    square = dx * dx + dy * dy
    t = 0.0 if square == 0.0 else max(0.0, min(1.0, ((x - ax) * dx + (y - ay) * dy) / square))
    return math.hypot(x - ax - t * dx, y - ay - t * dy)


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2 * np.pi) - np.pi


def _turning(points: Sequence[tuple[float, float]]) -> float:
    total = 0.0
    for a, b, c in zip(points, points[1:], points[2:]):
        h1 = math.atan2(b[1] - a[1], b[0] - a[0])
        h2 = math.atan2(c[1] - b[1], c[0] - b[0])
        total += abs(W.wrap(h2 - h1))
    return total


_NOMINAL: RouteMap | None = None


def nominal_map() -> RouteMap:
    """The route map of the nominal layout (built once)."""
    global _NOMINAL
    if _NOMINAL is None:
        _NOMINAL = RouteMap(W.nominal_obstacles())
    return _NOMINAL
