"""The kitchen simulator against physics computed by hand: drive times at the base's limits, the arm's ramps
plus the gripper's constant time, routes round the divider, failures as outcomes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tailor.errors import SimError
from tailor.sims import registry
from tailor.sims.episode import ActionCall
from tailor.sims.kitchen import world as W
from tailor.sims.kitchen.features import GRASP, ROUTE, ramp_time
from tailor.sims.kitchen.navigation import nominal_map
from tailor.sims.kitchen.simulator import BRAKE, KitchenSim, Noise

T1, T2 = W.TABLE1, W.TABLE2


QUIET = Noise.off()


def _sim(pose, tables=None, cups=None, holding=None, noise=QUIET, seed=0):
    sim = KitchenSim(seed, noise)
    sim.place(pose, tables or {}, cups or {}, holding)
    return sim


def _drive(distance: float, cruise: float = W.V_MAX) -> float:
    sim = _sim((1.0, 1.0, 0.0))
    episode = sim.run(ActionCall("navigate", (1.0 + distance, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, cruise)))
    assert episode.outcome == "success"
    assert sim.true_state()[0] == pytest.approx(1.0 + distance, abs=0.08)
    return episode.duration


def test_straight_drive_takes_the_trapezoid_time():
    # accelerate at A_MAX to V_MAX, cruise, brake at BRAKE * A_MAX: t = d / V + V / (2 A) + V / (2 BRAKE A)
    v, a = W.V_MAX, W.A_MAX
    for d in (2.0, 3.0):
        expected = d / v + v / (2 * a) + v / (2 * BRAKE * a)
        assert _drive(d) == pytest.approx(expected, abs=0.2)
    # a longer straight costs exactly its extra length at cruise speed
    assert _drive(3.0) - _drive(2.0) == pytest.approx(1.0 / v, abs=0.06)


@pytest.mark.parametrize("cruise", [0.3, 0.45])
def test_a_governed_drive_takes_the_trapezoid_time_at_its_cruise_speed(cruise):
    # the governor holds the base at the cruise speed c: t = d / c + c / (2 A) + c / (2 BRAKE A) (braking starts
    # where the braking profile meets c, so it ramps down from c as from V_MAX above)
    a = W.A_MAX
    for d in (2.0, 3.0):
        assert _drive(d, cruise) == pytest.approx(d / cruise + cruise / (2 * a) + cruise / (2 * BRAKE * a), abs=0.2)
    assert _drive(3.0, cruise) - _drive(2.0, cruise) == pytest.approx(1.0 / cruise, abs=0.06)


def test_the_governor_holds_the_speed_below_the_noisy_command():
    # with the motors' noise on, the base never drives faster than its cruise speed, and for most of the way it
    # drives exactly at it: the noisy command lies above the governor's limit
    sim = KitchenSim(3, Noise())
    sim.place((1.0, 1.0, 0.0), {}, {})
    speeds = []
    command = sim.command

    def recorded(v_cmd, w_cmd, e=(0.0, 0.0), cruise=math.inf):
        command(v_cmd, w_cmd, e, cruise)
        speeds.append(sim.v_cmd)
    sim.command = recorded
    assert sim.run(ActionCall("navigate", (4.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5))).outcome == "success"
    assert max(speeds) <= 0.5 and np.mean(np.array(speeds) == 0.5) > 0.5
    assert sim.v == pytest.approx(0.0, abs=0.05)


@pytest.mark.parametrize("dist", [0.4, 0.6, 0.8])
def test_grip_is_two_arm_ramps_plus_the_gripper_time(dist):
    cup = W.table_point(T1, 0.0, 0.2)  # straight ahead: only the extension moves
    frame = W.serving_frame(T1, *cup)
    sim = _sim(W.spot_pose(*frame, 0.0, dist, 0.0), {"table1": T1}, {"cup1": cup})
    episode = sim.run(ActionCall("grip", cup))
    reach = dist + 0.2 - W.SHOULDER_OFFSET - W.EXT_REST
    assert episode.outcome == "success"
    assert episode.duration == pytest.approx(2 * ramp_time(reach, W.EXT_SPEED, W.EXT_ACCELERATION)
                                             + W.GRIPPER_TIME, abs=0.15)
    assert sim.held == "cup1"
    assert sim.cups["cup1"].position == pytest.approx(sim.gripper())


def test_pan_sets_the_time_when_it_is_the_slower_joint():
    cup = W.table_point(T1, 0.0, 0.2)
    frame = W.serving_frame(T1, *cup)
    sim = _sim(W.spot_pose(*frame, 0.0, 0.4, 1.0), {"table1": T1}, {"cup1": cup})  # base turned 1 rad away
    params = np.array([[*frame, 0.0, 0.4, 1.0, *cup]])
    pan, extension, ramp = GRASP(params)[0]
    assert ramp == pytest.approx(ramp_time(pan, W.PAN_SPEED, W.PAN_ACCELERATION))
    assert ramp > ramp_time(extension, W.EXT_SPEED, W.EXT_ACCELERATION) + 0.3
    assert sim.run(ActionCall("grip", cup)).duration == pytest.approx(2 * ramp + W.GRIPPER_TIME, abs=0.15)


def test_put_carries_the_cup_to_the_put_location():
    put = W.table_point(T2, 0.3, 0.2)
    sim = _sim(W.spot_pose(*W.serving_frame(T2, *put), 0.0, 0.5, 0.0), {"table2": T2}, {"cup1": (0.0, 0.0)},
               holding="cup1")
    assert sim.run(ActionCall("put", put)).outcome == "success"
    assert sim.held is None
    assert tuple(sim.cups["cup1"].position) == pytest.approx(put, abs=0.01)


def test_collision_with_a_table_is_an_outcome():
    sim = _sim((2.5, 4.0, math.pi / 2), {"table1": T1})
    episode = sim.run(ActionCall("navigate", (2.5, 5.1, math.pi / 2, 0.0, 0.0, 0.0, 0.0, 0.6)))  # a goal inside the table
    assert episode.outcome == "collision"
    edge = T1[1] - W.TABLE_DEPTH / 2
    assert sim.true_state()[1] == pytest.approx(edge - W.BASE_RADIUS, abs=0.04)  # stopped at first touch


def test_failures_of_the_arm_are_outcomes():
    cup = W.table_point(T1, 0.0, 0.2)
    frame = W.serving_frame(T1, *cup)
    far = _sim(W.spot_pose(*frame, 0.0, 1.2, 0.0), {"table1": T1}, {"cup1": cup})
    assert far.run(ActionCall("grip", cup)).outcome == "out_of_reach"  # 1.2 m from the edge: not 40-80 cm
    empty = _sim(W.spot_pose(*frame, 0.0, 0.5, 0.0), {"table1": T1}, {"cup1": cup})
    assert empty.run(ActionCall("grip", (cup[0] + 0.3, cup[1]))).outcome == "missed"  # no cup there
    assert empty.run(ActionCall("put", cup)).outcome == "not_holding"
    off = W.table_point(T1, 0.0, -0.3)  # 30 cm in front of the table: on the floor
    holding = _sim(W.spot_pose(*frame, 0.0, 0.8, 0.0), {"table1": T1}, {"cup1": cup}, holding="cup1")
    assert holding.run(ActionCall("put", off)).outcome in ("cup_dropped", "out_of_reach")
    holding = _sim(W.spot_pose(*frame, 0.0, 0.8, 0.0), {"table1": T1, "table2": T2}, {"cup1": cup}, holding="cup1")
    assert holding._base_at_table((T2[0], T2[1])) is False


def test_route_goes_through_the_door_round_the_jamb():
    path = nominal_map().path((2.0, 1.0), (8.5, 3.0))
    grow = W.BASE_RADIUS + W.CLEARANCE + 0.02  # the graph's nodes: jamb corners grown by radius and clearance
    corner = (W.DIVIDER_X - W.WALL_THICKNESS / 2 - grow, W.DOOR_Y - W.DOOR_WIDTH / 2 + grow)
    assert len(path) == 3
    assert path[1] == pytest.approx(corner)
    features = ROUTE(np.array([[2.0, 1.0, 0.0, 0, 0, 0, 0, 8.5, 3.0, 0.0, 0, 0, 0, 0, 0.6]]))[0]
    expected = math.dist((2.0, 1.0), corner) + math.dist(corner, (8.5, 3.0))
    assert features[0] == pytest.approx(expected)
    assert features[1] == pytest.approx(math.atan2(corner[1] - 1.0, corner[0] - 2.0))  # turn to the first leg


def test_go_to_pose_reaches_the_other_room_without_touching_anything():
    sim = _sim((2.0, 1.0, math.pi), {"table1": T1, "table2": T2}, noise=Noise())
    result = sim.run_sequence([ActionCall("navigate", (*W.serving_frame(T2, 9.5, 2.5), 0.2, 0.6, 0.3, 0.0, 0.6))])
    assert result.succeeded
    x, y = result.column("x"), result.column("y")
    gap = min(min(b.distance(px, py) for b in [*W.walls(), W.island()]) for px, py in zip(x, y))
    assert gap >= W.BASE_RADIUS
    assert np.any(x > W.DIVIDER_X) and np.all(np.abs(y[np.abs(x - W.DIVIDER_X) < 0.1] - W.DOOR_Y) < W.DOOR_WIDTH / 2)


def test_noise_is_on_by_default_and_seeded():
    entry = registry.get("kitchen")
    a, b, c = (entry.scenarios["navigate"].run(s) for s in (3, 3, 4))
    assert a.duration == b.duration and np.array_equal(a.state, b.state)
    sim = entry.create(5)
    assert sim.noise == Noise()
    noisy, exact = entry.scenarios["grip"].run(7), entry.scenarios["grip"].run(7, Noise.off())
    assert W.spot_pose(*noisy.params[:6])[0] != W.spot_pose(*exact.params[:6])[0]  # the believed start pose
    assert c.duration != a.duration


def test_reset_takes_the_binding_scene_and_rejects_bad_input():
    sim = registry.get("kitchen").create(0)
    sim.reset({"robot": (1.0, 1.0, 0.0, 0.0, 0.0, 0.0), "table table1": T1, "cup cup1": (2.5, 5.2)})
    assert set(sim.tables) == {"table1"} and set(sim.cups) == {"cup1"}
    with pytest.raises(SimError, match="unknown kitchen scene object"):
        sim.reset({"robot": (1.0, 1.0, 0.0, 0.0, 0.0, 0.0), "ball": (1.0, 2.0)})
    with pytest.raises(SimError, match="goal must be 8"):
        sim.run(ActionCall("navigate", (1.0, 2.0)))
