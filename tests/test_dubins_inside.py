"""The shortest Dubins path inside a region (sims.dubins_inside): far from the edges the free shortest path; near
them the shortest word whose path, sampled point by point, stays inside (else the one leaving least), as an
independent scalar implementation finds it; its enclosures over boxes of poses hold every sampled value, shrink to
the value at a point and are the free path's where both ends lie far inside."""

from __future__ import annotations

import math

import numpy as np
import pytest
from tailor.sims import dubins as D
from tailor.sims import dubins_inside as DI
from test_dubins import assert_encloses, pose_boxes, sampled

RADIUS = 0.4
REGION = (-3.0, 3.0, -2.0, 2.0)


def _poses(rng: np.random.Generator, n: int, inset: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    def pose():
        return np.column_stack([rng.uniform(REGION[0] + inset, REGION[1] - inset, n),
                                rng.uniform(REGION[2] + inset, REGION[3] - inset, n), rng.uniform(-4.0, 4.0, n)])

    return pose(), pose()


def _sampled_extent(start: np.ndarray, segments: np.ndarray, signs: np.ndarray, step: float = 0.01) -> np.ndarray:
    """(xmin, xmax, ymin, ymax) of the points of a path driven from `start`, every `step` metres."""
    x, y, h = start
    xs, ys = [x], [y]
    for length, sign in zip(segments, signs):
        n = max(1, math.ceil(length / step))
        for k in range(1, n + 1):
            s = length * k / n
            if sign == 0.0:
                xs.append(x + s * math.cos(h))
                ys.append(y + s * math.sin(h))
            else:
                turn = sign * s / RADIUS
                xs.append(x + sign * RADIUS * (math.sin(h + turn) - math.sin(h)))
                ys.append(y - sign * RADIUS * (math.cos(h + turn) - math.cos(h)))
        x, y = xs[-1], ys[-1]
        h += sign * length / RADIUS
    return np.array([min(xs), max(xs), min(ys), max(ys)])


def _excess(extent: np.ndarray) -> float:
    return max(REGION[0] - extent[0], extent[1] - REGION[1], REGION[2] - extent[2], extent[3] - REGION[3])


def test_far_from_the_edges_it_is_the_free_shortest_path():
    rng = np.random.default_rng(0)
    start, goal = _poses(rng, 300, inset=DI.FAR * RADIUS)
    assert np.array_equal(np.column_stack(DI.shortest_inside(start, goal, RADIUS, REGION)),
                          np.column_stack(D.shortest(start, goal, RADIUS)))


def test_near_the_edges_it_drives_the_shortest_word_that_stays_inside():
    rng = np.random.default_rng(1)
    start, goal = _poses(rng, 400)
    length, arcs = DI.shortest_inside(start, goal, RADIUS, REGION)
    free, _ = D.shortest(start, goal, RADIUS)
    segments, _ = D.words(start, goal, RADIUS)
    totals = D.totals(segments)
    checked = 0
    for k in range(len(start)):
        exists = np.isfinite(totals[k])
        excess = np.array([_excess(_sampled_extent(start[k], segments[k, w], D.SIGN[w])) if exists[w] else np.inf
                           for w in range(len(D.WORDS))])
        inside = exists & (excess < 0.0)
        if np.any(np.abs(excess[exists]) < 1e-3) or (not inside.any() and np.sum(excess < excess.min() + 1e-3) > 1):
            continue  # (a word on the edge, or a tie in leaving: sampling cannot tell which is taken)
        pick = np.where(inside, totals[k], np.inf).argmin() if inside.any() else excess.argmin()
        assert length[k] == pytest.approx(totals[k, pick], abs=1e-9), k
        assert arcs[k] == pytest.approx(float(np.sum(segments[k, pick] * D.ARC[pick])), abs=1e-9)
        checked += 1
    assert checked > 300
    assert np.mean(length > free + 1e-6) > 0.05  # near the edges, often a longer word than the free one
    assert np.all(length >= free - 1e-12)


def _boxes(rng: np.random.Generator, k: int, width: float) -> tuple[np.ndarray, np.ndarray]:
    start, goal = _poses(rng, k)
    centre = np.column_stack([start, goal])
    widths = rng.uniform(0.0, width, (k, 6)) * np.array([1, 1, 0.5, 1, 1, 0.5])
    return centre - widths / 2, centre + widths / 2


def _sampled(low: np.ndarray, high: np.ndarray, rng: np.random.Generator, m: int) -> tuple[np.ndarray, np.ndarray]:
    return sampled(low, high, rng, m, lambda start, goal: DI.shortest_inside(start, goal, RADIUS, REGION))


@pytest.mark.parametrize("width", [0.0, 1e-6, 0.02, 0.3, 2.0, 6.0])
def test_the_enclosure_holds_every_sampled_value(width):
    rng = np.random.default_rng(int(width * 1000) + 11)
    low, high = _boxes(rng, 150, width)
    bounds = DI.shortest_inside_bounds(pose_boxes(low, high, 0), pose_boxes(low, high, 3), RADIUS, REGION)
    assert_encloses(bounds, *_sampled(low, high, rng, 300))


def test_the_enclosure_shrinks_to_the_value_and_is_the_free_one_far_inside():
    rng = np.random.default_rng(2)
    low, _ = _boxes(rng, 300, 0.0)
    (l_lo, l_hi), (a_lo, a_hi) = DI.shortest_inside_bounds(pose_boxes(low, low, 0), pose_boxes(low, low, 3),
                                                           RADIUS, REGION)
    length, arcs = DI.shortest_inside(low[:, :3], low[:, 3:], RADIUS, REGION)
    assert np.all(l_hi - l_lo < 1e-7) and np.allclose(l_lo, length, atol=1e-7)
    assert np.all(a_hi - a_lo < 1e-7) and np.allclose(a_lo, arcs, atol=1e-7)
    wide = (-30.0, 30.0, -20.0, 20.0)  # every box far inside: the free path's enclosure
    low, high = _boxes(rng, 100, 0.3)
    assert np.array_equal(np.array(DI.shortest_inside_bounds(pose_boxes(low, high, 0), pose_boxes(low, high, 3),
                                                             RADIUS, wide)),
                          np.array(D.shortest_bounds(pose_boxes(low, high, 0), pose_boxes(low, high, 3), RADIUS)))


def test_small_boxes_near_the_edges_are_mostly_enclosed_closely():
    """Where a word that surely exists surely stays inside, the choice is among the words that may stay inside
    and are no longer: small boxes get close bounds though the free shortest word leaves the region."""
    rng = np.random.default_rng(4)
    low, high = _boxes(rng, 400, 1e-6)
    (l_lo, l_hi), _ = DI.shortest_inside_bounds(pose_boxes(low, high, 0), pose_boxes(low, high, 3), RADIUS,
                                                REGION)
    centre = (low + high) / 2
    longer = DI.shortest_inside(centre[:, :3], centre[:, 3:], RADIUS, REGION)[0] > \
        D.shortest(centre[:, :3], centre[:, 3:], RADIUS)[0] + 1e-6
    assert longer.sum() > 20
    assert np.mean(l_hi[longer] - l_lo[longer] < 1e-3) > 0.6
