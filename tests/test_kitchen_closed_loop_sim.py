"""The kitchen simulator for the closed loop (Ch. 8.1): what observe() and scene() measure between actions,
the "cup" disturbance (a cup displaced while the base drives) and the "slow_floor" variant (a carpeted room
B), against what run() logs and against drive times computed by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tailor.errors import SimError
from tailor.sims.episode import ActionCall
from tailor.sims.kitchen import SIMULATOR
from tailor.sims.kitchen import world as W
from tailor.sims.kitchen.disturbances import CUP_MOMENT, CUP_SHIFT, SLOW_FACTOR
from tailor.sims.kitchen.scenarios import random_layout, subgoal_episode
from tailor.sims.kitchen.simulator import BRAKE, CONTROL_HZ, KitchenSim, Noise
from tailor.sims.protocol import Observable

QUIET = Noise.off()


def _layout(seed: int, cups: int = 1) -> tuple[dict, dict]:
    """A random layout (the evaluation's) as a scene, and the layout."""
    layout = random_layout(np.random.default_rng(seed), cups)
    scene = {"robot": (*layout["start"], 0.0, 0.0, 0.0), "table table1": layout["table1"],
             "table table2": layout["table2"]}
    scene.update({f"cup cup{i}": c for i, c in enumerate(layout["cups"], start=1)})
    return scene, layout


def _plan(layout: dict) -> list[ActionCall]:
    """Fetch cup1 to the first put location: the open-loop plan of scenario 1 with fixed offsets."""
    cup, put = layout["cups"][0], layout["puts"][0]
    return [ActionCall("navigate", (*W.serving_frame(layout["table1"], *cup), 0.1, 0.6, 0.0, 0.0, 0.6)),
            ActionCall("grip", cup),
            ActionCall("navigate", (*W.serving_frame(layout["table2"], *put), -0.1, 0.5, 0.2, 0.0, 0.6)),
            ActionCall("put", put)]


def _sim(seed: int, scene: dict, noise: Noise = QUIET, **kwargs) -> KitchenSim:
    sim = SIMULATOR.simulator(seed, noise, **kwargs) if kwargs else SIMULATOR.create(seed, noise)
    sim.reset(scene)
    return sim


def _same(a, b) -> bool:
    return (a.outcome == b.outcome and a.duration == b.duration and np.array_equal(a.params, b.params)
            and np.array_equal(a.state, b.state))


# --- observe and scene ------------------------------------------------------------------------------------
def test_declared_and_observable():
    assert set(SIMULATOR.disturbances) == {"cup"} and set(SIMULATOR.variants) == {"slow_floor"}
    assert isinstance(SIMULATOR.create(0, QUIET), Observable)


@pytest.mark.parametrize("noise", [QUIET, Noise()], ids=["noise off", "default noise"])
def test_observe_is_what_the_next_run_logs_first(noise):
    scene, layout = _layout(3)
    sim = _sim(3, scene, noise)
    for call in _plan(layout):
        observed = sim.observe(call.action)
        assert observed == sim.observe(call.action)  # measuring twice between two actions: one measurement
        speed = sim.v  # navigate also observes the base's speed (true: the noise moves the pose only)
        episode = sim.run(call)
        assert episode.outcome == "success"
        n = len(SIMULATOR.action(call.action).observed)
        assert observed == tuple(episode.params[:n])  # exactly, the noise included
        assert len(observed) == n and observed[3:6] == (0.0, 0.0, 0.0)
        assert observed[6:] == ((speed,) if call.action == "navigate" else ())


def test_measuring_leaves_the_run_as_it_was():
    # a closed loop that observes and reads the scene between actions stays on the open loop's noise stream
    scene, layout = _layout(5)
    plain, measured = _sim(5, scene, Noise()), _sim(5, scene, Noise())
    for call in _plan(layout):
        measured.observe(call.action)
        measured.scene()
        assert _same(plain.run(call), measured.run(call))
    assert plain.true_state() == measured.true_state()


def test_scene_noise_off_is_the_true_world_and_reset_reproduces_it():
    scene, layout = _layout(7, cups=2)
    sim = _sim(7, scene)
    for call in _plan(layout)[:3]:  # the cup is in the gripper, the base at the dropoff spot
        assert sim.run(call).outcome == "success"
    measured = sim.scene()
    x, y, phi = sim.true_state()[:3]
    assert measured["robot"] == (x, y, phi, 0.0, 0.0, 0.0, sim.v)  # a spot and the speed it has (a residual one)
    assert measured["table table1"] == pytest.approx(layout["table1"], abs=0.0)
    assert measured["table table2"] == pytest.approx(layout["table2"], abs=0.0)
    assert measured["cup cup1"] == pytest.approx(sim.gripper(), abs=1e-12) and measured["held cup1"] == ()
    assert measured["cup cup2"] == pytest.approx(layout["cups"][1], abs=1e-12)
    again = SIMULATOR.create(8, QUIET)
    again.reset(measured)
    assert again.true_state()[:3] == pytest.approx((x, y, phi), abs=1e-12) and again.v == sim.v
    assert again.held == "cup1" and again.cups["cup1"].position == pytest.approx(again.gripper(), abs=1e-12)
    # reset tucks the arm exactly: the gripper moves by what the tuck left within its tolerances
    assert again.gripper() == pytest.approx(sim.gripper(), abs=0.01)
    assert again.cups["cup2"].position == pytest.approx(layout["cups"][1], abs=1e-12)
    assert again.tables == sim.tables
    assert again.run(_plan(layout)[3]).outcome == "success"  # the put goes on from the reset world


def test_scene_with_noise_measures_cups_near_where_they_stand():
    scene, _ = _layout(2, cups=2)
    sim = _sim(2, scene, Noise())
    first, second = sim.scene(), sim.scene()
    for name in ("cup1", "cup2"):
        true = tuple(sim.cups[name].position)
        assert first[f"cup {name}"] != true and first[f"cup {name}"] == pytest.approx(true, abs=0.05)
        assert first[f"cup {name}"] != second[f"cup {name}"]  # two measurements
    assert first["robot"] == second["robot"]  # the same noise row until a run uses it
    again = _sim(2, scene, Noise())
    assert again.scene() == first  # deterministic per seed


def test_observe_rejects_an_unknown_action():
    with pytest.raises(SimError, match="unknown kitchen action 'fly'"):
        SIMULATOR.create(0, QUIET).observe("fly")


# --- the "cup" disturbance --------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", range(12))
def test_cup_moves_on_its_table_while_the_base_drives(seed):
    scene, layout = _layout(seed, cups=2)
    plan = _plan(layout)
    calm, disturbed = _sim(seed, scene), _sim(seed, scene, disturbance="cup")
    before = {name: tuple(body.position) for name, body in disturbed.cups.items()}
    a, b = calm.run(plan[0]), disturbed.run(plan[0])
    assert _same(a, b)  # the base does not notice: the same drive, the same noise
    (event,) = disturbed.events
    # where: one of the cups, CUP_SHIFT away, wholly on its table, clear of the other cup
    assert event.before == before[event.cup]
    assert CUP_SHIFT[0] <= event.distance <= CUP_SHIFT[1]
    assert tuple(disturbed.cups[event.cup].position) == event.after
    table = next(box for box in disturbed.tables.values() if box.contains(*event.before))
    top = W.Box(table.cx, table.cy, table.hx - W.CUP_RADIUS, table.hy - W.CUP_RADIUS, table.angle)
    assert top.contains(*event.after)
    other = next(name for name in before if name != event.cup)
    assert tuple(disturbed.cups[other].position) == before[other]
    assert math.dist(event.after, before[other]) >= W.CUP_SEPARATION
    # when: within its window of the navigate's least time, at the first control tick from the moment drawn
    gx, gy, _ = W.spot_pose(*plan[0].goal[:6])
    least = math.hypot(gx - layout["start"][0], gy - layout["start"][1]) / W.V_MAX
    assert event.window == pytest.approx((CUP_MOMENT[0] * least, CUP_MOMENT[1] * least))
    assert event.window[0] <= event.elapsed < event.window[1] + 1.0 / CONTROL_HZ
    assert event.elapsed < b.duration and event.time == pytest.approx(event.elapsed)
    # once: the next navigate moves nothing
    disturbed.run(ActionCall("navigate", (*layout["start"], 0.0, 0.0, 0.0, 0.0, 0.6)))
    assert len(disturbed.events) == 1


def test_nothing_changes_before_the_cup_moves():
    scene, layout = _layout(4)
    calm = _sim(4, scene, Noise()).run_sequence(_plan(layout))
    disturbed_sim = _sim(4, scene, Noise(), disturbance="cup")
    disturbed = disturbed_sim.run_sequence(_plan(layout))
    (event,) = disturbed_sim.events
    assert calm.results[0] == disturbed.results[0]  # the navigate with the same noise
    before = calm.trajectory[:, 0] <= event.time
    n = int(before.sum())
    assert n > 0 and np.array_equal(calm.trajectory[:n], disturbed.trajectory[:n])


def test_open_loop_grip_misses_the_displaced_cup_the_closed_loop_grips_it():
    for seed in range(6):
        scene, layout = _layout(seed)
        plan = _plan(layout)
        open_loop = _sim(seed, scene, Noise(), disturbance="cup")
        result = open_loop.run_sequence(plan)
        assert [r.outcome for r in result.results] == ["success", "missed"]
        assert open_loop.held is None
        # closed loop: after the drive, read where the cup stands and grip there
        closed = _sim(seed, scene, Noise(), disturbance="cup")
        assert closed.run(plan[0]).outcome == "success"
        cup = closed.scene()["cup cup1"]
        assert math.dist(cup, layout["cups"][0]) >= CUP_SHIFT[0] - 0.05
        episode = closed.run(ActionCall("grip", cup))
        if episode.outcome == "out_of_reach":  # from a new spot in front of the cup
            frame = W.serving_frame(layout["table1"], *cup)
            assert closed.run(ActionCall("navigate", (*frame, 0.0, 0.6, 0.0, 0.0, 0.6))).outcome == "success"
            episode = closed.run(ActionCall("grip", closed.scene()["cup cup1"]))
        assert episode.outcome == "success" and closed.held == "cup1"
        assert [closed.run(call).outcome for call in plan[2:]] == ["success", "success"]


def test_a_disturbance_is_deterministic_per_seed():
    scene, layout = _layout(9, cups=2)
    runs = []
    for _ in range(2):
        sim = _sim(9, scene, Noise(), disturbance="cup")
        result = sim.run_sequence(_plan(layout))
        runs.append((sim.events, result.results, result.trajectory))
    assert runs[0][0] == runs[1][0] and runs[0][1] == runs[1][1] and np.array_equal(runs[0][2], runs[1][2])
    other = _sim(10, scene, Noise(), disturbance="cup")
    other.run(_plan(layout)[0])
    assert other.events != runs[0][0]


def test_no_cup_on_a_table_no_displacement():
    scene, layout = _layout(1)
    sim = _sim(1, scene, disturbance="cup")
    sim.place(layout["start"], {"table1": layout["table1"]}, {"cup1": layout["cups"][0]}, holding="cup1")
    assert sim.run(_plan(layout)[0]).outcome == "success"
    assert sim.events == []


# --- the "slow_floor" variant -----------------------------------------------------------------------------
def _drive(x0: float, distance: float, variant: str | None) -> float:
    sim = KitchenSim(0, QUIET, variant=variant)
    sim.place((x0, 1.5, 0.0), {}, {})
    episode = sim.run(ActionCall("navigate", (x0 + distance, 1.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.6)))
    assert episode.outcome == "success"
    return episode.duration


def test_slow_floor_drives_room_b_at_seven_tenths():
    # the trapezoid at the carpet's limits: t = d / (f V) + f V / (2 f A) + f V / (2 BRAKE f A); the ramps
    # take as long as nominally (speed and acceleration both x f), the cruise 1 / f as long
    v, a, f = W.V_MAX, W.A_MAX, SLOW_FACTOR
    for d in (2.0, 3.0):
        nominal = d / v + v / (2 * a) + v / (2 * BRAKE * a)
        slow = d / (f * v) + v / (2 * a) + v / (2 * BRAKE * a)
        assert _drive(5.5, d, "slow_floor") == pytest.approx(slow, abs=0.3)
        assert _drive(5.5, d, "slow_floor") - _drive(5.5, d, None) == pytest.approx(slow - nominal, abs=0.12)
    # an extra metre at cruise speed costs 1 / (f V) instead of 1 / V
    extra_metre = _drive(5.5, 3.0, "slow_floor") - _drive(5.5, 2.0, "slow_floor")
    assert extra_metre == pytest.approx(1 / (f * v), abs=0.06)


def test_slow_floor_leaves_room_a_as_it_was():
    assert _drive(1.0, 3.0, "slow_floor") == _drive(1.0, 3.0, None)
    sim = KitchenSim(0, QUIET, variant="slow_floor")
    sim.place((1.0, 1.5, 0.0), {}, {})
    assert sim.limits() == (W.V_MAX, W.W_MAX, W.A_MAX, W.ALPHA_MAX)
    sim.place((6.0, 1.5, 0.0), {}, {})
    slow = tuple(SLOW_FACTOR * q for q in (W.V_MAX, W.W_MAX, W.A_MAX, W.ALPHA_MAX))
    assert sim.limits() == pytest.approx(slow)


def test_slow_floor_lengthens_the_plan_only_in_room_b():
    scene, layout = _layout(6)
    nominal = _sim(6, scene).run_sequence(_plan(layout)).results
    slow = _sim(6, scene, variant="slow_floor").run_sequence(_plan(layout)).results
    assert all(r.outcome == "success" for r in nominal + slow)
    assert slow[:2] == nominal[:2]  # to table1 and the grip: room A
    assert slow[2].duration > nominal[2].duration + 1.0  # through the door to table2: half on the carpet


# --- names and scenarios ------------------------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["disturbance", "variant"])
def test_unknown_names_are_sim_errors_naming_the_known(kind):
    known = "cup" if kind == "disturbance" else "slow_floor"
    with pytest.raises(SimError, match=f"no {kind} 'quake' \\(known: {known}\\)"):
        SIMULATOR.simulator(0, None, **{kind: "quake"})
    with pytest.raises(SimError, match=f"no {kind} 'quake' \\(known: {known}\\)"):
        KitchenSim(0, **{kind: "quake"})


def test_scenarios_run_the_variant_robot():
    for scenario in SIMULATOR.scenarios.values():
        for seed in range(3):
            assert _same(scenario.run(seed), scenario.run(seed, variant=None))
            assert scenario.run(seed, variant="slow_floor").outcome == scenario.run(seed).outcome
    # a navigate into room B (the scenario's dropoff spots) takes longer on the carpet
    longer = [SIMULATOR.scenarios["navigate"].run(s, variant="slow_floor").duration
              > SIMULATOR.scenarios["navigate"].run(s).duration for s in range(12)]
    assert any(longer)
    params = SIMULATOR.scenarios["navigate"].run(1).params
    assert _same(subgoal_episode("navigate", params, 1), subgoal_episode("navigate", params, 1, variant=None))
    assert subgoal_episode("navigate", params, 1, variant="slow_floor").outcome == "success"
    with pytest.raises(SimError, match="no variant 'quake'"):
        SIMULATOR.scenarios["grip"].run(0, variant="quake")
