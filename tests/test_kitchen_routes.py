"""The kitchen's routes round the furniture (sims.kitchen.navigation), vectorized over many start/goal pairs,
against a plain one-pair-at-a-time search written here with scalar geometry; and the time-optimal transfer of
sims.kinematics against its closed forms."""

import math

import numpy as np
import pytest

from tailor.sims.kinematics import transfer_time
from tailor.sims.kitchen import world as W
from tailor.sims.kitchen.navigation import EPS, nominal_map


def _through(p, q, box) -> bool:
    """Whether the segment p->q passes through the interior of `box` (cx, cy, hx, hy, angle): the segment clipped
    to each slab of the box's frame, one pair of numbers at a time."""
    cx, cy, hx, hy, angle = box
    c, s = math.cos(angle), math.sin(angle)
    lo, hi = 0.0, 1.0
    for origin, delta, half in ((c * (p[0] - cx) + s * (p[1] - cy), c * (q[0] - p[0]) + s * (q[1] - p[1]), hx),
                                (-s * (p[0] - cx) + c * (p[1] - cy), -s * (q[0] - p[0]) + c * (q[1] - p[1]), hy)):
        h = half - EPS
        if abs(delta) < 1e-12:
            if abs(origin) >= h:
                return False
            continue
        t1, t2 = (-h - origin) / delta, (h - origin) / delta
        lo, hi = max(lo, min(t1, t2)), min(hi, max(t1, t2))
    return lo < hi - 1e-9


def _inside(point, box) -> bool:
    cx, cy, hx, hy, angle = box
    c, s = math.cos(angle), math.sin(angle)
    u, w = c * (point[0] - cx) + s * (point[1] - cy), -s * (point[0] - cx) + c * (point[1] - cy)
    return abs(u) < hx - EPS and abs(w) < hy - EPS


def _clear(p, q, boxes, ignore) -> bool:
    return not any(_through(p, q, b) for b in boxes if not any(_inside(x, b) for x in ignore))


def _route(routes, start, goal) -> tuple[float, int, int]:
    """Length, first and last node of the shortest route from start to goal, one pair: straight where nothing
    is in the way, else the best pair of nodes visible from either end joined through the graph."""
    boxes = [tuple(b) for b in routes.boxes]
    if _clear(start, goal, boxes, (start, goal)):
        return math.hypot(goal[0] - start[0], goal[1] - start[1]), -1, -1
    best = (math.inf, 0, 0)
    nodes = [tuple(n) for n in routes.nodes]
    for i, a in enumerate(nodes):
        if not _clear(start, a, boxes, (start,)):
            continue
        for j, b in enumerate(nodes):
            if not _clear(goal, b, boxes, (goal,)):
                continue
            length = math.dist(start, a) + routes.dist[i, j] + math.dist(b, goal)
            if length < best[0]:
                best = (length, i, j)
    return best


def _points(rng, n):
    return rng.uniform([-0.3, -0.3], [W.ROOM_LENGTH + 0.3, W.ROOM_WIDTH + 0.3], (n, 2))


@pytest.mark.parametrize("shared", [None, "start", "goal"])
def test_vectorized_routes_are_the_one_pair_search(shared):
    routes = nominal_map()
    rng = np.random.default_rng(3)
    start, goal = _points(rng, 300), _points(rng, 300)
    if shared == "start":  # an optimizer's population: every row starts where the window starts
        start[:] = start[7]
    elif shared == "goal":
        goal[:] = goal[11]
    length, first, last, _ = routes.routes(start, goal)
    expected = [_route(routes, tuple(s), tuple(g)) for s, g in zip(start, goal)]
    assert 0 < sum(f < 0 for f in first) < len(first)  # both straight and round-the-furniture rows
    for k, (d, i, j) in enumerate(expected):
        assert (first[k], last[k]) == (i, j)
        assert length[k] == pytest.approx(d, rel=1e-12, abs=1e-12)


def test_a_route_of_a_batch_is_the_route_of_its_row_alone():
    routes = nominal_map()
    rng = np.random.default_rng(4)
    start, goal = _points(rng, 200), _points(rng, 200)
    start[:100] = start[0]
    together = routes.routes(start, goal)
    for k in range(0, 200, 7):
        alone = routes.routes(start[k:k + 1], goal[k:k + 1])
        for a, b in zip(together, alone):
            assert a[k] == b[0]


def test_transfer_time_meets_its_closed_forms():
    v, a = 0.6, 0.5
    d = np.array([0.1, 0.5, 0.72, 3.0])
    rest_to_rest = np.where(d >= v * v / a, d / v + v / a, 2.0 * np.sqrt(d / a))  # triangle or trapezoid
    assert transfer_time(d, 0.0, 0.0, v, a) == pytest.approx(rest_to_rest, rel=1e-12)
    # from rest to passing at top speed: ramp up then cruise where the ramp fits
    assert transfer_time(3.0, 0.0, v, v, a) == pytest.approx(3.0 / v + v / (2 * a), rel=1e-12)
    # at top speed to rest: cruise, then brake
    assert transfer_time(3.0, v, 0.0, v, a) == pytest.approx(3.0 / v + v / (2 * a), rel=1e-12)
    # too short to brake from top speed: overshoot and come back (the profile passes through zero)
    assert transfer_time(0.1, v, 0.0, v, a) > v / a


def test_transfer_time_of_a_batch_is_that_of_each_row():
    rng = np.random.default_rng(5)
    d, v0, vg = rng.uniform(-4, 4, 500), rng.uniform(-1, 1, 500), rng.uniform(-1, 1, 500)
    v0[::5] = 0.0
    batch = transfer_time(d, v0, vg, 0.8, 0.6)
    assert batch.shape == (500,)
    assert [float(t) for t in batch] == [float(transfer_time(*row, 0.8, 0.6)) for row in zip(d, v0, vg)]
    assert transfer_time(np.ones((3, 4)), 0.0, np.zeros(4), 1.0, 1.0).shape == (3, 4)
