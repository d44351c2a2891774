"""Soccer simulator: physics against hand computation, action outcomes, noise, determinism, logging."""

import math

import numpy as np
import pytest

from tailor.sims.episode import ActionCall
from tailor.errors import SimError
from tailor.sims.experience import episode_seeds, run_episode
from tailor.sims.soccer import SIMULATOR, Noise, SoccerSim, simulate_sequence
from tailor.sims.soccer import world as W
from tailor.sims.soccer.scenarios import run_chain
from tailor.sims.soccer.simulator import (CONTROL_HZ, DT, LOG_HZ, STATE_COLUMNS, STEPS_PER_CONTROL,
                                         TRAJECTORY_COLUMNS)


def test_rolling_ball_stops_after_v0_squared_over_two_mu_g():
    sim = SoccerSim(0, Noise.off())
    sim.place((-3.0, -2.0, 0.0, 0.0), (0.0, 0.0))
    v0 = 1.2
    sim.ball.velocity = (v0, 0.0)
    for _ in range(2000):
        sim.space.step(DT)
    expected = v0 ** 2 / (2 * 0.05 * 9.81)  # 1.468 m
    assert sim.ball.velocity.length == 0.0
    assert sim.ball.position.x == pytest.approx(expected, rel=0.02)


def test_robot_never_exceeds_its_limits_under_random_commands():
    rng = np.random.default_rng(3)
    sim = SoccerSim(1, Noise(motor=0.5))  # large motor noise pushes commands beyond the limits
    sim.place((0.0, 0.0, 0.0, 0.0))
    for _ in range(300):
        sim.command(rng.uniform(-3, 3), rng.uniform(-10, 10))
        for _ in range(STEPS_PER_CONTROL):
            v0, w0 = sim.v, sim.w
            sim.step()
            assert abs(sim.v) <= W.V_MAX + 1e-12 and abs(sim.w) <= W.W_MAX + 1e-12
            assert abs(sim.v - v0) <= W.A_MAX * DT + 1e-12
            assert abs(sim.w - w0) <= W.ALPHA_MAX * DT + 1e-12


def test_go_to_pose_reaches_random_reachable_poses():
    outcomes = [run_episode("soccer", "goToPose", s).outcome for s in episode_seeds(11, 20)]
    assert outcomes == ["success"] * 20


def test_episode_ends_within_tolerance_and_logs_at_10_hz():
    sim = SoccerSim(4)
    sim.place((0.0, 0.0, 0.0, 0.0))
    ep = sim.run(ActionCall("goToPose", (2.0, 1.0, math.pi / 2, 0.3)))
    assert ep.outcome == "success"
    np.testing.assert_allclose(ep.t, np.arange(len(ep.t)) / LOG_HZ)
    assert ep.duration == pytest.approx(round(ep.duration * CONTROL_HZ) / CONTROL_HZ)
    assert ep.t[-1] <= ep.duration < ep.t[-1] + 1.0 / LOG_HZ
    x, y, phi, v, *_ = sim.true_state()
    assert math.hypot(x - 2.0, y - 1.0) <= 0.1 and abs(W.wrap(phi - math.pi / 2)) <= 0.2 and abs(v - 0.3) <= 0.15


def test_same_seed_same_episode_other_seed_slightly_different_duration():
    call = ActionCall("goToPose", (2.5, 1.0, 1.0, 0.2))
    durations = []
    for seed in range(12):
        sim = SoccerSim(seed)
        sim.place((-1.0, -1.0, 0.0, 0.0))
        durations.append(sim.run(call).duration)
    again = SoccerSim(0)
    again.reset({"robot": (-1.0, -1.0, 0.0, 0.0)})  # the protocol's reset gives the same episode
    ep0 = again.run(call)
    assert ep0.duration == durations[0]
    d = np.array(durations)
    assert d.std() > 0.0 and d.std() < 0.05 * d.mean()


def test_dribbling_straight_keeps_the_ball():
    sim = SoccerSim(5)
    sim.place((0.0, 0.0, 0.0, 0.0), (0.0, 0.0))
    ep = sim.run(ActionCall("dribbleBall", (2.0, 0.0, 0.0, 0.1)))
    assert ep.outcome == "success"


@pytest.mark.parametrize("noise", [Noise.off(), Noise()])
def test_dribble_ends_lost_when_robot_and_ball_rest_apart_at_the_goal(noise):
    # standing at the goal (vg 0) with the ball at rest 8 cm ahead (out of the guide: > 6 cm), neither moves
    # again: the action ends at once as "ball_lost" (it used to wait for the 30 s timeout: seed 1000's
    # situation 218 stopped so after braking at its goal)
    phi = 0.5
    ahead = (0.08 * math.cos(phi), 0.08 * math.sin(phi))
    sim = SoccerSim(3, noise)
    sim.place((0.0, 0.0, phi, 0.0), ahead)
    assert (sim.run(ActionCall("dribbleBall", (0.0, 0.0, phi, 0.0))).outcome, sim.time) == ("ball_lost", 0.0)


def test_dribble_waits_while_the_ball_is_held_rolling_or_the_goal_is_reached_moving():
    phi = 0.5
    sim = SoccerSim(3, Noise.off())
    sim.place((0.0, 0.0, phi, 0.0), (0.03 * math.cos(phi), 0.03 * math.sin(phi)))  # in the guide
    assert sim.run(ActionCall("dribbleBall", (0.0, 0.0, phi, 0.0))).outcome == "success"
    sim.place((0.0, 0.0, phi, 0.0), (0.08 * math.cos(phi), 0.08 * math.sin(phi)))
    sim.ball.velocity = (-0.2 * math.cos(phi), -0.2 * math.sin(phi))  # rolling back into the guide
    assert sim.run(ActionCall("dribbleBall", (0.0, 0.0, phi, 0.0))).outcome == "success"
    sim.place((0.0, 0.0, phi, 0.1), (0.08 * math.cos(phi), 0.08 * math.sin(phi)))
    ep = sim.run(ActionCall("dribbleBall", (0.0, 0.0, phi, 0.1)))  # to pass the goal at 0.1 m/s: it drives on
    assert ep.outcome == "success" and sim.time > 0.0  # and takes the ball into the guide


def _dribble_then(sim, v_cmd, w_cmd, seconds):
    for _ in range(int(2.0 * CONTROL_HZ)):  # accelerate straight to 0.8 m/s with the ball
        sim.command(0.8, 0.0)
        for _ in range(STEPS_PER_CONTROL):
            sim.step()
    for _ in range(int(seconds * CONTROL_HZ)):
        sim.command(v_cmd, w_cmd)
        for _ in range(STEPS_PER_CONTROL):
            sim.step()
    x, y, _, _, bx, by = sim.true_state()
    return math.hypot(bx - x, by - y)


def test_ball_kept_at_speed_lost_on_hard_brake_and_sharp_turn():
    sim = SoccerSim(6, Noise.off())
    sim.place((-3.0, 0.0, 0.0, 0.0), (-3.0, 0.0))
    assert _dribble_then(sim, 0.8, 0.0, 0.5) < 0.02  # held while pushed
    # braking at A_MAX = 1 m/s^2 > mu_r g = 0.49: the ball runs on (v^2/2)(1/0.49 - 1/1) = 0.33 m ahead
    sim.place((-3.0, 0.0, 0.0, 0.0), (-3.0, 0.0))
    assert _dribble_then(sim, 0.0, 0.0, 1.5) > 0.25
    sim.place((-3.0, 0.0, 0.0, 0.0), (-3.0, 0.0))
    assert _dribble_then(sim, 0.8, W.W_MAX, 0.7) > 0.15


def test_dribble_ball_succeeds_on_random_scenarios():
    outcomes = [run_episode("soccer", "dribbleBall", s).outcome for s in episode_seeds(31, 20)]
    assert outcomes.count("success") >= 19, outcomes


def test_approach_then_dribble_chain_succeeds_on_random_scenarios():
    results = [run_chain(s) for s in episode_seeds(41, 20)]
    assert sum(r.succeeded for r in results) >= 19, [[a.outcome for a in r.results] for r in results]
    assert all(len(r.results) == 2 for r in results if r.succeeded)


def _dribble_duration(phi, seed=0):
    sim = SoccerSim(seed)
    sim.place((-2.0, 0.0, phi, 0.0), (-2.0, 0.0))
    ep = sim.run(ActionCall("dribbleBall", (1.0, 0.0, 0.0, 0.0)))
    assert ep.outcome == "success"
    return ep.duration


def test_dribble_duration_grows_with_the_turn_needed_at_the_start():
    # facing the goal: 3 m straight; facing away: first a U-turn at W_DRIBBLE (pi / W_DRIBBLE = 5.2 s)
    from tailor.sims.soccer.dribble import W_DRIBBLE

    ahead, side, away = (_dribble_duration(phi) for phi in (0.0, math.pi / 2, math.pi))
    assert ahead < side < away
    assert away - ahead > math.pi / W_DRIBBLE * 0.7  # at least 70% of the U-turn's time at arc speed


def _turn_holds_ball(v, w, seconds=6.0):
    """Dribble straight up to speed v, then turn at rate w: whether the ball stays in the guide."""
    sim = SoccerSim(7, Noise.off())
    sim.place((-2.0, 0.0, 0.0, 0.0), (-2.0, 0.0))
    for v_cmd, w_cmd, duration in ((v, 0.0, 2.0), (v, w, seconds)):
        for _ in range(int(duration * CONTROL_HZ)):
            sim.command(v_cmd, w_cmd)
            for _ in range(STEPS_PER_CONTROL):
                sim.step()
            x, y, _, _, bx, by = sim.true_state()
            if math.hypot(bx - x, by - y) > 0.15:
                return False
    return True


def test_guide_holds_the_dribble_turn_rate_but_not_a_sharper_turn():
    from tailor.sims.soccer.dribble import R_DRIBBLE, W_DRIBBLE, W_HOLD

    assert _turn_holds_ball(W_DRIBBLE * R_DRIBBLE, W_DRIBBLE)  # the arcs dribbleBall drives
    assert _turn_holds_ball(0.3, W_HOLD)  # its largest rotational command, at a low speed
    assert not _turn_holds_ball(W_DRIBBLE * R_DRIBBLE, 2.0 * W_HOLD)  # twice as sharp: lost


def test_approach_ball_rarely_collides_and_plain_go_to_pose_runs_over_a_ball_in_its_way():
    seeds = episode_seeds(21, 20)
    approach = [run_episode("soccer", "approachBall", s).outcome for s in seeds]
    assert approach.count("collision") == 0 and approach.count("success") >= 19
    sim = SoccerSim(0)
    sim.place((-2.0, 0.0, 0.0, 0.0), ball=(0.0, 0.0))  # goToPose does not see the ball on its straight path
    assert sim.run(ActionCall("goToPose", (2.0, 0.0, 0.0, 0.0))).outcome == "collision"


def test_run_sequence_continues_without_stopping_and_logs_true_state():
    calls = [ActionCall("approachBall", (1.0, 0.0, 0.0, 0.2)), ActionCall("dribbleBall", (2.5, 0.0, 0.0, 0.1))]
    res = simulate_sequence((-1.0, 0.0, 0.0, 0.0), (1.0, 0.0), calls, seed=2)
    assert [r.outcome for r in res.results] == ["success", "success"]
    assert res.results[1].start == pytest.approx(res.results[0].duration)
    np.testing.assert_allclose(np.diff(res.trajectory[:, 0]), 1.0 / LOG_HZ, atol=1e-9)
    assert res.trajectory.shape[1] == 7 and res.trajectory[0, 1] == pytest.approx(-1.0)
    assert res.columns == TRAJECTORY_COLUMNS == ("t", *STATE_COLUMNS)
    np.testing.assert_array_equal(res.column("ball_x"), res.trajectory[:, 5])


def test_bad_input_raises_sim_error():
    sim = SoccerSim(0)
    sim.place((0.0, 0.0, 0.0, 0.0))
    with pytest.raises(SimError, match="unknown soccer action 'kick'"):
        sim.run(ActionCall("kick", (0.0, 0.0, 0.0, 0.0)))
    with pytest.raises(SimError, match="dribbleBall needs a ball"):
        sim.run(ActionCall("dribbleBall", (1.0, 0.0, 0.0, 0.0)))
    assert set(SIMULATOR.scenarios) == {"goToPose", "approachBall", "dribbleBall", "goToPoseAtBall",
                                        "goToPoseFarSide", "goToPosition"}
    assert {n: s.action for n, s in SIMULATOR.scenarios.items()} == {
        "goToPose": "goToPose", "approachBall": "approachBall", "dribbleBall": "dribbleBall",
        "goToPoseAtBall": "goToPose", "goToPoseFarSide": "goToPose", "goToPosition": "goToPosition"}


def test_reset_to_a_scene_is_place():
    """The protocol's reset(scene) places the robot and the (optional) ball as place(robot, ball) does."""
    call = ActionCall("approachBall", (1.0, 0.5, 0.0, 0.2))
    by_scene, by_place = SoccerSim(3), SoccerSim(3)
    by_scene.reset({"robot": (-1.0, 0.0, 0.3, 0.1), "ball": (1.0, 0.5)})
    by_place.place((-1.0, 0.0, 0.3, 0.1), (1.0, 0.5))
    assert by_scene.true_state() == by_place.true_state()
    a, b = by_scene.run(call), by_place.run(call)
    assert (a.outcome, a.duration) == (b.outcome, b.duration)
    np.testing.assert_array_equal(a.state, b.state)
    no_ball = SoccerSim(3)
    no_ball.reset({"robot": (0.0, 0.0, 0.0, 0.0)})
    assert not no_ball.has_ball
    for scene, message in (({"ball": (0.0, 0.0)}, "needs a robot"),
                           ({"robot": (0, 0, 0, 0), "cup": (1, 1)}, "not cup"),
                           ({"robot": (0.0, 0.0, 0.0)}, r"robot is \(x, y, phi, v\)"),
                           ({"robot": (0, 0, 0, 0), "ball": (1.0,)}, r"its ball \(x, y\)")):
        with pytest.raises(SimError, match=message):
            SoccerSim(0).reset(scene)


def test_episodes_log_named_state_columns():
    assert SoccerSim.state_columns == STATE_COLUMNS == ("x", "y", "phi", "v", "ball_x", "ball_y")
    ep = run_episode("soccer", "approachBall", 9)
    assert ep.action == "approachBall" and ep.columns == STATE_COLUMNS and ep.state.shape == (len(ep.t), 6)
    np.testing.assert_array_equal(ep.column("phi"), ep.state[:, 2])
    np.testing.assert_array_equal(ep.columns_of(("ball_x", "x")), ep.state[:, [4, 0]])
    assert np.all(np.isfinite(ep.state))  # approachBall has a ball at its goal
    np.testing.assert_allclose(ep.params[:2], ep.state[0, :2])  # params start with the first logged pose
    without_ball = run_episode("soccer", "goToPose", 9)
    assert np.all(np.isnan(without_ball.columns_of(("ball_x", "ball_y"))))
    with pytest.raises(KeyError, match="no state column 'z'"):
        ep.column("z")


@pytest.mark.parametrize("scene, call, message", [
    ({"robot": (40.0, 1.0, 0.0, 0.0)}, None, r"the robot's ball point \(40, 1\) lies outside the walls"),
    ({"robot": (0.0, 0.0, 0.0, 0.0), "ball": (0.0, -4.5)}, None, r"the ball \(0, -4.5\) lies outside the walls"),
    ({"robot": (0.0, 0.0, 0.0, 0.0)}, ("goToPose", (9.0, 0.0, 0.0, 0.0)), "goToPose's goal .* outside the walls"),
    ({"robot": (0.0, 0.0, 0.0, 0.0)}, ("goToPose", (2.0, 0.0, 0.0, 5.0)),
     r"goal speed 5 m/s is beyond the robot's 1 m/s"),
])
def test_nothing_outside_the_world_is_simulated(scene, call, message):
    """A scene or goal beyond the walls (|x| <= 5, |y| <= 4 m) or a goal speed beyond the robot's is a SimError,
    not a run that times out."""
    sim = SoccerSim(0)
    with pytest.raises(SimError, match=message):
        sim.reset(scene)
        sim.run(ActionCall(*call))
