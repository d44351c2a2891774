"""A small first correction before a long straight is driven at the speed its curvature allows, not crept along
at the arc speed (dribbleBall, approachBall and goToPose; sims.soccer.follow.Follower.gentle_at_speed): a start heading a
little off the path must not cost seconds."""

import dataclasses

import pytest
from tailor.sims.episode import ActionCall
from tailor.sims.soccer import approach, dribble, goto
from tailor.sims.soccer.scenarios import subgoal_episode
from tailor.sims.soccer.simulator import SoccerSim

# a 7 m dribble whose first arc is a small correction: the start heading 2.19 rad needs none, 2.0 rad one of 0.19
GENTLE = (1.25, -1.79, 2.19, 0.3, -1.94, 1.02, -1.2, 0.0)


def _dribble_time(heading: float) -> float:
    episode = subgoal_episode("dribbleBall", (*GENTLE[:2], heading, *GENTLE[3:]), 1)
    assert episode.succeeded
    return episode.duration


def test_a_small_start_heading_error_costs_the_dribble_no_seconds():
    assert abs(_dribble_time(2.0) - _dribble_time(2.19)) < 0.3


def test_without_gentle_corrections_at_speed_the_dribble_creeps(monkeypatch):
    monkeypatch.setattr(dribble, "DRIBBLE", dataclasses.replace(dribble.DRIBBLE, gentle_at_speed=False))
    assert _dribble_time(2.0) - _dribble_time(2.19) > 2.0  # it crept at 0.24 m/s for seconds (measured 3.3 s)


def _time(action: str, heading: float) -> float:
    """From rest 4.3 m from the goal (the ball's position), arriving in the direction of the straight line
    (2.42 rad): approachBall with the ball there, goToPose without it."""
    sim = SoccerSim(1)
    sim.place((1.25, -1.79, heading, 0.0), ball=(-1.94, 1.02) if action == "approachBall" else None)
    episode = sim.run(ActionCall(action, (-1.94, 1.02, 2.42, 0.1)))
    assert episode.succeeded
    return episode.duration


@pytest.mark.parametrize("action", ["approachBall", "goToPose"])
def test_a_small_start_heading_error_costs_the_approach_no_seconds(action):
    assert max(_time(action, h) for h in (2.12, 2.22, 2.52)) - _time(action, 2.42) < 0.1


def test_without_gentle_corrections_at_speed_the_approach_creeps(monkeypatch):
    monkeypatch.setattr(approach, "APPROACH", dataclasses.replace(approach.APPROACH, gentle_at_speed=False))
    assert _time("approachBall", 2.12) - _time("approachBall", 2.42) > 0.6  # measured 0.95 s (6.35 against 5.4 s)


def test_without_gentle_corrections_at_speed_go_to_pose_creeps(monkeypatch):
    monkeypatch.setattr(goto, "GOTO", dataclasses.replace(goto.GOTO, gentle_at_speed=False))
    assert _time("goToPose", 2.12) - _time("goToPose", 2.42) > 0.6  # measured 0.85 s (6.15 against 5.3 s)
