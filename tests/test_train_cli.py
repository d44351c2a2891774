"""`tailor train`: files written, report printed, errors as one line, nothing half-written on Ctrl-C."""

from __future__ import annotations

import base64
import json
import os
import re
import stat

import numpy as np
import pytest

import synthetic_episodes
from tailor.refinement.models.action_models import load_action_models, load_collision_model
from tailor.cli.main import main
from tailor.refinement.models.features import compute_features
from synthetic_episodes import random_params
from test_reports import assert_self_contained

UMASK = os.umask(0o022)
os.umask(UMASK)

EXPECTED_FILES = {
    "models/goToPose.json", "models/approachBall.json", "models/dribbleBall.json", "models/goToPose.collision.json",
    "models/goToPosition.json",
    "training/report.json", "training/report.txt", "training/report.html", "training/mae_vs_n_i.png",
    "training/mae_vs_episodes.png", "training/feature_spaces.png",
    "training/angle_at_polar.png", "training/goToPose.success_region.png",
}


def files_under(root) -> set[str]:
    """The files under root, but for the kept experience (OUT/experience/, tests/test_experience_shards.py)."""
    return {str(p.relative_to(root)) for p in root.rglob("*")
            if p.is_file() and p.relative_to(root).parts[0] != "experience"}


def check_outputs(out, report: dict, episodes: int, fresh: int) -> None:
    assert files_under(out) == EXPECTED_FILES
    assert json.loads((out / "training" / "report.json").read_text()) == report
    models = load_action_models(out / "models")
    assert sorted(models) == ["approachBall", "dribbleBall", "goToPose", "goToPosition"]
    params = random_params(20, seed=1)
    for action, model in models.items():
        row = report["models"][action]
        assert set(row) >= {"episodes", "mean_duration", "mae", "mae_hgb", "leaves"}
        extra = sum(chain["episodes"] for chain in report["subgoal_experience"] if chain["action"] == action)
        assert 8 <= row["episodes"] <= episodes + extra and row["leaves"] == model.duration.n_leaves_
        assert model.report == row and model.n_i == row["n_i"]
        assert np.all(np.isfinite(model.predict_duration(params)))
    # dribbleBall also learned from the subgoals refinement chose in random `score` situations, goToPose from
    # those in random `waypoints` situations (three way-points after the first in each) (Sec. 8.1)
    score, waypoints = report["subgoal_experience"]
    assert (score["generator"], score["action"], waypoints["generator"], waypoints["action"]) == (
        "score", "dribbleBall", "waypoints", "goToPose")
    assert score["situations"] == score["episodes"] == round(0.5 * episodes)
    assert waypoints["situations"] == round(episodes / 6) and waypoints["episodes"] == 3 * waypoints["situations"]
    assert score["rounds"] == min(3, score["situations"]) and waypoints["rounds"] == min(3, waypoints["situations"])
    collision = load_collision_model(out / "models" / "goToPose.collision.json")
    assert (report["schema"], report["domain"], report["simulator"]) == ("tailor.training_report/4", "soccer", "soccer")
    assert list(report["classifiers"]) == ["goToPose"]
    c = report["classifiers"]["goToPose"]
    assert c["action"] == "goToPose"
    assert 0.0 <= c["accuracy"] <= 1.0 and 0.0 <= c["false_success"] <= 1.0
    assert c["fresh_episodes"] == 2 * fresh  # of each of its scenarios: at the ball and from the far side
    assert collision.predict_success(params).dtype == bool
    assert collision.feature_space == "pose_walls"  # the soccer robot's own space: it sees the walls
    text = (out / "training" / "report.txt").read_text()
    for action in models:
        assert f"Rules of {action}" in text
    assert "predicted Success" in text and "observed Fail" in text
    for png in ("mae_vs_n_i", "mae_vs_episodes", "feature_spaces", "angle_at_polar", "goToPose.success_region"):
        assert (out / "training" / f"{png}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # Fig. 4.3 per action: the raw parameters, Table 4.1's pose row, the binding's expert space and the generated
    # one, beside gradient boosting on the raw parameters; in the report's text and HTML tables
    for action, row in report["models"].items():
        comparison = row["space_comparison"]
        assert [r["space"] for r in comparison["rows"]] == ["raw", "generic", "expert", "auto"]
        assert all(r["mae"] > 0 for r in comparison["rows"]) and comparison["mae_hgb_raw"] > 0
        assert row["feature_selection"]["selected"] and row["feature_selection"]["chosen"] in ("auto", "goto",
                                                                                                "approach", "dribble",
                                                                                                "position", "pose",
                                                                                                "pose_delta",
                                                                                                "pose_walls")
    assert "Feature spaces (Fig. 4.3)" in text
    # the HTML report: one file, nothing external, every action's row, every figure embedded, rules collapsible
    page = assert_self_contained((out / "training" / "report.html").read_text(encoding="utf-8"))
    assert {row[0] for row in page.rows if row} >= set(report["models"])
    images = [base64.b64decode(attrs["src"].split(",", 1)[1]) for tag, attrs in page.tags if tag == "img"]
    assert images == [(out / "training" / f"{png}.png").read_bytes() for png in
                      ("mae_vs_n_i", "mae_vs_episodes", "feature_spaces", "angle_at_polar",
                       "goToPose.success_region")]
    # the rules of every model: each duration model, each further measure's (Ch. 8.1) and the classifier
    assert page.details == sum(1 + len(model.measures) for model in models.values()) + 1
    assert report["measures"] == {action: {name: m.report for name, m in model.measures.items()}
                                  for action, model in models.items()}
    assert all(set(model.measures) == {"energy", "error"} for model in models.values())
    assert sorted(report["files"]) == sorted(EXPECTED_FILES)
    for name in EXPECTED_FILES:  # a new file's permissions (the tests run under umask 022), not mkstemp's 0600
        assert stat.S_IMODE((out / name).stat().st_mode) == 0o666 & ~UMASK, name


def test_train_soccer_end_to_end_in_the_simulator(tmp_path, capsys):
    """The real pipeline on 24 episodes per scenario (n_i candidates cut down to keep it quick)."""
    code = main(["train", "soccer", "--episodes", "24", "--fresh-episodes", "20", "--n-i", "1,3", "--seed", "1",
                 "--out", str(tmp_path), "--json"])
    assert code == 0
    report = json.loads(capsys.readouterr().out)
    check_outputs(tmp_path, report, 24, 20)
    assert {p.name for p in (tmp_path / "experience").iterdir()} == {  # the episodes are kept, with their seeds
        "goToPose.seed1.0-24.npz", "approachBall.seed1.0-24.npz", "dribbleBall.seed1.0-24.npz",
        "goToPoseAtBall.seed1.0-24.npz", "goToPoseAtBall.seed7919001.0-20.npz", "goToPoseFarSide.seed1.0-24.npz",
        "goToPoseFarSide.seed7919001.0-20.npz", "goToPosition.seed1.0-24.npz"}
    assert [row["n_i"] for row in report["models"]["goToPose"]["n_i_curve"]] == [1, 3]


def test_train_is_reproducible_and_prints_the_table(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr("tailor.sims.experience.gather", synthetic_episodes.gather)
    args = ["train", "soccer", "--episodes", "24", "--fresh-episodes", "20", "--n-i", "1,3", "--out"]
    assert main([*args, str(tmp_path / "a")]) == 0
    captured = capsys.readouterr()
    printed = captured.out
    assert printed.startswith("Action models of domain soccer (simulator soccer, seed 0, 24 episodes per scenario;")
    for name in EXPECTED_FILES:  # every file written is named
        assert f"  {tmp_path / 'a' / name}" in printed
    # the short summary: a row per action, no rules (they are in report.txt and report.html)
    assert "Rules of" not in printed and len(printed.splitlines()) < 30
    report = json.loads((tmp_path / "a" / "training" / "report.json").read_text())
    for action, row in report["models"].items():
        assert re.search(rf"^  {action} +{row['episodes']} +{row['examples']} +{row['mae']:.3f} ", printed, re.M)
    assert "success classifier of goToPose: " in printed
    # 24 episodes are too few to trust: warnings on stderr (and in the report files), not on stdout
    assert report["warnings"] and "too small to trust" not in printed
    assert [line for line in captured.err.splitlines() if "too small to trust" in line] == [
        f"tailor train: warning: this run is too small to trust: {w}" for w in report["warnings"]]
    assert "too small to trust" in (tmp_path / "a" / "training" / "report.html").read_text()
    assert "too small to trust" in (tmp_path / "a" / "training" / "report.txt").read_text()
    assert main([*args, str(tmp_path / "b")]) == 0
    for name in ("goToPose.json", "approachBall.json", "dribbleBall.json", "goToPose.collision.json"):
        assert (tmp_path / "a" / "models" / name).read_text() == (tmp_path / "b" / "models" / name).read_text()
    model = load_action_models(tmp_path / "a" / "models")["goToPose"]
    assert model.duration.predict(compute_features("goto", random_params(5, 2))).shape == (5,)


def test_only_learns_the_named_models(tmp_path, monkeypatch, capsys):
    """--only trains a model new to a domain without retraining (or touching) the others."""
    monkeypatch.setattr("tailor.sims.experience.gather", synthetic_episodes.gather)
    assert main(["train", "soccer", "--only", "goToPosition", "--episodes", "24", "--n-i", "1", "--json",
                 "--out", str(tmp_path)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert list(report["models"]) == ["goToPosition"] and report["classifiers"] == {}
    assert report["subgoal_experience"] == []
    assert {p for p in files_under(tmp_path) if p.startswith("models/")} == {"models/goToPosition.json"}
    assert main(["train", "soccer", "--only", "goToPositon", "--out", str(tmp_path / "x")]) == 11
    err = capsys.readouterr().err.strip()
    assert err.endswith("did you mean 'goToPosition'?") and len(err.splitlines()) == 1
    assert not (tmp_path / "x").exists()


def test_a_folder_where_a_model_file_goes_is_named(tmp_path, monkeypatch, capsys):
    """The error names the folder in the way (not the last file of the run) and nothing is written."""
    monkeypatch.setattr("tailor.sims.experience.gather", synthetic_episodes.gather)
    (tmp_path / "models" / "goToPosition.json").mkdir(parents=True)
    assert main(["train", "soccer", "--only", "goToPosition", "--episodes", "24", "--n-i", "1",
                 "--out", str(tmp_path)]) == 16
    err = capsys.readouterr().err.strip().splitlines()[-1]  # (after the experience it kept)
    assert err == f"tailor train: error: {tmp_path / 'models' / 'goToPosition.json'}: cannot write: Is a directory"
    assert not (tmp_path / "training").exists()


def test_only_a_model_with_subgoal_experience_refines_with_the_domains_others(tmp_path):
    """--only dribbleBall: its subgoal experience refines `score` situations, which need goToPose (the
    approach): the domain's own model of it, or OUT's where OUT holds one; never the model being learned."""
    from tailor.planner_bridge import resolve_domain_dir
    from tailor.cli.train import _companions, _only
    from tailor.refinement.learning.recipe import load_recipe

    domain = resolve_domain_dir("soccer")
    recipe = _only(load_recipe(domain), ("dribbleBall",))
    companions = _companions(recipe, tmp_path / "out")
    assert set(companions) == {"goToPose", "approachBall", "goToPosition"}
    assert companions["goToPose"].source == str(domain / "models" / "goToPose.json")
    (tmp_path / "out" / "models").mkdir(parents=True)
    (tmp_path / "out" / "models" / "goToPose.json").write_bytes((domain / "models" / "goToPose.json").read_bytes())
    assert set(_companions(recipe, tmp_path / "out")) == {"goToPose"}
    assert _companions(_only(load_recipe(domain), ("goToPosition",)), tmp_path / "out") == {}


def test_unknown_domain_is_one_line(capsys, tmp_path):
    assert main(["train", "hockey", "--out", str(tmp_path)]) == 3
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(
        "tailor train: error: hockey: no such domain folder, domain file or bundled domain (bundled: ")
    assert "soccer" in err[0]
    assert not any(tmp_path.iterdir())


def test_domain_without_a_training_recipe_is_one_line(capsys, tmp_path):
    domain = tmp_path / "delivery"
    domain.mkdir()
    (domain / "domain.pddl").write_text("(define (domain delivery) (:predicates (at ?p)) "
                                        "(:action drive :parameters (?a ?b) :precondition (at ?a) :effect (at ?b)))")
    (domain / "actions.toml").write_text('schema = 2\nsimulator = "soccer"\n'
                                         '[actions.drive]\nexecutable = "goToPose"\nobserved = 0\ninternal = 1\n')
    out = tmp_path / "out"
    assert main(["train", str(domain), "--out", str(out)]) == 11
    assert capsys.readouterr().err.strip() == (
        f"tailor train: error: {domain / 'actions.toml'}: [training] missing: the domain's binding says nothing "
        "about what to learn (add a [training] table)")
    assert not out.exists()


@pytest.mark.parametrize("argv, message", [
    (["--episodes", "5"], "argument --episodes: must be at least 8: '5'"),
    (["--jobs", "0"], "argument --jobs: must be at least 1: '0'"),
])
def test_bad_numbers_are_one_line(argv, message, capsys, tmp_path):
    with pytest.raises(SystemExit) as exit:  # a usage error, status 2 in every command (README)
        main(["train", "soccer", *argv, "--out", str(tmp_path)])
    assert exit.value.code == 2
    assert capsys.readouterr().err.strip() == f"tailor train: error: {message} (see `tailor train --help`)"


def test_interrupt_while_writing_leaves_nothing_half_written(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr("tailor.sims.experience.gather", synthetic_episodes.gather)
    (tmp_path / "models").mkdir()
    (tmp_path / "models" / "goToPose.json").write_text("old")

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("tailor.refinement.learning.plots.plot_duration_curve", interrupted)  # a figure being drawn
    code = main(["train", "soccer", "--episodes", "24", "--fresh-episodes", "20", "--n-i", "1", "--out", str(tmp_path)])
    assert code == 130
    assert capsys.readouterr().err.strip().endswith("tailor train: interrupted")
    assert files_under(tmp_path) == {"models/goToPose.json"}  # staged files removed, the old model untouched
    assert (tmp_path / "models" / "goToPose.json").read_text() == "old"


def test_black_box_learns_on_generated_features_with_no_space_of_the_simulator(tmp_path, monkeypatch, capsys):
    """--black-box: the binding's space ("position") is not used and the simulator's own spaces do not compete."""
    monkeypatch.setattr("tailor.sims.experience.gather", synthetic_episodes.gather)
    argv = ["train", "soccer", "--only", "goToPosition", "--episodes", "40", "--n-i", "1", "--no-compare", "--json"]
    assert main([*argv, "--out", str(tmp_path / "expert")]) == 0
    expert = json.loads(capsys.readouterr().out)["models"]["goToPosition"]
    assert "feature_selection" not in expert  # the binding's space, no selection run
    assert json.loads((tmp_path / "expert/models/goToPosition.json").read_text())["feature_space"] == "position"
    assert main([*argv, "--black-box", "--out", str(tmp_path / "black")]) == 0
    black = json.loads(capsys.readouterr().out)["models"]["goToPosition"]
    assert list(black["feature_selection"]["candidate_sets"]) == ["generated"]
    assert black["feature_selection"]["chosen"] == "auto"
    model = json.loads((tmp_path / "black/models/goToPosition.json").read_text())
    assert model["feature_space"] == "auto" and "phig" in model["expressions"]["parameters"]
