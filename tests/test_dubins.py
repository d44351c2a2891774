"""Dubins paths over many rows (sims.dubins): the shortest length equals an independent scalar implementation and
its word really drives from the start pose to the goal; the enclosures over boxes of poses hold every sampled
value, shrink to the value at a point and stay within a small factor of the sampled range on small boxes; the
soccer robot's enclosure of the words is the same computation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from tailor.sims import dubins as D

RADIUS = 0.4


def _poses(rng: np.random.Generator, n: int, spread: float = 3.0) -> tuple[np.ndarray, np.ndarray]:
    def pose():
        return np.column_stack([rng.uniform(-spread, spread, (n, 2)), rng.uniform(-4.0, 4.0, n)])

    return pose(), pose()


def _drive(start: np.ndarray, segments: np.ndarray, signs: np.ndarray, radius: float) -> np.ndarray:
    """The pose reached from `start` driving each segment (arc length `segments[j]`, turn sense `signs[j]`)."""
    x, y, h = start
    for length, sign in zip(segments, signs):
        if sign == 0.0:
            x, y = x + length * math.cos(h), y + length * math.sin(h)
        else:
            turn = sign * length / radius
            x += sign * radius * (math.sin(h + turn) - math.sin(h))
            y -= sign * radius * (math.cos(h + turn) - math.cos(h))
            h += turn
    return np.array([x, y, h])


def test_the_shortest_length_is_the_exact_scalar_one_and_its_word_reaches_the_goal():
    from tailor.sims.soccer.dubins import candidates  # an independent, scalar implementation

    rng = np.random.default_rng(0)
    start, goal = _poses(rng, 400)
    start[:40, 2] = goal[:40, 2]  # parallel headings, and goals straight ahead: straights and their limits
    goal[40:60] = start[40:60] + np.column_stack([np.cos(start[40:60, 2]), np.sin(start[40:60, 2]), 0 * start[40:60, 2]])
    length, arcs = D.shortest(start, goal, RADIUS)
    segments, _ = D.words(start, goal, RADIUS)
    totals = D.totals(segments)
    for k in range(len(start)):
        exact = [c for c in candidates(tuple(start[k]), tuple(goal[k]), RADIUS) if c[3]]
        assert length[k] == pytest.approx(exact[0][0], abs=1e-9)
        w = int(np.argmin(totals[k]))
        end = _drive(start[k], segments[k, w], D.SIGN[w], RADIUS)
        assert np.allclose(end[:2], goal[k, :2], atol=1e-6)
        assert abs(math.remainder(end[2] - goal[k, 2], 2 * math.pi)) < 1e-6
        assert arcs[k] == pytest.approx(float(np.sum(segments[k, w] * D.ARC[w])), abs=1e-12)
    straight = np.hypot(*(goal[:, :2] - start[:, :2]).T)
    assert np.all(length >= straight - 1e-9) and np.all(arcs <= length + 1e-12)
    assert np.allclose(length[40:60], 1.0) and np.allclose(arcs[40:60], 0.0, atol=1e-9)  # dead ahead: straight


def test_a_radius_near_zero_is_the_straight_line_and_the_turns_at_its_ends():
    rng = np.random.default_rng(1)
    start, goal = _poses(rng, 200)
    radius = 1e-4
    length, arcs = D.shortest(start, goal, radius)
    straight = np.hypot(*(goal[:, :2] - start[:, :2]).T)
    assert np.allclose(length, straight, atol=10 * radius)
    assert np.all(arcs <= 2 * np.pi * radius * 1.01)


def _boxes(rng: np.random.Generator, k: int, width: float) -> tuple[np.ndarray, np.ndarray]:
    centre = np.column_stack([rng.uniform(-3, 3, (k, 2)), rng.uniform(-4, 4, k),
                              rng.uniform(-3, 3, (k, 2)), rng.uniform(-4, 4, k)])
    widths = rng.uniform(0.0, width, (k, 6)) * np.array([1, 1, 0.5, 1, 1, 0.5])
    return centre - widths / 2, centre + widths / 2


def pose_boxes(low: np.ndarray, high: np.ndarray, first: int) -> D.Pose:
    """The pose intervals of boxes (k, 6) of start and goal poses, from column `first` (0: start, 3: goal)."""
    return tuple((low[:, first + j], high[:, first + j]) for j in range(3))


def sampled(low: np.ndarray, high: np.ndarray, rng: np.random.Generator, m: int, shortest
            ) -> tuple[np.ndarray, np.ndarray]:
    """(k, m) lengths and arcs `shortest(starts, goals)` gives at m points of each box, 64 of its corners among
    them."""
    u = rng.uniform(size=(len(low), m, 6))
    u[:, :64] = [[(c >> j) & 1 for j in range(6)] for c in range(64)]
    points = (low[:, None] + u * (high - low)[:, None]).reshape(-1, 6)
    length, arcs = shortest(points[:, :3], points[:, 3:])
    return length.reshape(len(low), m), arcs.reshape(len(low), m)


def _sampled(low: np.ndarray, high: np.ndarray, rng: np.random.Generator, m: int) -> tuple[np.ndarray, np.ndarray]:
    return sampled(low, high, rng, m, lambda start, goal: D.shortest(start, goal, RADIUS))


@pytest.mark.parametrize("width", [0.0, 1e-6, 0.02, 0.3, 2.0, 8.0])
def test_the_enclosure_holds_every_sampled_value(width):
    rng = np.random.default_rng(int(width * 1000) + 7)
    low, high = _boxes(rng, 150, width)
    bounds = D.shortest_bounds(pose_boxes(low, high, 0), pose_boxes(low, high, 3), RADIUS)
    assert_encloses(bounds, *_sampled(low, high, rng, 300))


def assert_encloses(bounds, length: np.ndarray, arcs: np.ndarray) -> None:
    """Each box's (length, arcs) enclosure holds every value sampled in it (a row per box), finite, lengths >= 0."""
    (l_lo, l_hi), (a_lo, a_hi) = bounds
    assert np.all(l_lo[:, None] <= length) and np.all(length <= l_hi[:, None])
    assert np.all(a_lo[:, None] <= arcs) and np.all(arcs <= a_hi[:, None])
    assert np.all(np.isfinite(l_hi)) and np.all(l_lo >= 0.0)


def test_the_enclosure_shrinks_to_the_value_and_is_close_on_small_boxes():
    rng = np.random.default_rng(2)
    low, _ = _boxes(rng, 200, 0.0)
    (l_lo, l_hi), (a_lo, a_hi) = D.shortest_bounds(pose_boxes(low, low, 0), pose_boxes(low, low, 3), RADIUS)
    length, arcs = D.shortest(low[:, :3], low[:, 3:], RADIUS)
    assert np.all(l_hi - l_lo < 1e-7) and np.allclose(l_lo, length, atol=1e-7)
    assert np.all(a_hi - a_lo < 1e-7) and np.allclose(a_lo, arcs, atol=1e-7)
    for width, typical in ((0.02, 2.0), (0.3, 2.5)):  # bound width over sampled range: median, not worst
        low, high = _boxes(rng, 300, width)
        (l_lo, l_hi), _ = D.shortest_bounds(pose_boxes(low, high, 0), pose_boxes(low, high, 3), RADIUS)
        length, _ = _sampled(low, high, rng, 200)
        spread = length.max(axis=1) - length.min(axis=1)
        assert np.median((l_hi - l_lo) / np.maximum(spread, 1e-12)) < typical


def test_unbounded_boxes_give_sound_whole_ranges():
    inf = (np.array([-np.inf]), np.array([np.inf]))
    zero = (np.zeros(1), np.zeros(1))
    (l_lo, l_hi), (a_lo, a_hi) = D.shortest_bounds((zero, zero, inf), (inf, inf, inf), RADIUS)
    assert l_lo[0] == 0.0 and l_hi[0] == np.inf and a_lo[0] <= 0.0 and a_hi[0] >= 3 * D.FULL * RADIUS
    (l_lo, l_hi), _ = D.shortest_bounds((zero, zero, inf), (zero, (np.ones(1), np.ones(1)), inf), RADIUS)
    assert l_lo[0] >= 1.0 - 2e-9 and l_hi[0] <= 1.0 + D.LOOP * RADIUS + 1e-9  # any headings: LSL's bound


def test_many_boxes_are_enclosed_in_chunks_exactly_as_each_alone():
    """WordBounds encloses more than CHUNK boxes a chunk at a time: every row as it is when enclosed alone."""
    rng = np.random.default_rng(3)
    low, high = _boxes(rng, D.CHUNK + 150, 0.1)
    many = D.WordBounds(pose_boxes(low, high, 0), pose_boxes(low, high, 3), RADIUS, 1e-3)
    rows = [0, D.CHUNK - 1, D.CHUNK, D.CHUNK + 149]
    few = D.WordBounds(pose_boxes(low[rows], high[rows], 0), pose_boxes(low[rows], high[rows], 3), RADIUS, 1e-3)
    for name in ("lo", "hi", "arcs_lo", "arcs_hi", "surely", "maybe", "exact_surely", "exact_maybe", "seg_lo",
                 "seg_hi"):
        assert np.array_equal(getattr(many, name)[rows], getattr(few, name)), name
