"""The soccer robot's pose spaces (Table 4.1's pose rows, tailor.sims.soccer.pose): hand-computed features,
invariance to moving the whole scene, and piecewise affinity in headings and speeds (App. C.3.4)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tailor.refinement.models.features import FEATURE_SPACES, compute_features, feature_names, feature_spaces
from tailor.sims.soccer import SIMULATOR
from tailor.sims.soccer.pose import POSE_PARAMETERS, norm
from synthetic_episodes import random_params

PI = math.pi
POSE_SPACES = ("pose", "pose_delta", "position")  # Table 4.1's rows of a navigation to a pose


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


def test_the_pose_spaces_come_with_the_soccer_robot():
    assert set(POSE_SPACES) <= {s.name for s in SIMULATOR.feature_spaces}
    assert all(feature_spaces()[name].parameters == POSE_PARAMETERS for name in POSE_SPACES)
    assert not set(POSE_SPACES) & set(FEATURE_SPACES)  # not the core's
    assert feature_names("pose_delta") == feature_names("pose") + ("delta_angle",)
    assert feature_names("position") == ("v", "dist", "angle_to")  # Table 4.1's goToPosition row


def test_the_position_space_ignores_the_goal_heading_and_speed():
    params = random_params(50, seed=4)
    other = params.copy()
    other[:, 6:] = np.random.default_rng(5).uniform(-3, 3, (50, 2))
    pose = compute_features("pose", params)
    np.testing.assert_array_equal(compute_features("position", params), pose[:, [0, 2, 3]])
    np.testing.assert_array_equal(compute_features("position", other), compute_features("position", params))


@pytest.mark.parametrize("space", POSE_SPACES)
@pytest.mark.parametrize("mirror", [False, True])
def test_features_invariant_to_translation_rotation_and_mirroring(space, mirror):
    params = random_params(500, seed=1)
    before = compute_features(space, params)
    for angle, shift in ((0.7, (1.5, -2.0)), (-2.9, (-3.0, 0.4)), (PI, (0.0, 0.0))):
        after = compute_features(space, transform(params, angle, shift, mirror))
        np.testing.assert_allclose(after, before, atol=1e-9)


def test_features_see_a_change_of_the_goal_relative_to_the_robot():
    params = random_params(200, seed=2)
    moved = params.copy()
    moved[:, 6] += 0.3  # turn only the goal heading: angle_at must change, the rest must not
    a, b = compute_features("pose", params), compute_features("pose", moved)
    np.testing.assert_array_equal(a[:, :4], b[:, :4])
    assert np.all(np.abs(b[:, 4] - a[:, 4]) > 0.29)


@pytest.mark.parametrize("space", POSE_SPACES)
@pytest.mark.parametrize("column", [2, 3, 6, 7])  # phi, v, phig, vg
def test_features_piecewise_affine_in_headings_and_speeds(space, column):
    """With positions fixed, each feature is affine in phi, v, phig, vg between a few kinks (App. C.3.4)."""
    base = random_params(20, seed=3)
    grid = np.linspace(-PI, PI, 2001) if column in (2, 6) else np.linspace(0.0, 1.0, 2001)
    for row in base:
        params = np.repeat(row[None, :], len(grid), axis=0)
        params[:, column] = grid
        values = compute_features(space, params)
        bends = np.abs(np.diff(values, n=2, axis=0)) > 1e-9  # second differences vanish on affine pieces
        assert np.all(bends.sum(axis=0) <= 8), bends.sum(axis=0)
