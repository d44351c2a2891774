"""The kitchen's way-points (Sec. 5.5, Fig. 5.9): navigate passing its goal at a free speed v, a navigate that
starts at a speed, the observed speed, the "route" space's speed features, and the navigate legs of the
experience, against physics computed by hand (a 1-D move under the base's limits V_MAX, A_MAX; the controller
brakes at BRAKE * A_MAX)."""

from __future__ import annotations

import math
from collections import Counter

import numpy as np
import pytest
from tailor.errors import SimError
from tailor.sims.episode import ActionCall
from tailor.sims.kinematics import transfer_time
from tailor.sims.kitchen import world as W
from tailor.sims.kitchen.features import ROUTE
from tailor.sims.kitchen.scenarios import STOP_SHARE, TOP_CRUISE_SHARE, run_goto, sample_goto, subgoal_episode
from tailor.sims.kitchen.simulator import BRAKE, DT, DT_CONTROL, PASS_HEADING_TOL, PASS_TOL, KitchenSim, Noise

QUIET = Noise.off()
V, A = W.V_MAX, W.A_MAX
X0, Y0, D = 1.0, 1.0, 3.0  # straight runs in room A, east along y = Y0, clear of the island and the walls


def _sim(pose, speed: float = 0.0, noise: Noise = QUIET, seed: int = 0) -> KitchenSim:
    sim = KitchenSim(seed, noise)
    sim.place(pose, {}, {}, speed=speed)
    return sim


def _straight(v: float):
    """From rest at (X0, Y0) facing east, navigate to the spot D ahead facing east, passing it at v."""
    sim = _sim((X0, Y0, 0.0))
    return sim, sim.run(ActionCall("navigate", (X0 + D, Y0, 0.0, 0.0, 0.0, 0.0, v, 0.6)))


def _passing_time_bounds(d: float, v: float) -> tuple[float, float]:
    """The duration of passing a point d straight ahead at v, from rest. Below: no admissible profile (|a| <=
    A_MAX, v <= V_MAX) covers d faster ending at the speed the base crosses with (at most v + A_MAX *
    DT_CONTROL, see test_passing_a_waypoint_straight_ahead; transfer_time falls with the end speed), less a
    physics step for the discrete integration. Above: speeding up at A_MAX and braking at BRAKE * A_MAX is no
    slower than the time-optimal move at BRAKE * A_MAX throughout; the controller's braking command is up to
    a control period stale (it brakes later: faster), and the crossing is seen at the next control tick (up
    to DT_CONTROL late)."""
    low = float(transfer_time(d, 0.0, min(V, v + A * DT_CONTROL), V, A)) - DT
    high = float(transfer_time(d, 0.0, v, V, BRAKE * A)) + DT_CONTROL
    return low, high


def _mixed_profile(d: float, v: float) -> float:
    """By hand: from rest to V_MAX at A_MAX, cruise, brake to v at BRAKE * A_MAX (d long enough to cruise)."""
    up, down = V * V / (2 * A), (V * V - v * v) / (2 * BRAKE * A)
    assert d >= up + down
    return V / A + (d - up - down) / V + (V - v) / (BRAKE * A)


# --- passing a way-point ------------------------------------------------------------------------------------
@pytest.mark.parametrize("v", [0.2, 0.4, W.V_MAX])
def test_passing_a_waypoint_straight_ahead(v):
    sim, episode = _straight(v)
    assert episode.outcome == "success"
    x, y, phi, speed = sim.true_state()[:4]
    assert y == pytest.approx(Y0, abs=1e-9) and phi == pytest.approx(0.0, abs=1e-9)  # a straight line
    # the speed: the braking command sqrt(v^2 + 2 BRAKE A_MAX dist) never falls below v (and the base comes
    # down to it from above), and is stale by at most a control period's braking when the crossing is seen
    assert v - 1e-9 <= speed <= v + A * DT_CONTROL
    assert sim.v == speed  # it ends driving: the next action starts at that speed
    # it ends at the first control tick past the goal's line: within one control period's travel of it
    assert X0 + D <= x <= X0 + D + (speed + A * DT_CONTROL) * DT_CONTROL
    low, high = _passing_time_bounds(D, v)
    assert low <= episode.duration <= high
    assert episode.duration == pytest.approx(_mixed_profile(D, v), abs=DT_CONTROL)
    # faster than stopping at the same spot
    _, stop = _straight(0.0)
    assert stop.outcome == "success" and episode.duration < stop.duration


def test_the_passing_checks_fail_where_the_goal_speed_is_ignored():
    """The switch-off check: the same spot with the goal speed forced to 0 (a controller that ignores v) does
    not pass test_passing_a_waypoint_straight_ahead's duration and speed checks for v = 0.4."""
    v = 0.4
    sim, stop = _straight(0.0)
    low, high = _passing_time_bounds(D, v)
    assert not low <= stop.duration <= high
    assert stop.duration != pytest.approx(_mixed_profile(D, v), abs=DT_CONTROL)
    assert not v - 1e-9 <= sim.v <= v + A * DT_CONTROL


def test_the_next_navigate_starts_at_the_speed_the_waypoint_was_passed_at():
    sim = _sim((X0, Y0, 0.0))
    first = sim.run(ActionCall("navigate", (X0 + 1.5, Y0, 0.0, 0.0, 0.0, 0.0, 0.4, 0.6)))
    assert first.outcome == "success"
    end_speed, (x, y, phi) = sim.v, sim.true_state()[:3]
    assert end_speed >= 0.4 and sim.observe("navigate")[6] == end_speed
    on = (X0 + D, Y0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.6)
    second = sim.run(ActionCall("navigate", on))
    assert second.outcome == "success"
    assert second.params[6] == end_speed and second.state[0, 6] == end_speed
    # the rest of the way from where it crossed, shorter at that speed than from rest
    rest = _sim((x, y, phi)).run(ActionCall("navigate", on))
    assert rest.outcome == "success" and second.duration < rest.duration


def test_a_waypoint_crossed_at_a_sharp_angle_is_off_course():
    # a spot 0.6 m in front of the south wall, facing away from it: its lead-in point lies in the wall, so the
    # route goes straight to it; from the west along its line the base crosses it heading east, not north
    goal = (2.0, 0.6, math.pi / 2, 0.0, 0.0, 0.0, 0.4, 0.6)
    sim = _sim((1.0, 0.5, 0.0))
    assert sim.routes.inside((2.0, 0.0))
    episode = sim.run(ActionCall("navigate", goal))
    assert episode.outcome == "off_course"
    assert sim.true_state()[1] >= goal[1]  # it ended crossing the goal's line
    assert episode.measures["heading_error"] > PASS_HEADING_TOL or episode.measures["error"] > PASS_TOL
    # stopping there (v = 0) turns in place to the heading: a success
    assert _sim((1.0, 0.5, 0.0)).run(ActionCall("navigate", (*goal[:6], 0.0, 0.6))).outcome == "success"


# --- starting at a speed ------------------------------------------------------------------------------------
def test_a_start_with_speed_brakes_before_it_turns_back():
    start = (3.0, 1.5, 0.0)
    goal = (1.0, 1.5, math.pi, 0.0, 0.0, 0.0, 0.0, 0.6)  # 2 m behind the base, facing west
    moving = _sim(start, speed=0.4).run(ActionCall("navigate", goal))
    resting = _sim(start).run(ActionCall("navigate", goal))
    assert moving.outcome == resting.outcome == "success"
    assert moving.params[6] == 0.4 and resting.params[6] == 0.0  # the true speed at the start, logged
    assert moving.state[0, 6] == 0.4
    assert moving.duration > resting.duration  # it must brake first, and drive back the overshoot
    # the overshoot: the base cannot lose speed faster than A_MAX, so it travels v^2 / (2 A_MAX) before it
    # first stands; the goal lies behind (beyond TURN_IN_PLACE) so the controller commands 0 at once and
    # brakes at A_MAX exactly. Measured as the length of the logged path (noise off: the true one) up to the
    # first standstill; slack: the discrete integration, and the polygon through the 10 Hz samples of the
    # arc it turns along
    stop = int(np.argmax(moving.column("v") == 0.0))
    assert stop > 0
    xy = moving.state[: stop + 1, :2]
    travelled = float(np.sum(np.hypot(*np.diff(xy, axis=0).T)))
    assert travelled >= 0.4 ** 2 / (2 * A) - 0.005
    assert travelled == pytest.approx(0.4 ** 2 / (2 * A), abs=0.01)


def test_place_clips_the_speed_to_the_base_limit():
    sim = _sim((1.0, 1.0, 0.0), speed=2.0)
    assert sim.v == V and sim.observe("navigate")[6] == V


# --- observe ------------------------------------------------------------------------------------------------
def test_observe_navigate_has_the_speed_grip_and_put_the_spot():
    sim = _sim((1.0, 1.0, 0.3), speed=0.25)
    navigate, grip, put = (sim.observe(a) for a in ("navigate", "grip", "put"))
    assert len(navigate) == 7 and navigate[6] == 0.25
    assert len(grip) == len(put) == 6 and navigate[:6] == grip == put
    assert grip == pytest.approx((1.0, 1.0, 0.3, 0.0, 0.0, 0.0), abs=1e-12)
    assert sim.scene()["robot"] == pytest.approx((*grip, 0.25))  # the scene: the spot and the speed, as reset takes
    sim.reset(sim.scene())
    assert sim.v == pytest.approx(0.25)  # reset(scene()) places the base driving as it was


# --- the "route" space --------------------------------------------------------------------------------------
def _route_params(rng: np.random.Generator, n: int) -> np.ndarray:
    """n random (start, goal) pairs of spots with speeds, the start in room A, the goal in room A or B, both
    clear of the grown furniture (every route exists: the features are finite)."""
    def spots(x, y):
        return np.column_stack([rng.uniform(*x, n), rng.uniform(*y, n), rng.uniform(-np.pi, np.pi, n),
                                rng.uniform(-0.3, 0.3, n), rng.uniform(0.0, 0.5, n),
                                rng.uniform(-np.pi, np.pi, n), rng.uniform(0.0, V, n)])
    start = spots((1.0, 3.8), (1.2, 1.8))
    room_a, room_b = spots((1.0, 3.8), (1.2, 1.8)), spots((6.2, 9.0), (1.2, 4.8))
    goal = np.where(rng.uniform(size=(n, 1)) < 0.5, room_a, room_b)
    return np.column_stack([start, goal, rng.uniform(*W.CRUISE, n)])


def test_the_route_space_reads_both_speeds_and_the_cruise_speed():
    assert len(ROUTE.parameters) == 15 and ROUTE.parameters[6] == "v" and ROUTE.parameters[13] == "vg"
    assert ROUTE.parameters[14] == "cruiseg"
    assert ROUTE.names == ("length", "turn_start", "turn_goal", "turning",
                           "v_start", "v_goal", "transfer", "carry", "cruise", "slow", "drive", "corners")


def test_the_route_transfer_is_the_trapezoid_and_falls_with_the_goal_speed():
    # 3 m straight east in room A: transfer = d / V + ((V - v_start)^2 + (V - v_goal)^2) / (2 A V) by hand (a
    # ramp from v to V covers (V^2 - v^2) / 2A in (V - v) / A: (V - v)^2 / 2AV more than at cruise speed)
    v_goal = np.linspace(0.0, V, 7)
    params = np.array([[X0, Y0, 0.0, 0.0, 0.0, 0.0, 0.2, X0 + D, Y0, 0.0, 0.0, 0.0, 0.0, vg, V]
                       for vg in v_goal])
    f = ROUTE(params)
    assert f[:, 0] == pytest.approx(D) and np.all(f[:, 1:4] == pytest.approx(0.0, abs=1e-12))
    assert np.all(f[:, 4] == 0.2) and np.all(f[:, 5] == v_goal)
    hand = D / V + ((V - 0.2) ** 2 + (V - v_goal) ** 2) / (2 * A * V)
    assert f[:, 6] == pytest.approx(hand, abs=1e-9)
    assert np.all(np.diff(f[:, 6]) < 0)
    assert np.all(f[:, 7] == 0.0)  # no turn at the start: nothing carried
    assert np.all(f[:, 8] == V) and np.all(f[:, 9] == 0.0)  # at the top cruise speed the governor adds nothing
    assert f[:, 10] == pytest.approx(D * V * V) and np.all(f[:, 11] == 0.0)


def test_the_route_cruise_features_by_hand():
    # 3 m straight: the cruise columns are c, D (1/c - 1/V), D c^2 and c^2 times the turning (0 here); a cruise
    # speed beyond V_MAX counts as V_MAX
    cruise = np.array([0.3, 0.45, V, 0.9])
    params = np.array([[X0, Y0, 0.0, 0.0, 0.0, 0.0, 0.0, X0 + D, Y0, 0.0, 0.0, 0.0, 0.0, 0.0, c] for c in cruise])
    f = ROUTE(params)
    c = np.minimum(cruise, V)
    assert np.all(f[:, 8] == c)
    assert f[:, 9] == pytest.approx(D * (1.0 / c - 1.0 / V), abs=1e-12)
    assert f[:, 10] == pytest.approx(D * c * c) and np.all(f[:, 11] == 0.0)

def test_the_route_carry_is_the_start_speed_times_the_start_turn():
    # facing away from the goal: the start turn is pi
    params = np.array([[X0 + D, Y0, 0.0, 0.0, 0.0, 0.0, 0.4, X0, Y0, math.pi, 0.0, 0.0, 0.0, 0.0, V]])
    f = ROUTE(params)[0]
    assert f[1] == pytest.approx(math.pi) and f[7] == pytest.approx(0.4 * math.pi)


def test_the_route_bounds_enclose_the_features_over_boxes_wide_in_the_speeds():
    rng = np.random.default_rng(4)
    n, samples = 40, 200
    centre = _route_params(rng, n)
    half = np.append(np.tile([0.02, 0.02, 0.02, 0.01, 0.01, 0.02, 0.0], 2), 0.0) * rng.uniform(size=(n, 15))
    low, high = centre - half, centre + half
    for k, speeds in ((6, (0.0, V)), (13, (0.0, V)), (14, W.CRUISE)):  # the speeds anywhere, some a single value
        a, b = np.sort(rng.uniform(*speeds, (2, n)), axis=0)
        point = rng.uniform(size=n) < 0.2
        low[:, k], high[:, k] = a, np.where(point, a, b)
    f_lo, f_hi = ROUTE.bounds(low, high)
    assert f_lo.shape == f_hi.shape == (n, 12) and np.all(f_lo <= f_hi)
    u = rng.uniform(size=(n, samples, 15))
    u[:, :8, [6, 13, 14]] = [[i >> 2 & 1, i >> 1 & 1, i & 1] for i in range(8)]  # the speeds' corners
    points = low[:, None] + (high - low)[:, None] * u
    F = ROUTE(points.reshape(-1, 15)).reshape(n, samples, 12)
    assert np.all(np.isfinite(F))
    assert np.all((f_lo[:, None] <= F) & (F <= f_hi[:, None]))
    # the speed columns' bounds are the boxes' speeds; at a point every new column is the feature itself
    assert np.all(f_lo[:, 4] == low[:, 6]) and np.all(f_hi[:, 4] == high[:, 6])
    assert np.all(f_lo[:, 5] == low[:, 13]) and np.all(f_hi[:, 5] == high[:, 13])
    p_lo, p_hi = ROUTE.bounds(centre, centre)
    values = ROUTE(centre)
    np.testing.assert_allclose(p_lo[:, 4:], values[:, 4:], atol=1e-9)
    np.testing.assert_allclose(p_hi[:, 4:], values[:, 4:], atol=1e-9)


def test_the_route_features_do_not_see_the_frame_a_pose_is_written_in():
    rng = np.random.default_rng(5)
    params = _route_params(rng, 200)
    moved = ROUTE.transform(params, rng)
    assert np.all(np.abs(moved[:, [0, 1, 2, 7, 8, 9]] - params[:, [0, 1, 2, 7, 8, 9]]) > 0)  # new frames
    assert np.all(moved[:, [6, 13, 14]] == params[:, [6, 13, 14]])  # the speeds stay
    np.testing.assert_allclose(ROUTE(moved), ROUTE(params), atol=1e-9)


# --- the experience's navigate legs -------------------------------------------------------------------------
def _spot_kind(spot: tuple[float, ...], layout: dict) -> str:
    if spot[:3] == tuple(layout["start"]):
        return "start"
    if spot[:3] == W.door_frame(True):
        return "east"
    if spot[:3] == W.door_frame(False):
        return "west"
    if math.isclose(spot[2], W.TABLE1[2]):
        return "pickup"
    assert math.isclose(spot[2], W.TABLE2[2])
    return "dropoff"


def test_the_experience_covers_every_leg_and_passes_the_door_at_a_free_speed():
    legs, door_speeds, cruises = Counter(), [], []
    for seed in range(400):
        layout, start, goal = sample_goto(np.random.default_rng((seed, 1)))
        assert len(start) == 7 and len(goal) == 8 and W.CRUISE[0] <= goal[7] <= W.CRUISE[1]
        cruises.append(goal[7])
        kinds = _spot_kind(start, layout), _spot_kind(goal, layout)
        legs[kinds] += 1
        for spot, kind in zip((start, goal), kinds):
            if kind in ("east", "west"):
                assert W.DOOR_ALONG[0] <= spot[3] <= W.DOOR_ALONG[1] and spot[4] == 0.0
                assert W.DOOR_HEADING[0] <= spot[5] <= W.DOOR_HEADING[1]
                assert W.PASS_SPEED[0] <= spot[6] <= W.PASS_SPEED[1]
                door_speeds.append(spot[6])
            else:
                assert spot[6] == 0.0  # the start and the tables: at rest
        if kinds[0] == "start":
            assert start[3:6] == (0.0, 0.0, 0.0)
    assert set(legs) == {("start", "pickup"), ("pickup", "east"), ("east", "dropoff"), ("dropoff", "west"),
                         ("west", "pickup")}
    assert min(legs.values()) >= 50  # about a fifth each
    stops = np.mean(np.array(door_speeds) == 0.0)
    assert stops == pytest.approx(STOP_SHARE, abs=0.07)  # ~320 door spots: 3 standard deviations
    assert np.ptp([s for s in door_speeds if s > 0]) > 0.5 * V
    top = np.mean(np.array(cruises) == W.CRUISE[1])  # 400 legs: 3 standard deviations
    assert top == pytest.approx(TOP_CRUISE_SHARE, abs=0.07) and np.ptp(cruises) > 0.8 * np.ptp(W.CRUISE)


def test_run_goto_starts_a_leg_from_the_door_at_its_speed_written_in_the_doors_frame():
    legs = [(seed, *sample_goto(np.random.default_rng((seed, 1)))) for seed in range(40)]
    from_door = [(seed, start, goal) for seed, layout, start, goal in legs
                 if _spot_kind(start, layout) in ("east", "west")]
    assert len(from_door) >= 5
    for seed, start, goal in from_door[:5]:
        episode = run_goto(seed, QUIET)
        assert len(episode.params) == 15
        assert tuple(episode.params[:3]) == start[:3]  # the spot's frame, its offsets solved
        assert episode.params[3:6] == pytest.approx(start[3:6], abs=1e-9)
        assert episode.params[6] == start[6] and tuple(episode.params[7:]) == goal


def test_a_navigate_subgoal_episode_starts_at_its_speed():
    frame = W.door_frame(True)
    goal = (*W.serving_frame(W.TABLE2, 9.6, 3.0), 0.0, 0.6, 0.0, 0.0, 0.4)
    params = np.array([*frame, 0.1, 0.0, 0.2, 0.5, *goal])
    episode = subgoal_episode("navigate", params, seed=3)
    assert episode.params[6] == 0.5 and tuple(episode.params[7:]) == goal
    assert tuple(episode.params[:3]) == frame
    assert episode.params[3:6] == pytest.approx((0.1, 0.0, 0.2), abs=0.05)  # up to the believed pose's noise
    assert episode.outcome == "success"


@pytest.mark.parametrize(("start", "goal"), [
    ((7.0, 3.0, 0.0), (7.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0.4, 0.6)),  # standing on the way-point, facing along it
    ((2.0, 2.0, -math.pi / 2), (2.0, 0.6, math.pi / 2, 0.0, 0.0, 0.0, 0.4, 0.6)),  # beyond its line, lead-in in a wall
])
def test_a_way_point_reached_from_on_or_beyond_its_line_ends_without_timing_out(start, goal):
    """Passing mode ends on the route's last leg past the goal's line even where the base never was behind it."""
    sim = KitchenSim(0, Noise.off())
    sim.place(start, {}, {})
    episode = sim.run(ActionCall("navigate", goal))
    assert episode.outcome in ("success", "off_course") and episode.duration < 20.0


def test_a_cruise_speed_of_zero_is_refused():
    sim = KitchenSim(0, Noise.off())
    sim.place((1.0, 1.0, 0.0), {}, {})
    with pytest.raises(SimError, match=r"navigate: the cruise speed must be > 0 m/s, got 0"):
        sim.run(ActionCall("navigate", (4.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)))


def test_a_negative_passing_speed_is_refused():
    sim = KitchenSim(0, Noise.off())
    sim.place((2.0, 2.0, 0.0), {}, {})
    with pytest.raises(SimError, match=r"navigate: the speed to pass the goal at must be >= 0 m/s, got -0.1"):
        sim.run(ActionCall("navigate", (4.0, 2.0, 0.0, 0.0, 0.0, 0.0, -0.1, 0.6)))
