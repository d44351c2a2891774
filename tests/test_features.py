"""Feature spaces (Table 4.1) and intermediate examples (Sec. 4.1.2)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tailor.errors import DataError
from tailor.refinement.models.features import (
    FEATURE_SPACES,
    feature_spaces,
    POSE_PARAMETERS,
    compute_features,
    feature_names,
    first_examples,
    intermediate_examples,
)
from tailor.sims.episode import Episode
from tailor.sims.pose import norm
from synthetic_episodes import COLUMNS, random_params

PI = math.pi
# the feature spaces of a navigation to a pose (x, y, phi, v, xg, yg, phig, vg)
POSE_SPACES = sorted(name for name, space in FEATURE_SPACES.items() if space.parameters == POSE_PARAMETERS)


def transform(params: np.ndarray, angle: float, shift: tuple[float, float], mirror: bool) -> np.ndarray:
    """Rotate the whole scene by `angle` about the origin, translate it by `shift`, optionally mirror in y."""
    out = params.copy()
    c, s = math.cos(angle), math.sin(angle)
    for xi, yi, hi in ((0, 1, 2), (4, 5, 6)):
        x, y = params[:, xi], params[:, yi]
        out[:, xi] = c * x - s * y + shift[0]
        out[:, yi] = s * x + c * y + shift[1]
        out[:, hi] = params[:, hi] + angle
        if mirror:
            out[:, yi], out[:, hi] = -out[:, yi], -out[:, hi]
    return out


def test_norm_wraps_into_minus_pi_to_pi():
    angles = np.array([0.0, 0.5, PI - 1e-9, PI + 0.25, -PI - 0.25, 7 * PI + 0.1, -5.0])
    wrapped = norm(angles)
    assert np.all((wrapped >= -PI) & (wrapped < PI))
    np.testing.assert_allclose(wrapped, [0.0, 0.5, PI - 1e-9, -PI + 0.25, PI - 0.25, -PI + 0.1, 2 * PI - 5.0], atol=1e-12)


def test_pose_features_by_hand():
    names = feature_names("pose")
    assert names == ("v", "vg", "dist", "angle_to", "angle_at")
    params = np.array([
        # robot at the origin facing +x, goal at (1, 1) facing +y: goal 45 deg to the left, arrive 45 deg left
        [0.0, 0.0, 0.0, 0.3, 1.0, 1.0, PI / 2, 0.1],
        # robot facing +y: the goal is 45 deg to its right, so angle_at is mirrored: -norm(0 - pi/4)
        [0.0, 0.0, PI / 2, 0.0, 1.0, 1.0, 0.0, 0.2],
        # across the wrap: bearing pi, heading -3 -> angle_to_signed = 3 - pi < 0; phig = -3
        [1.0, 2.0, -3.0, 0.5, -1.0, 2.0, -3.0, 0.0],
    ])
    expected = np.array([
        [0.3, 0.1, math.sqrt(2), PI / 4, PI / 4],
        [0.0, 0.2, math.sqrt(2), PI / 4, PI / 4],
        [0.5, 0.0, 2.0, PI - 3.0, -(PI - 3.0)],
    ])
    np.testing.assert_allclose(compute_features("pose", params), expected, atol=1e-12)
    delta = compute_features("pose_delta", params)[:, -1]
    np.testing.assert_allclose(delta, [PI / 2, PI / 2, 0.0], atol=1e-12)


def test_the_pose_spaces_are_registered():
    assert POSE_SPACES == ["pose", "pose_delta", "position"]
    assert FEATURE_SPACES["pose_delta"].names == feature_names("pose") + ("delta_angle",)
    assert feature_names("position") == ("v", "dist", "angle_to")  # Table 4.1's goToPosition row


def test_the_position_space_ignores_the_goal_heading_and_speed():
    params = random_params(50, seed=4)
    other = params.copy()
    other[:, 6:] = np.random.default_rng(5).uniform(-3, 3, (50, 2))
    pose = compute_features("pose", params)
    np.testing.assert_array_equal(compute_features("position", params), pose[:, [0, 2, 3]])
    np.testing.assert_array_equal(compute_features("position", other), compute_features("position", params))


@pytest.mark.parametrize("feature_set", POSE_SPACES)
@pytest.mark.parametrize("mirror", [False, True])
def test_features_invariant_to_translation_rotation_and_mirroring(feature_set, mirror):
    params = random_params(500, seed=1)
    before = compute_features(feature_set, params)
    for angle, shift in ((0.7, (1.5, -2.0)), (-2.9, (-3.0, 0.4)), (PI, (0.0, 0.0))):
        after = compute_features(feature_set, transform(params, angle, shift, mirror))
        np.testing.assert_allclose(after, before, atol=1e-9)


def test_features_see_a_change_of_the_goal_relative_to_the_robot():
    params = random_params(200, seed=2)
    moved = params.copy()
    moved[:, 6] += 0.3  # turn only the goal heading: angle_at must change, the rest must not
    a, b = compute_features("pose", params), compute_features("pose", moved)
    np.testing.assert_array_equal(a[:, :4], b[:, :4])
    assert np.all(np.abs(b[:, 4] - a[:, 4]) > 0.29)


@pytest.mark.parametrize("name", sorted(feature_spaces()))
def test_every_feature_space_passes_its_own_invariance_test(name):
    """The generic spaces and those the installed simulators bring (the arm's ramps)."""
    space = feature_spaces()[name]
    rng = np.random.default_rng(4)
    params = rng.uniform(-3.0, 3.0, (300, len(space.parameters)))
    before = space(params)
    assert before.shape == (300, len(space.names)) and np.all(np.isfinite(before))
    assert space.transform is not None, f"{name} declares no invariance test ({space.invariance})"
    for _ in range(5):
        moved = space.transform(params, rng)
        assert not np.allclose(moved, params)  # the transform changes the parameters ...
        np.testing.assert_allclose(space(moved), before, atol=1e-9)  # ... but not the features


@pytest.mark.parametrize("feature_set", POSE_SPACES)
@pytest.mark.parametrize("column", [2, 3, 6, 7])  # phi, v, phig, vg
def test_features_piecewise_affine_in_headings_and_speeds(feature_set, column):
    """With positions fixed, each feature is affine in phi, v, phig, vg between a few kinks (App. C.3.4)."""
    base = random_params(20, seed=3)
    grid = np.linspace(-PI, PI, 2001) if column in (2, 6) else np.linspace(0.0, 1.0, 2001)
    for row in base:
        params = np.repeat(row[None, :], len(grid), axis=0)
        params[:, column] = grid
        values = compute_features(feature_set, params)
        bends = np.abs(np.diff(values, n=2, axis=0)) > 1e-9  # second differences vanish on affine pieces
        assert np.all(bends.sum(axis=0) <= 8), bends.sum(axis=0)


def test_compute_features_rejects_bad_input():
    with pytest.raises(ValueError, match=r"shape \(n, 8\)"):
        compute_features("pose", np.zeros((3, 7)))
    with pytest.raises(DataError, match=r"unknown feature space 'speed' \(known: .*pose.*\)"):
        compute_features("speed", np.zeros((1, 8)))
    assert compute_features("pose", np.zeros(8)).shape == (1, 5)


def make_episode(rows: int, duration: float, seed: int = 0) -> Episode:
    t = np.arange(rows) * 0.1
    robot = np.column_stack([np.arange(rows) + 100.0 * seed, np.zeros(rows), np.zeros(rows), np.full(rows, 0.5)])
    state = np.column_stack([robot, np.full((rows, 2), np.nan)])  # no ball
    params = np.array([100.0 * seed, 0.0, 0.0, 0.5, 9.0, 1.0, 0.5, 0.2])
    return Episode("goToPose", params, t, state, COLUMNS, "success", duration, seed)


def test_intermediate_examples_take_the_first_n_i_rows_of_each_episode():
    episodes = [make_episode(5, 0.45, seed=0), make_episode(2, 0.15, seed=1)]
    params, targets, owner = intermediate_examples(episodes, 3, observed=("x", "y", "phi", "v"))
    np.testing.assert_array_equal(owner, [0, 0, 0, 1, 1])  # the short episode gives all it has
    np.testing.assert_allclose(targets, [0.45, 0.35, 0.25, 0.15, 0.05])
    np.testing.assert_array_equal(params[:, 0], [0.0, 1.0, 2.0, 100.0, 101.0])  # logged x at t_k
    np.testing.assert_array_equal(params[:, 3], 0.5)
    np.testing.assert_array_equal(params[:, 4:], np.tile([9.0, 1.0, 0.5, 0.2], (5, 1)))  # the goal stays

    first, durations = first_examples(episodes)
    np.testing.assert_array_equal(first, params[[0, 3]])
    np.testing.assert_array_equal(durations, [0.45, 0.15])
    with pytest.raises(ValueError, match="n_i must be at least 1"):
        intermediate_examples(episodes, 0, observed=("x", "y", "phi", "v"))


def test_intermediate_examples_read_the_observed_parameters_by_column_name():
    episode = make_episode(4, 0.35)
    # the state columns in another order: the observed parameters are still read by name
    order = [3, 5, 0, 4, 2, 1]
    shuffled = Episode(episode.action, episode.params, episode.t, episode.state[:, order],
                       tuple(COLUMNS[i] for i in order), episode.outcome, episode.duration, episode.seed)
    expected = intermediate_examples([episode], 4, ("x", "y", "phi", "v"))
    got = intermediate_examples([shuffled], 4, ("x", "y", "phi", "v"))
    for a, b in zip(expected, got):
        np.testing.assert_array_equal(a, b)
    # a line move observes (x, v): the logged x and v, then the episode's remaining parameters
    params, _, _ = intermediate_examples([episode], 2, ("x", "v"))
    np.testing.assert_array_equal(params[:, :2], [[0.0, 0.5], [1.0, 0.5]])
    np.testing.assert_array_equal(params[:, 2:], np.tile(episode.params[2:], (2, 1)))
    with pytest.raises(KeyError, match="no state column 'z'"):
        intermediate_examples([episode], 2, ("x", "z"))
