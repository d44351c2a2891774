"""goToPose (App. A.1): the lure point's geometry, its modes, and the cone in front of the goal where it
bumps a ball lying at the goal while it succeeds from behind (Sec. 4.2.2)."""

import math

import numpy as np
import pytest

from tailor.sims.episode import ActionCall
from tailor.sims.soccer import Noise, SoccerSim, simulate_sequence
from tailor.sims.soccer.control import axle_pose
from tailor.sims.soccer.goto import LURE_GAIN, LURE_MIN, V_CREEP, W_LURE, goToPose, lure_point
from tailor.sims.soccer.world import BALL_POINT_OFFSET

GOAL = (0.0, 0.0, 0.0, 0.0)  # ball point at the origin, heading +x, arriving at rest


def test_lure_point_lies_behind_the_goal_nearer_the_nearer_the_robot_comes_from_behind():
    goal = axle_pose(0.0, 0.0, 0.0)  # axle at (-0.315, 0)
    in_front = lure_point((2.0, 1.0, math.pi), goal)
    assert in_front == pytest.approx((goal[0] - LURE_MIN, 0.0))
    one_metre_behind = lure_point((goal[0] - 1.0, 0.7, 0.0), goal)
    assert one_metre_behind == pytest.approx((goal[0] - LURE_MIN - LURE_GAIN * 1.0, 0.0))
    turned = lure_point((0.4, -1.0, 0.0), (0.0, 0.0, math.pi / 2))  # the same for a goal heading +y
    assert turned == pytest.approx((0.0, -LURE_MIN - LURE_GAIN * 1.0))


def test_lure_turns_on_the_spot_toward_a_point_behind_it():
    # in front of the goal, facing away from it: the IP lies behind the robot
    v, w = goToPose(2.0, 0.3, 0.0, 0.0, *GOAL)
    assert v == V_CREEP and abs(w) == W_LURE
    # behind the goal on its line, aligned: straight in, no turn
    v, w = goToPose(-1.5, 0.0, 0.0, 0.5, *GOAL)
    assert v > 0.5 and w == pytest.approx(0.0, abs=1e-9)


def _run(robot, ball, seed=0):
    result = simulate_sequence(robot, ball, [ActionCall("goToPose", GOAL)], seed)
    return result.results[0].outcome, result.trajectory


@pytest.mark.parametrize("heading", [math.pi, 0.5 * math.pi, 0.0, -2.5])
def test_from_in_front_it_crosses_the_goal_position_and_bumps_a_ball_there(heading):
    start = (2.5, 0.3, heading, 0.0)
    assert _run(start, (0.0, 0.0))[0] == "collision"
    outcome, trajectory = _run(start, None)  # without the ball it gets there, across the goal position
    assert outcome == "success"
    x, y = trajectory[:, 1], trajectory[:, 2]
    crossing = np.argmax(x < 0.0)
    assert crossing > 0 and abs(y[crossing]) < BALL_POINT_OFFSET


@pytest.mark.parametrize("start", [(-2.5, 0.3, 0.0, 0.0), (-2.0, -1.5, 2.0, 0.0), (-1.0, 2.0, -1.0, 0.3),
                                   (0.5, 2.5, math.pi, 0.0)])
def test_from_behind_or_beside_it_reaches_a_pose_at_the_ball_without_touching_it(start):
    assert _run(start, (0.0, 0.0))[0] == "success"


def test_the_cone_does_not_depend_on_the_noise():
    # (-1.0, 2.0, -1.0, 0.3) was here: since goToPose drives gentle corrections at speed it passes the cone's
    # edge, and under twice the default noise one seed of four bumps the ball; half a metre further out it does not
    starts = [(2.5, 0.3, math.pi, 0.0), (-2.0, -1.5, 2.0, 0.0), (3.0, -0.6, 1.0, 0.2), (-1.5, 2.0, -1.0, 0.3)]
    for start in starts:
        outcomes = set()
        for seed in range(4):
            sim = SoccerSim(seed, Noise(motor=0.06, position=0.02))  # twice the default noise
            sim.reset({"robot": start, "ball": (0.0, 0.0)})
            outcomes.add(sim.run(ActionCall("goToPose", GOAL)).outcome)
        assert len(outcomes) == 1, (start, outcomes)


def test_a_robot_beside_the_goal_is_not_stranded_by_the_line_follower():
    # found in a way-point chain: with a 30 cm wide line corridor at the goal, the robot stopped beside it (its
    # speed profile along the line had run out) and waited there until the timeout, on one noise seed of four
    robot, goal = (2.434, 1.018, 0.364, 0.6), (1.407, 1.588, 2.938, 0.0)
    for seed in range(4):
        result = simulate_sequence(robot, None, [ActionCall("goToPose", goal)], seed)
        assert result.results[0].outcome == "success" and result.results[0].duration < 15.0
