"""Dubins paths (sims.soccer.dubins) against hand-computed lengths, symmetry and dense sampling."""

import math

import numpy as np
import pytest

from tailor.sims.soccer.dubins import (WORDS, all_paths, bounds, distance_to, sample, shortest_path,
                                shortest_path_inside)

R = 0.5


def test_straight_line():
    path = shortest_path((0.0, 0.0, 0.0), (2.0, 0.0, 0.0), R)
    assert path.length == pytest.approx(2.0)
    assert path.lengths[1] == pytest.approx(2.0) and path.word[1] == "S"


def test_half_circle_left_and_right():
    left = shortest_path((0.0, 0.0, 0.0), (0.0, 2 * R, math.pi), R)
    right = shortest_path((0.0, 0.0, 0.0), (0.0, -2 * R, math.pi), R)
    assert left.length == pytest.approx(math.pi * R) and right.length == pytest.approx(math.pi * R)
    assert set(left.word) - {"S"} == {"L"} and set(right.word) - {"S"} == {"R"}


def test_quarter_turn_straight_quarter_turn():
    # heading up at the origin, heading down at (d, 0): right quarter circle, straight d - 2R, right quarter
    d = 3.0
    path = shortest_path((0.0, 0.0, math.pi / 2), (d, 0.0, -math.pi / 2), R)
    assert path.word == "RSR"
    assert path.lengths == pytest.approx((math.pi * R / 2, d - 2 * R, math.pi * R / 2))


def test_turning_back_on_the_spot_needs_a_loop():
    # the same position, reversed heading: three mutually tangent circles, arcs of pi/3, 5 pi/3 and pi/3
    # (the middle circle touches both end circles, whose centres are 2R apart): 7/3 pi R
    path = shortest_path((0.0, 0.0, 0.0), (0.0, 0.0, math.pi), R)
    assert path.word in ("RLR", "LRL")
    assert path.length == pytest.approx(7.0 / 3.0 * math.pi * R)


def test_mirror_symmetry_swaps_left_and_right():
    rng = np.random.default_rng(0)
    swap = str.maketrans("LR", "RL")
    for _ in range(50):
        x, y, h, gx, gy, gh = rng.uniform(-2, 2, 6)
        a = shortest_path((x, y, h), (gx, gy, gh), R)
        b = shortest_path((x, -y, -h), (gx, -gy, -gh), R)
        assert a.length == pytest.approx(b.length, abs=1e-9)
        if all_paths((x, y, h), (gx, gy, gh), R)[1].length > a.length + 1e-6:  # a unique shortest word
            assert a.word.translate(swap) == b.word


def test_every_word_ends_at_the_goal_and_the_shortest_is_first():
    rng = np.random.default_rng(1)
    for _ in range(200):
        start, goal = tuple(rng.uniform(-3, 3, 3)), tuple(rng.uniform(-3, 3, 3))
        paths = all_paths(start, goal, R)
        assert {p.word for p in paths} <= set(WORDS) and len(paths) >= 4  # the four CSC words always exist
        assert [p.length for p in paths] == sorted(p.length for p in paths)
        for p in paths:
            x, y, h = sample(start, p, 0.05)[-1]
            if p.exact:
                assert math.hypot(x - goal[0], y - goal[1]) < 1e-6
                assert abs(math.remainder(h - goal[2], 2 * math.pi)) < 1e-6
            else:  # circles overlapping by at most TANGENT_SLACK: taken as touching, the end lies near the goal
                assert p.word in ("LSR", "RSL") and p.lengths[1] == 0.0
                assert math.hypot(x - goal[0], y - goal[1]) < 2 * R


def test_bounds_and_distance_match_dense_sampling():
    rng = np.random.default_rng(2)
    for _ in range(100):
        start, goal = tuple(rng.uniform(-3, 3, 3)), tuple(rng.uniform(-3, 3, 3))
        point = tuple(rng.uniform(-3, 3, 2))
        for p in all_paths(start, goal, R):
            pts = np.array(sample(start, p, 0.002))[:, :2]
            assert bounds(start, p) == pytest.approx((pts[:, 0].min(), pts[:, 0].max(), pts[:, 1].min(),
                                                      pts[:, 1].max()), abs=1e-5)
            assert distance_to(start, p, point) == pytest.approx(np.hypot(*(pts - point).T).min(), abs=1e-3)


def test_shortest_path_inside_avoids_a_wall():
    # a U-turn to the left would cross the wall at y = 0.6; the right one stays below it
    start, goal = (0.0, 0.0, 0.0), (0.0, 0.0, math.pi)
    box = (-5.0, 5.0, -5.0, 0.6)
    path = shortest_path_inside(start, goal, R, box)
    assert bounds(start, path)[3] <= 0.6
    assert path.length > shortest_path(start, goal, R).length - 1e-9


def test_bad_radius_raises():
    with pytest.raises(ValueError, match="radius must be positive"):
        shortest_path((0, 0, 0), (1, 0, 0), 0.0)
