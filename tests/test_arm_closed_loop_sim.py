"""The arm simulator for the closed loop (Ch. 8.1): what observe() and scene() measure between reaches, the
"bump" disturbance (a joint-velocity kick) and the "payload" variant (the ramps' acceleration x0.7), against
what run() logs and against ramp times computed by hand."""

from __future__ import annotations

import numpy as np
import pytest

from tailor.errors import SimError
from tailor.sims.arm import SIMULATOR
from tailor.sims.arm import world as W
from tailor.sims.arm.disturbances import BUMP_KICK, BUMP_WINDOW, PAYLOAD_FACTOR
from tailor.sims.arm.letters import random_stroke
from tailor.sims.arm.scenarios import subgoal_episode
from tailor.sims.arm.simulator import CONTROL_HZ, ArmSim, Noise
from tailor.sims.episode import ActionCall
from tailor.sims.protocol import Observable

QUIET = Noise.off()


def _letter(seed: int, n: int = 5) -> tuple[tuple[float, float, float, float], list[ActionCall]]:
    """A random stroke of n way-points: the arm at rest at the first, reaches through the others (passing them
    at 0.3 and -0.2 rad/s), at rest at the last."""
    angles = [W.inverse(*p) for p in random_stroke(np.random.default_rng(seed), n)]
    calls = [ActionCall("reach", (a, 0.3, b, -0.2)) for a, b in angles[1:-1]]
    calls.append(ActionCall("reach", (angles[-1][0], 0.0, angles[-1][1], 0.0)))
    return (angles[0][0], 0.0, angles[0][1], 0.0), calls


def _sim(seed: int, start, noise: Noise = QUIET, **kwargs) -> ArmSim:
    sim = SIMULATOR.simulator(seed, noise, **kwargs) if kwargs else SIMULATOR.create(seed, noise)
    sim.reset({"arm": start})
    return sim


def _same(a, b) -> bool:
    return (a.outcome == b.outcome and a.duration == b.duration and np.array_equal(a.params, b.params)
            and np.array_equal(a.state, b.state))


# --- observe and scene ------------------------------------------------------------------------------------
def test_declared_and_observable():
    assert set(SIMULATOR.disturbances) == {"bump"} and set(SIMULATOR.variants) == {"payload"}
    assert isinstance(SIMULATOR.create(0, QUIET), Observable)


@pytest.mark.parametrize("noise", [QUIET, Noise()], ids=["noise off", "default noise"])
def test_observe_is_what_the_next_run_logs_first(noise):
    start, calls = _letter(1)
    sim = _sim(1, start, noise)
    for call in calls:
        observed = sim.observe("reach")
        assert sim.scene() == {"arm": observed}
        episode = sim.run(call)
        assert episode.outcome == "success"
        assert observed == tuple(episode.params[:4])  # exactly, the noise included
    if noise == QUIET:
        assert sim.observe("reach") == sim.true_state()[:4]


def test_measuring_leaves_the_run_as_it_was():
    start, calls = _letter(2)
    plain, measured = _sim(2, start, Noise()), _sim(2, start, Noise())
    for call in calls:
        measured.observe("reach")
        measured.scene()
        assert _same(plain.run(call), measured.run(call))


def test_reset_to_the_scene_reproduces_the_state():
    start, calls = _letter(3)
    sim = _sim(3, start)
    for call in calls[:2]:  # stopped mid-letter, moving
        sim.run(call)
    scene = sim.scene()
    assert scene["arm"] == sim.true_state()[:4] and max(abs(scene["arm"][1]), abs(scene["arm"][3])) > 0.1
    again = _sim(4, scene["arm"])
    assert again.true_state() == pytest.approx(sim.true_state(), abs=1e-12)
    assert again.run(calls[2]).outcome == "success"


def test_observe_rejects_an_unknown_action():
    with pytest.raises(SimError, match="unknown arm action 'wave'"):
        SIMULATOR.create(0, QUIET).observe("wave")


# --- the "bump" disturbance -------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", range(8))
def test_bump_kicks_the_joints_once_within_its_window(seed):
    start, calls = _letter(seed, 6)
    calm, bumped = _sim(seed, start), _sim(seed, start, disturbance="bump")
    a, b = calm.run_sequence(calls), bumped.run_sequence(calls)
    (event,) = bumped.events
    assert BUMP_WINDOW[0] <= event.moment <= BUMP_WINDOW[1]
    assert event.moment <= event.reaching < event.moment + 1.0 / CONTROL_HZ
    assert event.time == pytest.approx(event.reaching)  # one placement: the clock counts reaching time
    assert all(BUMP_KICK[0] <= abs(k) <= BUMP_KICK[1] for k in event.kick)
    # nothing changes before it strikes; the true state jumps after it
    n = int((a.trajectory[:, 0] <= event.time + 1e-9).sum())
    assert n > 0 and np.array_equal(a.trajectory[:n], b.trajectory[:n])
    assert not np.array_equal(a.trajectory[n:n + 1], b.trajectory[n:n + 1])
    # the reach it struck still ends: at its goal, or at a joint limit
    assert b.results[-1].outcome in {"success", "joint_limit"}


def test_the_kick_is_the_joint_velocity_jump():
    sim = _sim(0, (0.5, 0.0, 1.0, 0.0))
    sim.command(0.0, 0.0)
    before = sim.true_state()
    sim._kick((2.0, -3.0))
    after = sim.true_state()
    assert after[1] - before[1] == pytest.approx(2.0) and after[3] - before[3] == pytest.approx(-3.0)
    # the links stay rigid about the shoulder and the elbow: the pivots' velocities agree
    a, b = sim.link_a, sim.link_b
    elbow = a.local_to_world((0.5 * W.LINK_A_LENGTH, 0.0))
    assert a.velocity_at_world_point(elbow) == pytest.approx(b.velocity_at_world_point(elbow), abs=1e-9)
    assert a.velocity_at_world_point((0.0, 0.0)) == pytest.approx((0.0, 0.0), abs=1e-9)


def test_a_bump_is_deterministic_per_seed_and_strikes_a_single_reach():
    start, calls = _letter(5)
    runs = []
    for _ in range(2):
        sim = _sim(5, start, Noise(), disturbance="bump")
        result = sim.run_sequence(calls)
        runs.append((sim.events, result.results, result.trajectory))
    assert runs[0][0] == runs[1][0] and runs[0][1] == runs[1][1] and np.array_equal(runs[0][2], runs[1][2])
    other = _sim(6, start, Noise(), disturbance="bump")
    other.run_sequence(calls)
    assert other.events[0].kick != runs[0][0][0].kick
    short = _sim(5, start, disturbance="bump")  # a reach shorter than the moment: no bump yet
    short.run(ActionCall("reach", (start[0] + 0.01, 0.0, start[2], 0.0)))
    assert short.events == []


# --- the "payload" variant --------------------------------------------------------------------------------
def _shoulder_move(distance: float, variant: str | None) -> float:
    sim = ArmSim(0, QUIET, variant=variant)
    sim.place(0.0, 0.0, 1.0, 0.0)
    episode = sim.run(ActionCall("reach", (distance, 0.0, 1.0, 0.0)))
    assert episode.outcome == "success"
    return episode.duration


def _ramp(distance: float, v: float, a: float) -> float:
    """Rest to rest, time-optimal: d / v + v / a with a cruise (d >= v^2 / a), else 2 sqrt(d / a)."""
    return distance / v + v / a if distance >= v * v / a else 2.0 * (distance / a) ** 0.5


@pytest.mark.parametrize("distance", [0.4, 1.2, 2.0])
def test_payload_ramps_take_the_hand_computed_time(distance):
    # only the shoulder moves: 0.4 rad is a triangle (x 1/sqrt(0.7) = 1.195), 1.2 and 2 rad cruise
    # (+ v/a (1/0.7 - 1) = 0.214 s)
    v, a = W.OMEGA_MAX, W.ALPHA_MAX
    nominal, payload = _ramp(distance, v, a), _ramp(distance, v, PAYLOAD_FACTOR * a)
    assert _shoulder_move(distance, None) == pytest.approx(nominal, abs=0.1)
    assert _shoulder_move(distance, "payload") == pytest.approx(payload, abs=0.1)
    assert (_shoulder_move(distance, "payload") - _shoulder_move(distance, None)
            == pytest.approx(payload - nominal, abs=0.05))


def test_payload_keeps_every_goal_velocity_the_binding_allows():
    sim = ArmSim(0, QUIET, variant="payload")
    sim.place(-0.5, 0.0, 1.2, 0.0)
    episode = sim.run(ActionCall("reach", (0.8, W.OMEGA_MAX, 0.4, -W.OMEGA_MAX)))
    assert episode.outcome == "success"


# --- names and scenarios ------------------------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["disturbance", "variant"])
def test_unknown_names_are_sim_errors_naming_the_known(kind):
    known = "bump" if kind == "disturbance" else "payload"
    with pytest.raises(SimError, match=f"no {kind} 'quake' \\(known: {known}\\)"):
        SIMULATOR.simulator(0, None, **{kind: "quake"})
    with pytest.raises(SimError, match=f"no {kind} 'quake' \\(known: {known}\\)"):
        ArmSim(0, **{kind: "quake"})


def test_scenarios_run_the_variant_robot():
    for scenario in SIMULATOR.scenarios.values():
        slower = 0
        for seed in range(6):
            assert _same(scenario.run(seed), scenario.run(seed, variant=None))
            slower += scenario.run(seed, variant="payload").duration > scenario.run(seed).duration
        assert slower >= 4
    params = SIMULATOR.scenarios["reach"].run(1).params
    assert _same(subgoal_episode("reach", params, 1), subgoal_episode("reach", params, 1, variant=None))
    payload = subgoal_episode("reach", params, 1, variant="payload")
    assert payload.duration > subgoal_episode("reach", params, 1).duration
