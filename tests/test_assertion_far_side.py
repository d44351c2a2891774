"""Issue 35, Table 4.4 like for like: the collision-rich ball approaches (goToPoseFarSide, situations
`approach_far_side`), the success classifier's Table 4.4 on fresh episodes of a scenario (`tailor evaluate
--classifier`), and subgoal assertion on the rich situations (`--assertion --situations`)."""

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from tailor.cli.main import main
from tailor.refinement.evaluation.assertion_experiment import classifier_seed, classifier_table
from tailor.refinement.models.action_models import load_success_models
from tailor.sims.experience import gather
from tailor.sims.soccer.scenarios import FAR_SIDE, NEAR_BALL, RANGES, SITUATIONS, sample_task
from tailor.sims.soccer.world import wrap

MODELS = Path(__file__).resolve().parents[1] / "domains" / "soccer" / "models"


def _angle_at(robot, goal) -> float:
    """|angle_at|: the goal heading seen from the line from the start to the goal (Table 4.1)."""
    bearing = math.atan2(goal[1] - robot[1], goal[0] - robot[0])
    return abs(wrap(goal[2] - bearing))


def test_far_side_sampling_is_seeded_and_draws_far_side_approaches_near_the_ball():
    tasks = [sample_task(RANGES["goToPoseFarSide"], np.random.default_rng(seed)) for seed in range(200)]
    again = [sample_task(RANGES["goToPoseFarSide"], np.random.default_rng(seed)) for seed in range(200)]
    assert tasks == again
    for robot, ball, call in tasks:
        assert ball == call.goal[:2] and call.action == "goToPose"
        assert FAR_SIDE[0] <= _angle_at(robot, call.goal) <= FAR_SIDE[1]
        assert math.dist(robot[:2], ball) <= NEAR_BALL
    # the normal scenario's headings are uniform: half of its approaches come from the near side
    normal = [sample_task(RANGES["goToPoseAtBall"], np.random.default_rng(seed)) for seed in range(200)]
    assert sum(_angle_at(r, c.goal) < FAR_SIDE[0] for r, _, c in normal) > 60
    # the situations draw the same tasks, as the belief of problem `approach`
    problem, objects = SITUATIONS["approach_far_side"](np.random.default_rng(3))
    robot, _, call = tasks[3]
    assert problem == "approach" and objects["pos1"] == dict(zip(("x", "y", "phi", "v"), robot))
    assert objects["pos2"] == dict(zip(("x", "y", "phi", "v"), call.goal))


def test_far_side_approaches_collide_far_more_often_than_the_normal_ones():
    """Plain goToPose collided in 42% of 2000 far-side approaches, in 20% of 2000 normal ones: this fails
    where the far-side sampling is replaced by the normal one."""
    far = gather("soccer", "goToPoseFarSide", 100, seed=11, progress=False)
    normal = gather("soccer", "goToPoseAtBall", 100, seed=11, progress=False)
    far, normal = (float(np.mean([e.outcome == "collision" for e in episodes])) for episodes in (far, normal))
    assert far >= 0.3 and far >= normal + 0.15, (far, normal)


def test_classifier_table_reads_the_confusion_matrix_as_table_4_4():
    model = load_success_models(MODELS, {"goToPose"})["goToPose"]
    episodes = gather("soccer", "goToPoseFarSide", 40, seed=classifier_seed(0), progress=False)
    row = classifier_table(model, episodes)
    t = row["table"]
    predicted = model.predict_success(np.array([e.params for e in episodes]))
    observed = np.array([e.succeeded for e in episodes])
    assert row["episodes"] == 40 and sum(t.values()) == pytest.approx(1.0)
    assert row["correct"] == pytest.approx(np.mean(predicted == observed))
    assert row["false_success"] == pytest.approx(np.mean(predicted & ~observed))
    assert row["false_success"] == t["predicted_success_observed_fail"]
    assert row["always_success"] == pytest.approx(np.mean(observed)) == pytest.approx(1 - row["failed"])
    right = t["predicted_fail_observed_fail"] + t["predicted_success_observed_success"]
    assert row["correct"] == pytest.approx(right)
    assert row["outcomes"] == {"collision": int((~observed).sum())} or not (~observed).any()


def test_evaluate_classifier_reports_a_row_per_scenario(capsys):
    argv = ["evaluate", "soccer", "--classifier", "goToPoseAtBall,goToPoseFarSide", "--episodes", "20", "-q"]
    assert main([*argv, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["schema"] == "tailor.evaluate_classifier/1" and data["episode_seed"] == classifier_seed(0)
    assert [r["scenario"] for r in data["scenarios"]] == ["goToPoseAtBall", "goToPoseFarSide"]
    for row in data["scenarios"]:
        assert row["classifier"] == "goToPose.collision.json" and row["episodes"] == 20
        assert {"correct", "false_success", "always_success", "failed", "table"} <= set(row)
    assert [m["file"].rsplit("/", 1)[-1] for m in data["provenance"]["models"]] == ["goToPose.collision.json"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "always success" in out and "Table 4.4, goToPoseFarSide" in out


def test_evaluate_assertion_on_the_far_side_situations(capsys):
    assert main(["evaluate", "soccer", "--assertion", "--situations", "approach_far_side", "--episodes", "2",
                 "--json", "-q"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["generator"] == "approach_far_side" and data["episodes"] == 2


def _no_work(*args, **kwargs):
    raise AssertionError("work was started although the input was bad")


@pytest.mark.parametrize("argv, status, message", [
    (["--classifier", "kick"], 15, "no experience scenario 'kick'"),
    (["--classifier", "dribbleBall"], 12, "no success classifier dribbleBall.collision.json"),
    (["--classifier", "goToPoseFarSide", "--assertion"], 2, "two experiments"),
    (["--assertion", "--situations", "nowhere"], 2, "--situations 'nowhere' is not a situation generator"),
])
def test_a_bad_scenario_or_situation_name_is_one_line(argv, status, message, capsys, monkeypatch):
    monkeypatch.setattr("tailor.sims.experience.gather", _no_work)
    monkeypatch.setattr("tailor.sims.parallel.run_in_workers", _no_work)
    assert main(["evaluate", "soccer", *argv]) == status
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and re.match(r"^tailor evaluate: error: ", lines[0]) and message in lines[0], lines


def test_an_empty_scenario_name_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as exit:
        main(["evaluate", "soccer", "--classifier", "goToPoseAtBall,"])
    assert exit.value.code == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "expected comma-separated scenario names" in lines[0]
