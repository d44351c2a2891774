"""goToPose's own feature space (sims/soccer/features.py, "goto"): the word its controller plans inside the walls,
that word's detour (the controller's switch to the lure at MAX_DETOUR) and the lure through the IP, by hand and
against the scalar functions the controller itself calls."""

from __future__ import annotations

import math

import numpy as np
from tailor.refinement.models.features import compute_features, feature_space
from tailor.sims.soccer.control import axle_pose
from tailor.sims.soccer.features import GOTO_FEATURES, goto_path_features, lure_features
from tailor.sims.soccer.goto import GOTO, GOTO_STRAIGHT, LURE_MIN, MAX_DETOUR, goto_path, lure_point
from tailor.sims.soccer.walls import mirror_field
from tailor.sims.soccer.world import BALL_POINT_OFFSET


def _params(rng: np.random.Generator, n: int) -> np.ndarray:
    """Starts anywhere up to the walls, goals anywhere on the field."""
    return np.column_stack([rng.uniform(-4.4, 4.4, n), rng.uniform(-3.4, 3.4, n), rng.uniform(-math.pi, math.pi, n),
                            rng.uniform(0, 0.6, n), rng.uniform(-4, 4, n), rng.uniform(-3, 3, n),
                            rng.uniform(-math.pi, math.pi, n), rng.uniform(0, 0.6, n)])


def test_the_goto_space_is_the_pose_space_plus_the_word_and_the_lure():
    params = _params(np.random.default_rng(0), 200)
    features = compute_features("goto", params)
    assert feature_space("goto").names == GOTO_FEATURES
    np.testing.assert_array_equal(features[:, :5], compute_features("pose", params))
    np.testing.assert_array_equal(features[:, 5:9], goto_path_features(params))
    np.testing.assert_array_equal(features[:, 9:], lure_features(params))


def test_a_batch_with_repeated_poses_gives_each_row_its_own_features():
    """The paths are planned once per distinct pair of poses (speeds do not change them): in a batch where
    speeds vary over repeated poses, as a genetic algorithm's or a neighbourhood's, each row still gets exactly
    the features it gets alone, in every soccer space."""
    rng = np.random.default_rng(5)
    poses = _params(rng, 6)
    batch = poses[rng.integers(0, 6, 40)]
    batch[:, [3, 7]] = rng.uniform(0, 0.6, (40, 2))
    for space in ("goto", "approach", "dribble"):
        alone = np.vstack([compute_features(space, row[None, :]) for row in batch])
        np.testing.assert_array_equal(compute_features(space, batch), alone)


def test_word_and_detour_are_the_ones_the_controller_compares_with_max_detour():
    """For 1000 random poses: the length of the word goto_path plans (plus the final straight) and its detour over
    the straight line to the pre-pose, the quantity goToPose compares with MAX_DETOUR to choose the lure."""
    params = _params(np.random.default_rng(1), 1000)
    features = goto_path_features(params)
    lured = 0
    for p, (path, _, _, detour) in zip(params, features):
        start, goal = axle_pose(*p[:3]), axle_pose(p[4], p[5], p[6])
        pre = GOTO.pre_pose(goal)
        planned = goto_path(start, pre)
        np.testing.assert_allclose(path, planned.length + GOTO_STRAIGHT, atol=1e-9)
        np.testing.assert_allclose(detour, planned.length - math.hypot(pre[0] - start[0], pre[1] - start[1]),
                                   atol=1e-9)
        lured += detour > MAX_DETOUR
    assert 100 < lured < 900  # both of the controller's ways occur: the feature separates them


def test_the_lure_by_hand_and_against_the_controllers_ip():
    """Straight behind the goal, facing it, 2 m off: the IP lies LURE_MIN + LURE_GAIN * 2 behind the goal, on the
    way; the length is the distance, no turn toward the IP, none at it."""
    d = 2.0
    (length, bearing, turn), = lure_features(np.array([[-d, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.3]]))
    np.testing.assert_allclose([length, bearing, turn], [d, 0.0, 0.0], atol=1e-9)
    # facing away from a goal ahead of it: the IP LURE_MIN behind the goal (the robot is in front of it)
    (length, bearing, turn), = lure_features(np.array([[1.0, 0.0, math.pi, 0.0, 0.0, 0.0, 0.0, 0.3]]))
    ax = 1.0 - BALL_POINT_OFFSET * math.cos(math.pi)  # the axle, BALL_POINT_OFFSET behind the ball point
    gx = -BALL_POINT_OFFSET
    ip = gx - LURE_MIN
    np.testing.assert_allclose([length, bearing, turn], [ax - ip + (gx - ip), 0.0, math.pi], atol=1e-9)
    for p in _params(np.random.default_rng(2), 300):
        start, goal = axle_pose(*p[:3]), axle_pose(p[4], p[5], p[6])
        ix, iy = lure_point(start, goal)
        want = math.hypot(ix - start[0], iy - start[1]) + math.hypot(goal[0] - ix, goal[1] - iy)
        np.testing.assert_allclose(lure_features(p[None, :])[0, 0], want, atol=1e-9)


def test_the_goto_features_are_invariant_to_mirroring_the_field():
    rng = np.random.default_rng(3)
    params = _params(rng, 500)
    np.testing.assert_allclose(compute_features("goto", mirror_field(params, rng)), compute_features("goto", params),
                               atol=1e-7)
