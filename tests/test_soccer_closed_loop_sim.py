"""The soccer simulator's side of closed-loop execution (Ch. 8.1): what the robot measures between two actions
(observe, scene), the disturbance "nudge" and the robot variant "weak_motors"."""

import math

import numpy as np
import pytest

from tailor.errors import SimError
from tailor.sims.episode import ActionCall
from tailor.sims.protocol import Observable
from tailor.sims.soccer import SIMULATOR, Noise
from tailor.sims.soccer import world as W
from tailor.sims.soccer.control import ARRIVE_SLACK
from tailor.sims.soccer.goto import GOTO
from tailor.sims.soccer.scenarios import subgoal_episode
from tailor.sims.soccer.simulator import CONTROL_HZ, DT, SPEED_TOL

ROBOT = (-2.0, -1.0, 0.3, 0.0)
BALL = (1.0, 0.5)
TO_BALL = ActionCall("goToPose", (BALL[0], BALL[1], 0.0, 0.2))  # ball-blind: from the west, no bump
DRIBBLE = ActionCall("dribbleBall", (2.5, -1.5, -1.0, 0.0))


def _simulator(seed=0, noise=None, disturbance=None, variant=None):
    sim = SIMULATOR.simulator(seed, noise, disturbance=disturbance, variant=variant)
    sim.reset({"robot": ROBOT, "ball": BALL})
    return sim


# --- observe, scene ---------------------------------------------------------------------------------------
def test_the_soccer_simulator_is_observable():
    assert isinstance(_simulator(), Observable)


@pytest.mark.parametrize("noise", [Noise(), Noise.off()], ids=["noisy", "noise_off"])
def test_observe_and_scene_are_what_the_next_action_starts_from(noise):
    """Both read the reading the next run() logs as its first params, exactly, also with noise: they take it
    from a copy of the noise stream's state, which they leave where it was."""
    sim = _simulator(7, noise)
    assert sim.run(TO_BALL).succeeded
    state = sim.rng.bit_generator.state
    observed, scene = sim.observe("dribbleBall"), sim.scene()
    assert sim.observe("dribbleBall") == observed  # no draw: the same reading again
    assert sim.rng.bit_generator.state == state
    assert scene["robot"] == observed and len(scene["ball"]) == 2
    if noise == Noise.off():
        assert observed == sim.true_state()[:4] and scene["ball"] == sim.true_state()[4:]
    else:
        assert max(abs(a - b) for a, b in zip(observed, sim.true_state()[:4])) > 0.0
    episode = sim.run(DRIBBLE)
    assert tuple(episode.params[:4]) == observed
    assert tuple(episode.state[0, 4:]) == scene["ball"]


def test_observe_and_scene_advance_nothing():
    sim = _simulator(3)
    sim.run(TO_BALL)
    before = (sim.time, sim.steps, sim.true_state(), tuple(sim.ball.velocity))
    sim.observe("goToPose")
    sim.scene()
    assert (sim.time, sim.steps, sim.true_state(), tuple(sim.ball.velocity)) == before


def test_scene_without_a_ball_has_only_the_robot_and_observe_names_unknown_actions():
    sim = SIMULATOR.simulator(0)
    sim.reset({"robot": ROBOT})
    assert set(sim.scene()) == {"robot"}
    with pytest.raises(SimError, match="known: goToPose"):
        sim.observe("kick")


def test_reset_to_the_scene_reproduces_the_state_without_noise():
    sim = _simulator(2, Noise.off())
    assert sim.run(TO_BALL).succeeded
    again = SIMULATOR.simulator(9, Noise.off())
    again.reset(sim.scene())
    assert again.true_state() == pytest.approx(sim.true_state(), abs=1e-12)
    assert again.v == sim.v and again.phi == pytest.approx(sim.phi, abs=1e-12)


# --- the disturbance "nudge" ------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", range(6))
def test_the_nudge_pushes_the_ball_once_in_the_window_so_that_it_rolls_the_documented_distance(seed):
    sim = SIMULATOR.simulator(seed, Noise.off(), disturbance="nudge")
    sim.reset({"robot": (-3.0, -2.0, 0.0, 0.0), "ball": (0.5, 0.5)})  # the ball lies free, far from walls
    nudge = sim.nudge
    assert W.NUDGE_WINDOW[0] <= nudge.time <= W.NUDGE_WINDOW[1] + DT
    while sim.steps < nudge.step:
        sim.step()
    assert tuple(sim.ball.position) == (0.5, 0.5) and sim.nudged is None  # not before its time
    sim.step()
    assert sim.nudged == (0.5, 0.5) and tuple(sim.ball.velocity) != (0.0, 0.0)
    while sim.ball.velocity != (0.0, 0.0):
        sim.step()
    rolled = math.dist(sim.ball.position, (0.5, 0.5))
    assert rolled == pytest.approx(nudge.roll, abs=nudge.speed * DT)  # the friction's Euler step
    assert W.NUDGE_ROLL[0] <= nudge.roll <= W.NUDGE_ROLL[1]
    resting = tuple(sim.ball.position)
    for _ in range(int(2 * W.NUDGE_WINDOW[1] / DT)):  # once in a simulator's life
        sim.step()
    assert tuple(sim.ball.position) == resting


def test_the_nudge_time_counts_on_across_resets():
    sim = SIMULATOR.simulator(0, Noise.off(), disturbance="nudge")
    sim.reset({"robot": (-3.0, -2.0, 0.0, 0.0), "ball": (0.5, 0.5)})
    for _ in range(sim.nudge.step - 1):
        sim.step()
    sim.reset({"robot": (-3.0, -2.0, 0.0, 0.0), "ball": (0.0, 0.0)})
    sim.step()
    sim.step()
    assert sim.nudged == (0.0, 0.0) and sim.time == pytest.approx(2 * DT)


def test_the_nudge_leaves_the_robots_own_run_alone_until_the_push():
    """Same seed with and without the disturbance: the same noise, so the same logged run until the push."""
    plain, nudged = _simulator(11), _simulator(11, disturbance="nudge")
    a, b = plain.run(TO_BALL), nudged.run(TO_BALL)
    n = int(np.sum(a.t < nudged.nudge.time))  # rows logged before the push
    assert n >= 5 and min(a.t.size, b.t.size) > n + 1
    np.testing.assert_array_equal(a.params, b.params)
    np.testing.assert_array_equal(a.state[:n], b.state[:n])
    m = min(a.t.size, b.t.size)
    assert not np.array_equal(a.state[n:m, 4:], b.state[n:m, 4:])  # then the ball goes elsewhere


def test_a_nudged_approach_ends_as_ball_moved_at_rest_and_the_closed_loop_goes_on_from_the_scene():
    sim = _simulator(11, disturbance="nudge")
    episode = sim.run(TO_BALL)
    assert episode.outcome == "ball_moved"  # not "collision": the robot did not bump it
    assert sim.v == 0.0 and sim.w == 0.0 and tuple(sim.ball.velocity) == (0.0, 0.0)  # settled
    assert sim.nudged == BALL and math.dist(sim.true_state()[4:], BALL) > 0.2
    ball = sim.scene()["ball"]
    target = (2.5, -1.5)
    again = ActionCall("approachBall", (*ball, math.atan2(target[1] - ball[1], target[0] - ball[0]), 0.2))
    assert sim.run(again).outcome == "success"
    assert sim.run(ActionCall("dribbleBall", (*target, -1.0, 0.0))).outcome == "success"


def test_a_nudge_while_dribbling_knocks_the_ball_away():
    lost = 0
    for seed in range(10):
        sim = SIMULATOR.simulator(seed, disturbance="nudge")
        sim.reset({"robot": (-2.5, 0.0, 0.0, 0.0), "ball": (-2.5, 0.0)})  # in the guide
        episode = sim.run(ActionCall("dribbleBall", (2.5, 0.5, 0.0, 0.0)))
        assert episode.duration > sim.nudge.time  # pushed while dribbling
        lost += episode.outcome == "ball_lost"
    assert lost == 10


def test_a_robots_own_bump_stays_a_collision_under_the_nudge():
    """goToPose straight through a ball before the push: the robot's own collision, as without a nudge."""
    sim = SIMULATOR.simulator(0, Noise.off(), disturbance="nudge")
    sim.reset({"robot": (-1.0, 0.0, 0.0, 0.5), "ball": (-0.6, 0.0)})
    episode = sim.run(ActionCall("goToPose", (1.0, 0.0, 0.0, 0.0)))
    assert episode.outcome == "collision" and episode.duration < sim.nudge.time


# --- the variant "weak_motors" ----------------------------------------------------------------------------
def _straight_time(distance: float, a: float, v: float = W.V_MAX) -> float:
    """goToPose from rest straight ahead to a goal at rest, by hand: accelerate at a to the top speed v, cruise,
    brake at the planned deceleration b to reach 0 ARRIVE_SLACK before the goal; success once below SPEED_TOL."""
    b = GOTO.decel_plan
    cruise = distance - ARRIVE_SLACK - v * v / (2 * a) - v * v / (2 * b)
    return v / a + cruise / v + (v - SPEED_TOL) / b


@pytest.mark.parametrize("distance", [3.0, 4.5])
def test_weak_motors_take_as_much_longer_as_the_time_optimal_profile_says(distance):
    durations = {}
    for variant in (None, "weak_motors"):
        sim = SIMULATOR.simulator(0, Noise.off(), variant=variant)
        sim.reset({"robot": (-2.5, 0.0, 0.0, 0.0)})
        episode = sim.run(ActionCall("goToPose", (-2.5 + distance, 0.0, 0.0, 0.0)))
        assert episode.succeeded
        durations[variant] = episode.duration
    normal = _straight_time(distance, W.A_MAX)
    weak = _straight_time(distance, W.WEAK_MOTOR_FACTOR * W.A_MAX, W.WEAK_TOP_SPEED * W.V_MAX)
    tick = 1.0 / CONTROL_HZ  # the episode ends at a control tick
    assert durations[None] == pytest.approx(normal, abs=tick)
    assert durations["weak_motors"] == pytest.approx(weak, abs=tick)
    assert durations["weak_motors"] - durations[None] == pytest.approx(weak - normal, abs=tick)  # 1/6 s
    assert durations["weak_motors"] > durations[None]


def test_weak_motors_lower_the_top_speeds_and_the_accelerations():
    sim = SIMULATOR.simulator(0, variant="weak_motors")
    d = sim.dynamics
    assert (d.v_max, d.w_max) == (0.8 * W.V_MAX, 0.8 * W.W_MAX)
    assert (d.a_max, d.alpha_max) == (0.75 * W.A_MAX, 0.75 * W.ALPHA_MAX)


def test_experience_of_the_variant_robot_same_task_longer():
    scenario = SIMULATOR.scenarios["goToPose"]
    plain, weak = scenario.run(4), scenario.run(4, variant="weak_motors")
    assert scenario.run(4, variant=None).duration == plain.duration
    np.testing.assert_array_equal(plain.params, weak.params)  # the same task, the same first reading
    assert weak.duration > plain.duration
    params = np.array([-2.5, 0.0, 0.0, 0.0, 1.5, 0.0, 0.0, 0.0])
    assert (subgoal_episode("goToPose", params, 0, variant="weak_motors").duration
            > subgoal_episode("goToPose", params, 0).duration)


# --- declarations, errors, determinism --------------------------------------------------------------------
def test_the_declared_disturbances_and_variants_are_the_simulated_ones():
    assert set(SIMULATOR.disturbances) == set(W.DISTURBANCES) == {"nudge"}
    assert set(SIMULATOR.variants) == set(W.VARIANTS) == {"weak_motors"}
    assert all(text.strip() for text in (*SIMULATOR.disturbances.values(), *SIMULATOR.variants.values()))


@pytest.mark.parametrize("kwargs, known", [({"disturbance": "wind"}, "nudge"),
                                           ({"variant": "payload"}, "weak_motors")])
def test_unknown_disturbance_or_variant_names_the_known_ones(kwargs, known):
    with pytest.raises(SimError, match=f"known: {known}"):
        SIMULATOR.simulator(0, **kwargs)
    with pytest.raises(SimError, match=f"known: {known}"):
        SIMULATOR.create(0, None, **{"disturbance": None, "variant": None, **kwargs})
    if "variant" in kwargs:
        with pytest.raises(SimError, match=f"known: {known}"):
            SIMULATOR.scenarios["goToPose"].run(0, **kwargs)


def test_same_seed_same_run_with_disturbance_and_variant():
    def run(seed):
        sim = _simulator(seed, disturbance="nudge", variant="weak_motors")
        result = sim.run_sequence([TO_BALL, DRIBBLE])
        return result, sim.scene()

    (a, scene_a), (b, scene_b) = run(5), run(5)
    assert a.results == b.results and scene_a == scene_b
    np.testing.assert_array_equal(a.trajectory, b.trajectory)
    assert run(6)[1] != scene_a
