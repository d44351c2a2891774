"""The soccer robot's wall-aware feature space (sims/soccer/walls.py): by hand, piecewise affine in the
headings and speeds (so refinement stays analytic), and it tells apart what the pose row cannot."""

import math

import numpy as np
import pytest
from tailor.refinement.models.features import compute_features, feature_spaces
from tailor.sims.soccer.walls import NAMES, WALL_X, WALL_Y


def test_registered_by_the_soccer_simulator():
    assert "pose_walls" in feature_spaces()
    assert feature_spaces()["pose_walls"].names == NAMES


def test_by_hand():
    # start (1, -2) heading +x at 0.2 m/s; goal (-3.5, 0.5) heading pi/2 (+y), arriving at 0.1 m/s
    row = np.array([[1.0, -2.0, 0.0, 0.2, -3.5, 0.5, 0.5 * math.pi, 0.1]])
    f = dict(zip(NAMES, compute_features("pose_walls", row)[0]))
    bearing = math.atan2(2.5, -4.5)
    assert f["v"] == 0.2 and f["vg"] == 0.1
    assert f["dist"] == pytest.approx(math.hypot(4.5, 2.5))
    assert f["angle_to"] == pytest.approx(abs(bearing))
    assert f["start_wall_x"] == pytest.approx(WALL_X - 1.0)  # the end wall at +WALL_X is nearer
    assert f["start_wall_y"] == pytest.approx(WALL_Y - 2.0)  # the side wall at -WALL_Y
    assert f["start_heading_x"] == pytest.approx(0.0)  # heading straight at the +x end wall
    assert f["start_heading_y"] == pytest.approx(0.5 * math.pi)  # along the side wall
    assert f["goal_wall_x"] == pytest.approx(WALL_X - 3.5)
    assert f["goal_wall_y"] == pytest.approx(WALL_Y - 0.5)
    assert f["goal_heading_x"] == pytest.approx(0.5 * math.pi)  # along the -x end wall
    assert f["goal_heading_y"] == pytest.approx(0.0)  # straight at the +y side wall


def test_sees_the_wall_the_pose_row_cannot():
    """The same goal relative to the robot, once mid-field and once against an end wall: the pose features
    are equal, the wall features are not."""
    mid = np.array([[0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]])
    wall = mid + np.array([[3.5, 0.0, 0.0, 0.0, 3.5, 0.0, 0.0, 0.0]])
    np.testing.assert_allclose(compute_features("pose", mid), compute_features("pose", wall))
    a, b = compute_features("pose_walls", mid)[0], compute_features("pose_walls", wall)[0]
    np.testing.assert_allclose(a[:5], b[:5])
    assert b[NAMES.index("goal_wall_x")] == pytest.approx(WALL_X - 4.5) and a[NAMES.index("goal_wall_x")] == WALL_X - 1.0


@pytest.mark.parametrize("column", [2, 3, 6, 7])  # phi, v, phig, vg
def test_piecewise_affine_in_headings_and_speeds(column):
    """With positions fixed, each feature is affine in phi, v, phig, vg between a few kinks (App. C.3.4)."""
    rng = np.random.default_rng(3)
    base = np.column_stack([rng.uniform(-4, 4, 20), rng.uniform(-3, 3, 20), rng.uniform(-math.pi, math.pi, 20),
                            rng.uniform(0, 1, 20), rng.uniform(-4, 4, 20), rng.uniform(-3, 3, 20),
                            rng.uniform(-math.pi, math.pi, 20), rng.uniform(0, 1, 20)])
    grid = np.linspace(-math.pi, math.pi, 2001) if column in (2, 6) else np.linspace(0.0, 1.0, 2001)
    for row in base:
        params = np.repeat(row[None, :], len(grid), axis=0)
        params[:, column] = grid
        bends = np.abs(np.diff(compute_features("pose_walls", params), n=2, axis=0)) > 1e-9
        assert np.all(bends.sum(axis=0) <= 8), bends.sum(axis=0)
