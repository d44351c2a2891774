"""Measures besides the duration (Ch. 8.1, sims.episode): each bundled simulator reports the energy its
motors spent, as computed by hand on simple motions, and the end error, the distance between the commanded
subgoal and the state reached; the measures survive shards and recorded-executions logs (CSV and Parquet),
files written before them still load, a measure in another unit than the declared one is refused naming the
column, and the same seed gives the same measures."""

from __future__ import annotations

import csv
import dataclasses
import math
import pickle

import numpy as np
import pytest
from tailor.errors import DataError
from tailor.refinement.learning.logs import episode_rows, read_logs, write_log
from tailor.sims import registry
from tailor.sims.episode import ENERGY, ERROR, HEADING_ERROR, ActionCall, Episode, Measures
from tailor.sims.experience import Origin, gather, load_episodes, save_episodes
from tailor.sims.protocol import Quantity
from tailor.sims.shards import Piece, find_shards, load_piece, write_shard

SIMULATORS = ("soccer", "kitchen", "arm")


# --- energy, by hand ----------------------------------------------------------------------------------------
# The soccer robot is driven by a constant command instead of a controller, so that its motion is known
# exactly: its speed ramps at A_MAX (phidot at ALPHA_MAX) from the start to the command and holds there. The
# simulator sums the work of each physics step's speed change; on a ramp the sum telescopes to the kinetic
# energy, so the only difference to the hand value is the rounding of some hundred float additions (rel 1e-9
# is a million times wider than that; a wrong mass, a missing 1/2, a step counted twice are off by far more).
def _soccer_constant(monkeypatch, start, command, goal):
    from tailor.sims.soccer.actions import ACTION_FUNCTIONS
    from tailor.sims.soccer.simulator import Noise, SoccerSim

    monkeypatch.setitem(ACTION_FUNCTIONS, "goToPose", lambda *state_and_goal: command)
    sim = SoccerSim(0, Noise.off())
    sim.place(start)
    episode = sim.run(ActionCall("goToPose", goal))
    assert episode.succeeded
    return sim, episode


def test_soccer_energy_of_a_straight_acceleration_is_its_kinetic_energy(monkeypatch):
    from tailor.sims.soccer import world as W

    sim, episode = _soccer_constant(monkeypatch, (-2.0, 0.0, 0.0, 0.0), (0.8, 0.0), (0.5, 0.0, 0.0, 0.8))
    assert sim.v == 0.8 and sim.w == 0.0  # from rest to 0.8 m/s at A_MAX, then cruising
    assert episode.measures[ENERGY] == pytest.approx(0.5 * W.ROBOT_MASS * 0.8 ** 2, rel=1e-9)  # 2.88 J


def test_soccer_energy_of_a_turn_on_the_spot_is_its_rotational_energy(monkeypatch):
    from tailor.sims.soccer import world as W

    # the ball point circles the axle: the goal is where it is after a quarter turn (heading pi/2)
    offset = W.BALL_POINT_OFFSET
    sim, episode = _soccer_constant(monkeypatch, (0.0, 0.0, 0.0, 0.0), (0.0, 2.0),
                                    (-offset, offset, math.pi / 2, 0.0))
    assert sim.w == 2.0 and sim.v == 0.0
    # I = m (0.4^2 + 0.4^2) / 12 = 0.24 kg m^2: 0.48 J at 2 rad/s
    assert W.ROBOT_MOMENT == pytest.approx(9.0 * 0.32 / 12)
    assert episode.measures[ENERGY] == pytest.approx(0.5 * W.ROBOT_MOMENT * 2.0 ** 2, rel=1e-9)


def test_soccer_braking_then_reversing_costs_both_kinetic_energies(monkeypatch):
    from tailor.sims.soccer import world as W

    # forward at 0.5 m/s, commanded -0.8 m/s: braking to rest costs 1/2 m 0.5^2 (nothing is recovered), then
    # speeding up backward 1/2 m 0.8^2; the step in which v changes sign counts both of its parts
    sim, episode = _soccer_constant(monkeypatch, (0.0, 0.0, 0.0, 0.5), (-0.8, 0.0), (-1.5, 0.0, 0.0, -0.8))
    assert sim.v == -0.8
    assert episode.measures[ENERGY] == pytest.approx(0.5 * W.ROBOT_MASS * (0.5 ** 2 + 0.8 ** 2), rel=1e-9)


def test_kitchen_energy_of_a_straight_drive_is_twice_the_kinetic_energy_at_top_speed():
    from tailor.sims.kitchen import world as W
    from tailor.sims.kitchen.simulator import BASE_MASS, KitchenSim, Noise

    # 2 m straight ahead, nothing in the way: the base speeds up to V_MAX, brakes to a stop at the goal (the
    # action ends once |v| <= SPEED_TOL, at sim.v) and turns nowhere. Work: 1/2 M V_MAX^2 speeding up, 1/2 M
    # (V_MAX^2 - v_end^2) braking (the speed profile rises, then falls: the sum telescopes, rounding only)
    sim = KitchenSim(0, Noise.off())
    sim.place((1.0, 1.0, 0.0), {}, {})
    episode = sim.run(ActionCall("navigate", (3.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.6)))
    assert episode.succeeded and sim.w == 0.0 and 0.0 <= sim.v <= 0.05
    hand = 0.5 * BASE_MASS * (2 * W.V_MAX ** 2 - sim.v ** 2)  # about 43.1 J of a 120 kg base
    assert episode.measures[ENERGY] == pytest.approx(hand, rel=1e-9)
    assert episode.measures[HEADING_ERROR] == 0.0


def test_kitchen_energy_of_a_governed_drive_is_twice_the_kinetic_energy_at_the_cruise_speed():
    from tailor.sims.kitchen.simulator import BASE_MASS, KitchenSim, Noise

    # the same drive at cruise speed 0.4: 1/2 M 0.4^2 speeding up, 1/2 M (0.4^2 - v_end^2) braking; and with
    # the motors' noise the governed drive costs far less than the one at the top speed, which follows its noisy
    # command (4/9 of the kinetic energy, and no jitter while it holds the cruise speed)
    sim = KitchenSim(0, Noise.off())
    sim.place((1.0, 1.0, 0.0), {}, {})
    episode = sim.run(ActionCall("navigate", (3.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.4)))
    assert episode.succeeded and 0.0 <= sim.v <= 0.05
    assert episode.measures[ENERGY] == pytest.approx(0.5 * BASE_MASS * (2 * 0.4 ** 2 - sim.v ** 2), rel=1e-9)
    noisy = {}
    for cruise in (0.6, 0.5):
        sim = KitchenSim(1, Noise())
        sim.place((1.0, 1.0, 0.0), {}, {})
        noisy[cruise] = sim.run(ActionCall("navigate", (5.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, cruise))).measures[ENERGY]
    assert noisy[0.5] < 0.5 * noisy[0.6]


@pytest.mark.parametrize("action", ["grip", "put"])
def test_kitchen_energy_of_a_grip_straight_ahead_is_the_extension_ramps(action):
    from tailor.sims.kitchen import world as W
    from tailor.sims.kitchen.simulator import GRIPPER_MASS, KitchenSim, Noise

    # the cup straight ahead of the shoulder (pan 0): only the extension moves, out to the cup and back, each
    # way up to EXT_SPEED and down to rest (2 x 1/2 m v^2); it carries the cup one way (grip: back, put: out)
    sim = KitchenSim(0, Noise.off())
    table, cup = (3.0, 1.5, 0.0), (2.75, 1.5)  # its serving edge at x = 2.65, the base 0.6 m before it
    holding = "cup1" if action == "put" else None
    sim.place((2.05, 1.5, 0.0), {"t": table}, {"cup1": cup if holding is None else (0.0, 0.0)}, holding)
    episode = sim.run(ActionCall(action, cup))
    assert episode.succeeded and sim.pan == 0.0
    hand = (GRIPPER_MASS + (GRIPPER_MASS + W.CUP_MASS)) * W.EXT_SPEED ** 2  # 0.0506 J
    assert episode.measures[ENERGY] == pytest.approx(hand, rel=1e-9)


def test_arm_energy_of_a_single_joint_ramp_is_twice_its_kinetic_energy_at_cruise():
    from tailor.sims.arm import world as W
    from tailor.sims.arm.simulator import ArmSim, Noise

    # the shoulder turns 2 rad rest to rest, the elbow held at 0.5 rad: the arm turns as one body of moment
    # I = m_a l_a^2 / 3 + m_b l_b^2 / 12 + m_b d^2 about the shoulder, d the shoulder to link B's centre
    elbow = 0.5
    la, lb = W.LINK_A_LENGTH, W.LINK_B_LENGTH
    d2 = la ** 2 + (lb / 2) ** 2 + la * lb * math.cos(elbow)
    inertia = W.LINK_A_MASS * la ** 2 / 3 + W.LINK_B_MASS * lb ** 2 / 12 + W.LINK_B_MASS * d2  # 0.823 kg m^2
    sim = ArmSim(0, Noise.off())
    sim.place(-1.0, 0.0, elbow, 0.0)
    episode = sim.run(ActionCall("reach", (1.0, 0.0, elbow, 0.0)))
    assert episode.succeeded
    # up to the profile's cruise OMEGA_MAX and down to rest: I OMEGA_MAX^2 (0.823 J). The PID tracking it
    # overshoots the cruise by under 3% where the ramp ends (then settles back), which costs up to
    # 1.03^2 - 1 = 6% more; it cannot cost less than the profile's own ramps
    hand = inertia * W.OMEGA_MAX ** 2
    assert hand <= episode.measures[ENERGY] <= 1.07 * hand


# --- error --------------------------------------------------------------------------------------------------
def _check_end_error(episode: Episode, end: tuple[float, float], goal: tuple[float, float],
                     logged: tuple[float, float] | None) -> bool:
    """The error is the distance from `goal` to the end state; where the episode logged its end (noise off:
    the logged state is the true one), to the logged one as well. Whether it was logged."""
    assert episode.measures[ERROR] == math.hypot(end[0] - goal[0], end[1] - goal[1])
    if logged is None or episode.t[-1] != episode.duration:
        return False
    assert episode.measures[ERROR] == math.hypot(logged[0] - goal[0], logged[1] - goal[1])
    return True


def test_soccer_error_is_the_ball_point_to_the_goal_as_logged():
    from tailor.sims.soccer.scenarios import RANGES, sample_task
    from tailor.sims.soccer.simulator import Noise, SoccerSim

    logged = 0
    for name in ("goToPose", "approachBall", "goToPosition"):
        for seed in range(6):
            robot, ball, call = sample_task(RANGES[name], np.random.default_rng(seed))
            sim = SoccerSim(seed, Noise.off(), RANGES[name].dynamics)
            sim.place(robot, ball)
            episode = sim.run(call)
            x, y, phi = sim.true_state()[:3]
            xg, yg, phig, _ = call.goal
            logged += _check_end_error(episode, (x, y), (xg, yg), tuple(episode.state[-1, :2]))
            if name == "goToPosition":  # its goal has no heading
                assert HEADING_ERROR not in episode.measures
            else:
                heading = abs((phi - phig + math.pi) % (2 * math.pi) - math.pi)
                assert episode.measures[HEADING_ERROR] == pytest.approx(heading, abs=1e-12)
                assert 0.0 <= episode.measures[HEADING_ERROR] <= math.pi
    assert logged >= 3  # the comparison with the log took place


def test_kitchen_navigate_error_is_the_base_to_the_goal_spot_as_logged():
    from tailor.sims.kitchen import world as W
    from tailor.sims.kitchen.scenarios import sample_goto
    from tailor.sims.kitchen.simulator import KitchenSim, Noise

    logged = 0
    for seed in range(8):
        layout, start, goal = sample_goto(np.random.default_rng(seed))
        sim = KitchenSim(seed, Noise.off())
        tables = {"table1": layout["table1"], "table2": layout["table2"]}
        sim.place(W.spot_pose(*start[:6]), tables, {"cup1": layout["cups"][0]}, speed=start[6])
        episode = sim.run(ActionCall("navigate", goal))
        gx, gy, gphi = W.spot_pose(*goal[:6])
        x, y, phi = sim.true_state()[:3]
        # the log holds the base pose as a spot with zero offsets: ox, oy, ophi are x, y, phi
        logged += _check_end_error(episode, (x, y), (gx, gy), tuple(episode.state[-1, :2]))
        assert episode.measures[HEADING_ERROR] == pytest.approx(abs(W.wrap(phi - gphi)), abs=1e-12)
    assert logged >= 2


@pytest.mark.parametrize("action", ["grip", "put"])
def test_kitchen_grip_and_put_error_is_the_gripper_where_it_closed_or_opened(action):
    from tailor.sims.kitchen import world as W
    from tailor.sims.kitchen.scenarios import random_layout
    from tailor.sims.kitchen.simulator import KitchenSim, Noise

    rng = np.random.default_rng(3)
    for seed in range(4):
        layout = random_layout(rng, 1)
        table, place = ("table1", layout["cups"][0]) if action == "grip" else ("table2", layout["puts"][0])
        pose = W.spot_pose(*W.serving_frame(layout[table], *place), 0.1 * seed - 0.15, 0.6, 0.2 - 0.1 * seed)
        sim = KitchenSim(seed, Noise.off())
        sim.place(pose, {"table1": layout["table1"], "table2": layout["table2"]},
                  {"cup1": layout["cups"][0]}, "cup1" if action == "put" else None)
        result = sim.run_sequence([ActionCall(action, place)])
        assert result.succeeded
        # the gripper stands still at its furthest while it closes / opens (GRIPPER_TIME: many samples)
        ext = result.column("ext")
        there = np.flatnonzero(ext == ext.max())
        assert len(there) >= 10
        gripper = np.column_stack([result.column("gripper_x")[there], result.column("gripper_y")[there]])
        assert np.all(gripper == gripper[0])
        gx, gy = gripper[0]
        assert result.results[0].measures[ERROR] == math.hypot(gx - place[0], gy - place[1])
        assert HEADING_ERROR not in result.results[0].measures


def test_arm_error_is_the_tip_to_the_goal_tip_as_logged():
    from tailor.sims.arm import world as W
    from tailor.sims.arm.scenarios import sample_reach
    from tailor.sims.arm.simulator import ArmSim, Noise

    logged = 0
    for seed in range(30):
        start, call = sample_reach(np.random.default_rng(seed))
        sim = ArmSim(seed, Noise.off())
        sim.place(*start)
        episode = sim.run(call)
        goal = W.forward(call.goal[0], call.goal[2])
        logged += _check_end_error(episode, sim.true_state()[4:], goal, tuple(episode.state[-1, 4:]))
        assert set(episode.measures) == {ENERGY, ERROR}  # a reach has no heading
    assert logged >= 2


# --- measures everywhere an episode goes --------------------------------------------------------------------
@pytest.fixture(scope="module")
def episodes():
    """A few episodes of every scenario of every bundled simulator."""
    return {(name, scenario): gather(name, scenario, 4, seed=11, progress=False)
            for name in SIMULATORS for scenario in registry.get(name).scenarios}


def test_every_measure_is_declared_with_its_unit(episodes):
    for name in SIMULATORS:
        entry = registry.get(name)
        assert entry.quantity(ENERGY) == Quantity("J") and entry.quantity(ERROR) == Quantity("m")
        if name != "arm":
            assert entry.quantity(HEADING_ERROR) == Quantity("rad", angle=True)
    for (name, _), found in episodes.items():
        for episode in found:
            assert {ENERGY, ERROR} <= set(episode.measures)
            assert all(m in registry.get(name).units for m in episode.measures)
            assert episode.measures[ENERGY] > 0.0 and episode.measures[ERROR] >= 0.0


def test_the_same_seed_gives_the_same_measures_and_they_pickle(episodes):
    for (name, scenario), found in episodes.items():
        again = gather(name, scenario, 4, seed=11, progress=False)
        assert [dict(e.measures) for e in again] == [dict(e.measures) for e in found]
        assert pickle.loads(pickle.dumps(found[0])).measures == found[0].measures  # to and from workers


def test_a_sequence_reports_each_actions_measures():
    from tailor.sims.soccer.simulator import Noise, SoccerSim

    calls = [ActionCall("approachBall", (1.0, 0.0, 0.0, 0.2)),
             ActionCall("dribbleBall", (2.5, 0.0, 0.0, 0.1))]
    one_by_one = SoccerSim(2, Noise())
    one_by_one.place((-1.0, 0.0, 0.0, 0.0), (1.0, 0.0))
    episodes = [one_by_one.run(c) for c in calls]
    dispatched = SoccerSim(2, Noise())
    dispatched.place((-1.0, 0.0, 0.0, 0.0), (1.0, 0.0))
    result = dispatched.run_sequence(calls)
    assert result.succeeded and [r.measures for r in result.results] == [e.measures for e in episodes]
    assert all(r.measures[ENERGY] > 0.0 for r in result.results)


def test_measures_are_immutable_and_finite():
    episode = Episode("a", np.zeros(1), np.zeros(1), np.zeros((1, 1)), ("x",), "success", 1.0, 0)
    assert dict(episode.measures) == {}
    measured = dataclasses.replace(episode, measures={ENERGY: 2.0})
    with pytest.raises(TypeError):
        measured.measures[ENERGY] = 3.0  # type: ignore[index]
    with pytest.raises(ValueError, match="measure 'energy' must be a finite number"):
        Measures({ENERGY: math.nan})


# --- shards -------------------------------------------------------------------------------------------------
def test_measures_survive_a_shard(tmp_path, episodes):
    for name in SIMULATORS:
        for (simulator, scenario), found in episodes.items():
            if simulator != name:
                continue
            write_shard(tmp_path / name, Origin(name, scenario, 11, 0, len(found)), found)
        for shard in find_shards(tmp_path / name, name):
            back = load_piece(Piece(shard.origin.first, shard.origin.stop, shard))
            found = episodes[(name, shard.origin.scenario)]
            assert [dict(e.measures) for e in back] == [dict(e.measures) for e in found]
            assert all(a.duration == b.duration and a.state.tobytes() == b.state.tobytes()
                       for a, b in zip(back, found))


def test_episodes_without_some_measures_keep_them_absent(tmp_path, episodes):
    found = episodes[("soccer", "goToPose")]
    mixed = [found[0], dataclasses.replace(found[1], measures={}),
             dataclasses.replace(found[2], measures={ENERGY: 1.5})]
    save_episodes(tmp_path / "mixed.npz", mixed)
    back = load_episodes(tmp_path / "mixed.npz")
    assert [dict(e.measures) for e in back] == [dict(e.measures) for e in mixed]


def _rewrite(path, drop=(), **replace) -> None:
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files if k not in drop}
    arrays.update(replace)
    np.savez_compressed(path, **arrays)


def test_a_shard_written_before_measures_still_loads(tmp_path, episodes):
    found = episodes[("soccer", "approachBall")]
    shard = write_shard(tmp_path, Origin("soccer", "approachBall", 11, 0, len(found)), found)
    _rewrite(shard.path, drop=("measure_names", "measures"), schema=np.array(3))  # as tailor wrote it before
    (old,) = find_shards(tmp_path, "soccer")
    back = load_piece(Piece(0, len(found), old))
    assert [dict(e.measures) for e in back] == [{}] * len(found)
    assert [e.duration for e in back] == [e.duration for e in found]


@pytest.mark.parametrize("spoil, message", [
    ({"drop": ("measures",)}, "holds measure_names without measures"),
    ({"measures": np.full((4, 2), np.inf)}, "its measures hold infinite values"),
    ({"measures": np.zeros((3, 2))}, "its measures are not 4 x 2 numbers"),
    ({"measure_names": np.array(["energy", "energy"])}, "its measure_names are not distinct names"),
])
def test_a_shard_with_broken_measures_is_one_line_naming_the_file(tmp_path, episodes, spoil, message):
    path = tmp_path / "broken.npz"
    save_episodes(path, episodes[("arm", "reach")])
    _rewrite(path, **spoil)
    with pytest.raises(DataError, match=message) as caught:
        load_episodes(path)
    assert str(caught.value).startswith(str(path)) and "\n" not in str(caught.value)


# --- logs ---------------------------------------------------------------------------------------------------
def _write_log(tmp_path, simulator: str, found, kind: str = "csv"):
    columns, rows = episode_rows(found, registry.get(simulator), run="r1", source="test")
    path = tmp_path / f"{simulator}.{kind}"
    write_log(path, columns, rows, kind)
    return path


@pytest.mark.parametrize("kind", ["csv", "parquet"])
@pytest.mark.parametrize("simulator, scenario", [
    ("soccer", "goToPose"), ("soccer", "goToPosition"), ("kitchen", "navigate"), ("kitchen", "grip"),
    ("arm", "reach")])
def test_measures_survive_a_log(tmp_path, episodes, kind, simulator, scenario):
    if kind == "parquet":
        pytest.importorskip("pyarrow")
    found = episodes[(simulator, scenario)]
    path = _write_log(tmp_path, simulator, found, kind)
    (back,) = read_logs([path], registry.get(simulator), [found[0].action]).values()
    assert [dict(e.measures) for e in back] == [dict(e.measures) for e in found]  # exactly: repr round trip


def _csv(path):
    return list(csv.reader(path.read_text().splitlines()))


def _save_csv(path, rows) -> None:
    with open(path, "w", newline="") as f:
        csv.writer(f).writerows(rows)


def test_a_log_names_each_measure_with_its_unit_on_the_execution_rows(tmp_path, episodes):
    path = _write_log(tmp_path, "soccer", episodes[("soccer", "goToPose")][:1])
    rows = _csv(path)
    k = [rows[0].index(c) for c in ("measure.energy [J]", "measure.error [m]", "measure.heading_error [rad]")]
    assert all(rows[1][i] != "" for i in k) and all(row[i] == "" for row in rows[2:] for i in k)


def test_a_log_without_measure_columns_is_valid_and_measures_nothing(tmp_path, episodes):
    found = episodes[("kitchen", "navigate")]
    path = _write_log(tmp_path, "kitchen", found)
    rows = _csv(path)
    keep = [i for i, c in enumerate(rows[0]) if not c.startswith("measure.")]
    _save_csv(path, [[row[i] for i in keep] for row in rows])  # a log as written before measures existed
    back = read_logs([path], registry.get("kitchen"), ["navigate"])["navigate"]
    assert [dict(e.measures) for e in back] == [{}] * len(found)
    assert [e.duration for e in back] == [e.duration for e in found]


def test_an_empty_measure_cell_is_no_measure(tmp_path, episodes):
    path = _write_log(tmp_path, "arm", episodes[("arm", "reach")][:2])
    rows = _csv(path)
    rows[1][rows[0].index("measure.energy [J]")] = ""
    _save_csv(path, rows)
    back = read_logs([path], registry.get("arm"), ["reach"])["reach"]
    assert set(back[0].measures) == {ERROR} and set(back[1].measures) == {ENERGY, ERROR}


@pytest.mark.parametrize("column, row, cell, message", [
    ("measure.energy [kJ]", 1, None,
     ":1: column 'measure.energy [kJ]': unit 'kJ', simulator 'soccer' declares 'J'"),
    ("measure.error", 1, None, ":1: column 'measure.error': unit 'none', simulator 'soccer' declares 'm'"),
    ("measure.energy [J]", 2, "nan", ":2: column 'measure.energy [J]': not a finite number: 'nan'"),
    ("measure.error [m]", 2, "far", ":2: column 'measure.error [m]': not a number: 'far'"),
    ("measure.energy [J]", 3, "1.0",
     ":3: column 'measure.energy [J]': a measure belongs on its execution's row"),
])
def test_a_bad_measure_is_one_line_naming_file_row_and_column(tmp_path, episodes, column, row, cell, message):
    path = _write_log(tmp_path, "soccer", episodes[("soccer", "goToPose")][:2])
    rows = _csv(path)
    if cell is None:  # a header: the column declares another unit
        rows[0][rows[0].index("measure.energy [J]" if "energy" in column else "measure.error [m]")] = column
    else:
        rows[row - 1][rows[0].index(column)] = cell
    _save_csv(path, rows)
    with pytest.raises(DataError) as caught:
        read_logs([path], registry.get("soccer"), ["goToPose"])
    text = str(caught.value)
    assert text.startswith(str(path) + ":") and message in text and "\n" not in text
