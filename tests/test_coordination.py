"""Implicit coordination (Ch. 7): the lossy channel, the field of view, perspective taking, the strategies,
seeded runs of `tailor coordinate` and its errors."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from tailor.cli.main import main
from tailor.refinement.evaluation.coordination import (
    NOBODY,
    Predictor,
    Team,
    agreed,
    choices,
    fuse,
    going,
    most_certain,
    perturbed_columns,
    team_view,
)
from tailor.refinement.models.action_models import load_action_models
from tailor.sims.channel import link_states
from tailor.sims.soccer.simulator import SoccerSim
from tailor.sims.soccer.team import TEAM, visible
from tailor.sims.soccer.world import SPARROW
from tailor.sims.episode import ActionCall
from tailor.sims.team import Observations, Perception, TeamLog

MODELS = Path(__file__).resolve().parent.parent / "domains" / "soccer" / "models"


@pytest.fixture(scope="module")
def predictor() -> Predictor:
    return Predictor(TEAM, load_action_models(MODELS, ("approachBall", "goToPosition")))


# --- the channel --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("quality", [0.0, 0.3, 0.7, 1.0])
def test_the_channel_delivers_the_configured_share_of_packets(quality):
    up = link_states(30_000, 3, quality, mean_outage=1.0, period=0.1, rng=np.random.default_rng(4))
    pairs = ~np.eye(3, dtype=bool)
    assert abs(up[:, pairs].mean() - quality) < 0.03
    assert np.array_equal(up, up.transpose(0, 2, 1)) and not up[:, np.arange(3), np.arange(3)].any()


def test_the_channel_drops_packets_in_intervals_of_the_mean_outage():
    link = link_states(50_000, 2, 0.5, mean_outage=1.5, period=0.1, rng=np.random.default_rng(1))[:, 0, 1]
    edges = np.flatnonzero(np.diff(link.astype(int)))  # every change of state
    runs = np.diff(edges)[(~link[edges[:-1] + 1])]  # lengths (ticks) of the outages between two changes
    assert 13 < runs.mean() < 17  # 1.5 s at 10 Hz (drops come in intervals, not one packet at a time)
    assert np.array_equal(link_states(100, 2, 0.5, 1.5, 0.1, np.random.default_rng(1))[:, 0, 1], link[:100])


# --- the field of view -----------------------------------------------------------------------------------------
def test_field_of_view_by_hand_geometry():
    robot = np.array([0.0, 0.0, 0.0, 0.0])  # at the origin, heading along +x
    ahead_left = np.array([1.0, 0.5])  # bearing atan(0.5) = 26.57 degrees
    behind = np.array([-1.0, 0.1])
    assert visible(robot, ahead_left, 90.0) and not visible(robot, ahead_left, 45.0)
    assert not visible(robot, ahead_left, 2 * 26.5) and visible(robot, ahead_left, 2 * 26.6)
    assert not visible(robot, behind, 340.0) and visible(robot, behind, 360.0)
    assert not visible(robot, ahead_left, 0.0)
    facing_up = np.array([2.0, 1.0, math.pi / 2, 0.0])
    assert visible(facing_up, np.array([2.3, 3.0]), 30.0) and not visible(facing_up, np.array([3.0, 1.0]), 170.0)


def test_robots_perceive_only_inside_the_field_of_view():
    states = np.array([[[0.0, 0.0, 0.0, 0.0], [2.0, 0.5, math.pi, 0.0], [-2.0, 0.0, 0.0, 0.0]]])
    log = TeamLog(0.1, states, np.array([[1.0, -0.2]]), ("pioneer",) * 3)
    obs = TEAM.observe(log, Perception(field_of_view=90.0), np.random.default_rng(0))
    seen = np.isfinite(obs.others[0, :, :, 0])
    # robot 0 sees robot 1 ahead, not robot 2 behind it; robot 1 (facing -x) sees 0 and 2; robot 2 sees 0 and 1
    assert seen.tolist() == [[False, True, False], [True, False, True], [True, True, False]]
    assert np.isfinite(obs.target[0, :, 0]).tolist() == [True, True, True]
    blind = TEAM.observe(log, Perception(field_of_view=0.0), np.random.default_rng(0))
    assert np.isnan(blind.others).all() and np.isnan(blind.target).all()
    np.testing.assert_array_equal(blind.own, obs.own)  # the noise drawn does not depend on the field of view


# --- perspective taking --------------------------------------------------------------------------------------
def _standing(states, target, kinds=("pioneer",) * 3, ticks=3) -> TeamLog:
    return TeamLog(0.1, np.repeat(np.array([states], dtype=float), ticks, axis=0),
                   np.repeat(np.array([target], dtype=float), ticks, axis=0), kinds)


def test_perspective_taking_chooses_the_lowest_predicted_time_not_the_nearest(predictor):
    """The ball at the origin is approached heading for the opponent goal (+x): robot 0 stands nearest but in
    front of it, facing the wrong way; robot 1 stands behind it, lined up; robot 2 far away."""
    log = _standing([[1.2, 0.0, 0.0, 0.0], [-2.0, 0.2, 0.0, 0.0], [-3.0, 2.5, -1.0, 0.0]], [0.0, 0.0])
    times = predictor.times(np.array(log.kinds), log.states[0], np.repeat(log.target[:1], 3, axis=0))
    assert np.argmin(times) == 1 and np.argmin(TEAM.distance(log.states[0], np.repeat(log.target[:1], 3, axis=0))) == 0
    exact = Perception(self_noise=0, teammate_noise=0, target_noise=0, self_heading_noise=0,
                       teammate_heading_noise=0, speed_noise=0, field_of_view=360.0, communication=0.0)
    team = team_view(log, TEAM, exact, seed=0)
    np.testing.assert_allclose(team.utilities("implicit", predictor)[0], np.tile(times, (3, 1)))
    assert choices(team.utilities("implicit", predictor)).tolist() == [[1, 1, 1]] * 3
    assert choices(team.utilities("distance", predictor)).tolist() == [[0, 0, 0]] * 3
    # without communication the explicit strategy knows only its own time: every robot thinks it is quickest
    assert going(choices(team.utilities("explicit", predictor))).tolist() == [3, 3, 3]


def test_the_heterogeneous_robot_is_predicted_with_its_own_model(predictor):
    log = _standing([[-1.0, 0.0, 0.0, 0.0], [-1.0, 0.0, 0.0, 0.0]], [1.0, 0.0], kinds=("pioneer", "sparrow"))
    times = predictor.times(np.array(log.kinds), log.states[0], np.repeat(log.target[:1], 2, axis=0))
    assert times[1] > times[0] + 0.5  # the same start and goal: the slower kind takes longer
    assert times[1] == pytest.approx(predictor.models["goToPosition"].predict_duration(
        TEAM.utility_parameters("sparrow", log.states[0, 1:], log.target[:1]))[0])


def test_explicit_coordination_uses_the_utilities_that_arrived(predictor):
    log = _standing([[1.2, 0.0, 0.0, 0.0], [-2.0, 0.2, 0.0, 0.0], [-3.0, 2.5, -1.0, 0.0]], [0.0, 0.0], ticks=4)
    team = team_view(log, TEAM, Perception(field_of_view=360.0, communication=1.0), seed=2)
    utilities = team.utilities("explicit", predictor)
    own = np.diagonal(utilities, axis1=1, axis2=2)  # what each robot predicted for itself
    np.testing.assert_array_equal(utilities, np.repeat(own[:, None, :], 3, axis=1))  # everyone holds the same
    assert agreed(choices(utilities)).all()


def test_shared_belief_without_communication_is_implicit_coordination(predictor):
    log = TEAM.dynamic(("pioneer",) * 3, 4.0, seed=3)
    team = team_view(log, TEAM, Perception(communication=0.0, field_of_view=180.0), seed=3)
    np.testing.assert_array_equal(team.utilities("shared", predictor), team.utilities("implicit", predictor))


def test_a_fresh_message_is_preferred_to_a_perception_and_a_stale_one_is_not():
    values = [(np.array([[1.0, 0.0]]), np.array([0.0625])), (np.array([[2.0, 0.0]]), np.array([0.0081]))]
    assert most_certain(values).tolist() == [[2.0, 0.0]]
    stale = [values[0], (values[1][0], np.array([0.0081 + 0.3 ** 2]))]  # 0.3 s old at 1 m/s
    assert most_certain(stale).tolist() == [[1.0, 0.0]]
    assert np.isnan(most_certain([(np.full((1, 2), np.nan), np.array([1.0]))])).all()
    heading = fuse([(np.array([[0.0, 3.1]]), np.array([1.0])), (np.array([[2.0, -3.1]]), np.array([1.0]))], heading=1)
    assert heading[0, 0] == pytest.approx(1.0) and abs(heading[0, 1]) == pytest.approx(math.pi, abs=1e-9)


def test_the_scene_declares_its_robots_state_and_what_the_added_noise_perturbs(predictor):
    """The core reads a robot's state as its scene declares it: Q4's noise on the soccer robots' pose, not on
    their speed (and the same draws as before the declaration: the first three columns)."""
    from tailor.sims.team import TeamScene

    assert isinstance(TEAM, TeamScene) and TEAM.state == ("x", "y", "phi", "v")
    assert perturbed_columns(TEAM) == [0, 1, 2]
    log = TEAM.dynamic(("pioneer",) * 2, 1.0, seed=5)
    team = team_view(log, TEAM, Perception(field_of_view=360.0), seed=5)
    plain = team.beliefs("shared")
    noisy = team.beliefs("shared", 0.5, np.random.default_rng(1), perturbed_columns(TEAM))
    known = np.isfinite(plain.states[..., 0]) & ~np.eye(2, dtype=bool)  # teammates' estimates
    assert (noisy.states[..., 3][known] == plain.states[..., 3][known]).all()  # the speed as estimated
    assert not np.allclose(noisy.states[..., :3][known], plain.states[..., :3][known])
    draws = np.random.default_rng(1).standard_normal(plain.states[..., :3].shape) * 0.5  # as drawn before it
    np.testing.assert_array_equal(noisy.states[..., :3][known], (plain.states[..., :3] + draws)[known])


def test_a_robot_that_knows_no_target_chooses_nobody():
    utilities = np.array([[[np.nan, np.nan], [3.0, 2.0]]])
    assert choices(utilities).tolist() == [[NOBODY, 1]]
    assert not agreed(choices(utilities))[0] and going(choices(utilities)).tolist() == [1]


def test_a_team_view_without_observations_of_teammates_has_only_itself():
    log = _standing([[0.0, 0.0, 0.0, 0.0], [1.0, 1.0, 0.0, 0.0]], [2.0, 0.0], kinds=("pioneer", "pioneer"))
    own = log.states.copy()
    obs = Observations(own, np.full((3, 2, 2, 4), np.nan), np.repeat(log.target[:, None, :], 2, axis=1))
    team = Team(log, obs, Perception(communication=0.0), np.zeros((3, 2, 2), dtype=bool))
    beliefs = team.beliefs("implicit")
    assert np.isnan(beliefs.states[:, 0, 1]).all() and np.array_equal(beliefs.states[:, 0, 0], own[:, 0])


# --- the other robot kind ------------------------------------------------------------------------------------
def test_the_other_kind_is_limited_by_its_own_dynamics_and_ignores_the_goal_heading():
    sim = SoccerSim(0, dynamics=SPARROW)
    sim.place((0.0, 0.0, 0.0, 0.0))
    sim.command(5.0, 9.0)
    assert abs(sim.v_cmd) <= SPARROW.v_max * 1.0001 and abs(sim.w_cmd) <= SPARROW.w_max * 1.0001
    episode = sim.run(ActionCall("goToPosition", (2.0, 1.0, 3.0, 0.0)))  # the goal heading 3 rad is not judged
    assert episode.succeeded
    # at most 0.6 m/s: the 2.24 m take at least 3.7 s
    assert episode.duration >= math.hypot(2.0, 1.0) / SPARROW.v_max


def test_the_oracle_of_expected_times_and_repeatability_by_hand():
    """Three runs of two robots: run 0 says robot 0 is quickest, runs 1 and 2 say robot 1. Pairs (0, 1), (0, 2)
    disagree; leaving one run out, the mean of the others picks robot 1 for every held-out run, right twice
    (runs 1, 2) and wrong once (run 0); robots choosing robot 0 are right only on run 0."""
    from tailor.refinement.evaluation.coordination_experiments import summarize_static

    row = {"chosen": [0, 0], "chosen_distance": [0, 0], "chosen_true_states": 0, "predicted": [5.0, 5.0],
           "measured": [5.0, 5.2], "repeated": [[5.5, 5.1], [5.6, 5.0]]}
    s = summarize_static([row])
    assert s["repeats"] == 2 and s["chose_quickest"] == 1.0
    assert s["quickest_repeatable"] == 0.0
    assert s["chose_quickest_oracle"] == pytest.approx(2 / 3)
    assert s["chose_quickest_every_run"] == pytest.approx(1 / 3)
    assert summarize_static([{**row, "repeated": [[5.5, 5.1]]}])["chose_quickest_oracle"] == 0.0  # = repeatable
    # the oracle fed the belief: the mean of its runs from the believed states picks robot 0, right on run 0 only
    believed = summarize_static([{**row, "believed": [[5.0, 5.3], [5.2, 5.1]]}])
    assert believed["chose_quickest_oracle_belief"] == pytest.approx(1 / 3)
    assert s["chose_quickest_oracle_belief"] is None


# --- the command -----------------------------------------------------------------------------------------
def _coordinate(capsys, *argv) -> dict:
    assert main(["coordinate", "soccer", "--episodes", "2", "--json", *argv]) == 0
    return json.loads(capsys.readouterr().out)


def test_the_same_seed_gives_the_same_tables(capsys):
    first, second = _coordinate(capsys, "--seed", "5"), _coordinate(capsys, "--seed", "5")
    assert first == second
    assert {"agreement", "chose_quickest", "chose_quickest_distance", "static", "dynamic"} <= set(first)
    assert first["static"]["situations"] == 2 and first["dynamic"]["episodes"] == 2
    assert first["static"]["repeats"] == 1
    assert _coordinate(capsys, "--seed", "6")["dynamic"]["noise"] != first["dynamic"]["noise"]


@pytest.mark.parametrize("argv, status, message", [
    (["soccer", "--robots", "1"], 2, "tailor coordinate: error: argument --robots: must be at least 2: '1'"),
    (["soccer", "--robots", "9"], 2, "tailor coordinate: error: argument --robots: must be at most 8: '9'"),
    (["soccer", "--episodes", "0"], 2, "tailor coordinate: error: argument --episodes: must be at least 1: '0'"),
    (["soccer", "--repeats", "0"], 2, "tailor coordinate: error: argument --repeats: must be at least 1: '0'"),
    (["soccer", "--repeats", "40"], 2, "tailor coordinate: error: argument --repeats: must be at most 31: '40'"),
    (["hockey"], 3, "tailor coordinate: error: hockey: no such domain folder"),
    (["arm"], 11, "simulator 'arm' has no team scene: it cannot run coordination experiments"),
])
def test_bad_input_is_one_line(argv, status, message, capsys):
    try:
        code = main(["coordinate", *argv])
    except SystemExit as exit:
        code = exit.code
    assert code == status
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]


def test_an_unwritable_plot_folder_fails_before_any_work(tmp_path, capsys):
    occupied = tmp_path / "plots"
    occupied.write_text("a file")
    assert main(["coordinate", "soccer", "--plot", str(occupied)]) == 16
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "exists and is not a folder" in err[0]


def test_a_picture_that_cannot_be_written_fails_before_any_work(tmp_path, capsys):
    """Each of the pictures in the folder is checked up front (a folder in the way of the last one failed the
    run after its work, with two pictures written and the report lost)."""
    from tailor.refinement.evaluation.coordination_plots import FILES

    (tmp_path / FILES[-1]).mkdir()
    assert main(["coordinate", "soccer", "--plot", str(tmp_path)]) == 16
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"tailor coordinate: error: {tmp_path / FILES[-1]}: is a folder, not a file name"]
    assert sorted(p.name for p in tmp_path.iterdir()) == [FILES[-1]]


def test_domains_lists_coordinate_where_the_simulator_has_a_team_scene(capsys):
    import json

    assert main(["domains", "--json"]) == 0
    can = {d["name"]: d["can"] for d in json.loads(capsys.readouterr().out)["domains"]}
    assert "coordinate" in can["soccer"] and "coordinate" not in can["arm"] and "gather" in can["arm"]


def test_an_absurd_approach_model_is_refused_as_refine_refuses_it(tmp_path, capsys):
    """Every leaf of approachBall predicting 1e6 s: exit 12 naming the file (the team's predictions ran on it,
    an MAE of 1e6 s reported with exit 0)."""
    import json
    import shutil

    from tailor.planner_bridge import resolve_domain_dir

    shutil.copytree(resolve_domain_dir("soccer") / "models", tmp_path, dirs_exist_ok=True)
    model = tmp_path / "approachBall.json"
    data = json.loads(model.read_text())
    for leaf in data["duration"]["leaves"]:
        leaf["intercept"] = 1e6
    model.write_text(json.dumps(data))
    assert main(["coordinate", "soccer", "--episodes", "1", "--models", str(tmp_path)]) == 12
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith(f"tailor coordinate: error: {model}: a pioneer robot's approach: the model predicts 1e+06 s")
