"""dribbleBall brakes within a bound of the distance to go, not only of the sensed speed (issue 13, Sec. 2).

Braking "A_DRIBBLE_BRAKE below the believed speed" alone is a random walk under sensing and motor noise: under
noise seed 13 a run of same-signed draws kept the robot at 0.85-0.9 m/s (above V_DRIBBLE) until its last arc,
entered at 0.67 m/s instead of 0.24, and lost the ball ~22 s into this sequence. Since gentle corrections are
driven at speed the same sequence runs differently; without the bound it lost the ball under seeds 34, 57, 61
and 76 of the first 120, and since goToPose (the approach before it) drives them at speed too, under seed 77.
"""

import dataclasses

import pytest
from tailor.sims.episode import ActionCall
from tailor.sims.soccer import dribble, simulate_sequence
from tailor.sims.soccer.dribble import V_DRIBBLE

ROBOT = (-2.1295824060504405, 1.3774232900066283, -1.4488277848636213, 0.0)
BALL = (3.0924049545165273, 1.5148130286736388)
CALLS = [ActionCall("goToPose", (BALL[0], BALL[1], 0.06, 0.3)),
         ActionCall("dribbleBall", (-0.6472089344980092, -2.099958870673275, -0.8000434254250663, 0.0))]


def _run(seed: int):
    result = simulate_sequence(ROBOT, BALL, CALLS, seed)
    return result, result.trajectory


LOSES_WITHOUT_BOUND = 77


def test_seed_77_keeps_the_ball_and_the_top_speed():
    result, _ = _run(LOSES_WITHOUT_BOUND)
    assert [r.outcome for r in result.results] == ["success", "success"]
    v = result.columns.index("v")
    dribble_start = result.results[0].duration
    speeds = [row[v] for row in result.trajectory if row[0] > dribble_start + 1.0]
    assert max(speeds) < V_DRIBBLE * 1.1  # the motors' 3% noise on top of the bound, never a drift


def test_without_the_bound_seed_77_loses_the_ball(monkeypatch):
    monkeypatch.setattr(dribble, "DRIBBLE", dataclasses.replace(dribble.DRIBBLE, bounded_braking=False))
    result, _ = _run(LOSES_WITHOUT_BOUND)
    assert result.results[-1].outcome == "ball_lost"


@pytest.mark.parametrize("seed", [0, 1, 2, 3, 13])
def test_other_seeds_keep_the_ball(seed):
    result, _ = _run(seed)
    assert all(r.outcome == "success" for r in result.results)

