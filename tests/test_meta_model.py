"""The meta action model (Sec. 5.5.4): labels, the tree learning a planted rule, its JSON, the filter deciding
refine-or-greedy (CLI, API, binding), and a tiny `tailor evaluate --meta` run."""

from __future__ import annotations

import dataclasses
import json
import shutil

import numpy as np
import pytest

import tailor
from tailor.errors import BindingError, ModelFileError
from tailor.planner_bridge.bundled import DOMAINS_DIR
from tailor.cli.main import main
from tailor.refinement.evaluation import experiments
from tailor.refinement.evaluation.meta_episodes import label_gain, outcome_table
from tailor.refinement.evaluation.meta_experiment import fresh_report
from tailor.refinement.learning.meta_learning import CLASSES, confusion, episode_label, learn_meta_model
from tailor.refinement.meta_filter import REFINEMENT_FEATURES, decide, meta_features, window_features
from tailor.refinement.models.action_models import load_action_models
from tailor.refinement.models.decision_tree import LabelTree
from tailor.refinement.models.meta_model import MetaModel, load_meta_model
from tailor.refinement.refine import predicted_durations

SOCCER = DOMAINS_DIR / "soccer"
WINDOW = (("goToPose", "goto"), ("dribbleBall", "dribble"))
POSE = ("v", "vg", "dist", "angle_to", "angle_at")
PATH = POSE + ("path", "arcs", "exact_path")
NAMES = tuple(f"{k}.{a}.{n}" for k, a, names in ((1, "goToPose", PATH + ("detour", "lure_path", "lure_bearing",
                                                                         "lure_turn")), (2, "dribbleBall", PATH))
              for n in names)


def _row(greedy, refined, features=None, ok=(True, True)):
    return {"greedy": greedy, "refined": refined, "greedy_ok": ok[0], "refined_ok": ok[1],
            "signature": [list(w) for w in WINDOW], "feature_names": list(NAMES),
            "features": list(features if features is not None else np.zeros(len(NAMES)))}


def test_labels_use_the_tolerance_evaluate_counts_with():
    assert experiments.EQUAL_BAND == 0.01
    assert [label_gain(g) for g in (0.0101, 0.0099, 0.0, -0.0099, -0.0101)] == \
        ["better", "equal", "equal", "equal", "worse"]
    assert episode_label(_row(10.0, 9.0)) == 0 and episode_label(_row(10.0, 10.05)) == 1
    assert episode_label(_row(10.0, 10.2)) == 2
    assert episode_label(_row(10.0, 9.0, ok=(True, False))) == 2  # refined failed where greedy did not: worse
    assert episode_label(_row(10.0, 9.0, ok=(False, True))) == 0
    assert episode_label(_row(10.0, 9.0, ok=(False, False))) is None


def test_outcome_tables_unfiltered_and_filtered_by_hand():
    rows = [_row(10.0, 8.0), _row(10.0, 11.0), _row(10.0, 10.05), _row(20.0, 15.0), _row(10.0, 9.0, ok=(False, True))]
    u = outcome_table(rows)
    assert (u["scenarios"], u["episodes"], u["refined"], u["failed"]) == (5, 4, 5, 0)
    assert u["improvement"] == pytest.approx(np.mean([0.2, -0.1, -0.005, 0.25]))
    assert (u["better"], u["equal"], u["worse"]) == (2, 1, 1) and u["worse_share"] == 0.25
    f = outcome_table(rows, [True, False, True, True, False])  # the worse one kept greedy: gain 0, "equal"
    assert f["improvement"] == pytest.approx(np.mean([0.2, 0.0, -0.005, 0.25]))
    assert (f["better"], f["equal"], f["worse"], f["refined"], f["failed"]) == (2, 2, 0, 3, 1)
    assert f["mean"] == pytest.approx(np.mean([8.0, 10.0, 10.05, 15.0]))


def test_confusion_matrix_rows_actual_columns_predicted():
    c = confusion(np.array([0, 0, 1, 2]), np.array([0, 2, 1, 0]))
    assert c["counts"] == [[1, 0, 1], [0, 1, 0], [1, 0, 0]]
    assert c["correct"] == 0.5 and c["actual_totals"] == [0.5, 0.25, 0.25]
    assert c["predicted_totals"] == [0.5, 0.25, 0.25]


def _planted(n, rng):
    """Refinement helps where the goToPose distance exceeds 2 m, hurts where it is below 1 m, else no effect."""
    rows = []
    for _ in range(n):
        x = rng.uniform(0, 4, len(NAMES))
        gain = 0.1 if x[2] > 2 else -0.05 if x[2] <= 1 else 0.0
        rows.append(_row(10.0, 10.0 * (1 - gain), x))
    return rows


def test_tree_learns_a_planted_rule_and_the_filter_keeps_only_better():
    rng = np.random.default_rng(3)
    training = learn_meta_model(_planted(400, rng), horizon=2, seed=0)
    model = training.model
    assert model.window == WINDOW and model.feature_names == NAMES and model.equal_band == 0.01
    test = rng.uniform(0, 4, (300, len(NAMES)))
    away = np.abs(test[:, 2] - 2) > 0.1
    away &= np.abs(test[:, 2] - 1) > 0.1
    truth = np.where(test[:, 2] > 2, "better", np.where(test[:, 2] <= 1, "worse", "equal"))
    assert list(model.predict(test[away])) == list(truth[away])
    rules = model.rules_text()
    assert "1.goToPose.dist <=" in rules and "better (" in rules and "worse (" in rules
    report = fresh_report(model, _planted(200, rng))
    assert report["filtered"]["worse"] == 0 < report["unfiltered"]["worse"]
    assert report["filtered"]["improvement"] > report["unfiltered"]["improvement"]
    assert report["floor"]["worse_drop_met"] and report["floor"]["improvement_kept"]
    assert report["confusion"]["correct"] > 0.95


def test_meta_model_json_round_trip_and_bad_files(tmp_path):
    model = learn_meta_model(_planted(200, np.random.default_rng(1)), horizon=2, seed=0).model
    data = json.loads(json.dumps(model.to_json()))
    again = MetaModel.from_json(data, "x.json")
    assert again.to_json() == model.to_json()
    X = np.random.default_rng(2).uniform(0, 4, (50, len(NAMES)))
    assert list(again.predict(X)) == list(model.predict(X))
    folder = tmp_path / "models"
    folder.mkdir()
    with pytest.raises(ModelFileError, match="no meta action model here"):
        load_meta_model(folder)
    for broken, message in ((dict(data, schema="tailor.meta_model/0"), "schema"),
                            (dict(data, feature_names=data["feature_names"][:-1]), "feature_names"),
                            (dict(data, tree=dict(data["tree"], label=[7] * len(data["tree"]["label"]))),
                             "invalid decision tree"),
                            (dict(data, horizon=1), "horizon")):
        (folder / "meta.json").write_text(json.dumps(broken))
        with pytest.raises(ModelFileError, match=message) as err:
            load_meta_model(folder)
        assert str(folder / "meta.json") in str(err.value) and "\n" not in str(err.value)


def _one_leaf(label: str, judges_refinement: bool = False) -> MetaModel:
    counts = np.zeros((1, 3), dtype=np.int64)
    counts[0, CLASSES.index(label)] = 10
    tree = LabelTree(np.array([-1]), np.array([-1]), np.array([-1]), np.array([0.0]),
                     np.array([CLASSES.index(label)]), counts, CLASSES)
    return MetaModel(WINDOW, NAMES + (REFINEMENT_FEATURES if judges_refinement else ()), tree, 2, 0.01)


def _models_with_meta(tmp_path, label: str, judges_refinement: bool = False):
    folder = tmp_path / f"models-{label}-{judges_refinement}"
    shutil.copytree(SOCCER / "models", folder)
    (folder / "meta.json").write_text(json.dumps(_one_leaf(label, judges_refinement).to_json()))
    return folder


@pytest.mark.parametrize("judges_refinement", [False, True])
def test_filter_keeps_greedy_where_the_meta_model_predicts_no_gain(tmp_path, judges_refinement):
    equal = _models_with_meta(tmp_path, "equal", judges_refinement)
    better = _models_with_meta(tmp_path, "better", judges_refinement)
    plain = tailor.refine("soccer", "score", models=equal)  # the filter is off by default
    greedy = tailor.refine("soccer", "score", models=equal, horizon=1, risk=0, neighbourhood=0)  # the filter's greedy: plain h = 1
    kept = tailor.refine("soccer", "score", models=equal, filter=True)
    assert plain.filter is None and plain.chosen != greedy.chosen  # refinement moves the approach heading
    assert kept.chosen == greedy.chosen and kept.predicted_total == greedy.predicted_total
    assert (kept.filter.prediction, kept.filter.refine) == ("equal", False)
    refined = tailor.refine("soccer", "score", models=better, filter=True)
    assert refined.chosen == plain.chosen and refined.filter.refine and refined.to_json()["filter"]["refine"]
    with pytest.raises(tailor.ArgumentTypeError, match="filter must be bool"):
        tailor.refine("soccer", "score", filter="yes")


def test_window_features_are_the_action_models_features():
    greedy = tailor.refine("soccer", "score", horizon=1)
    models = load_action_models(SOCCER / "models", ("dribbleBall", "goToPose"))
    f = window_features(greedy.sequence, models, 2)
    assert f.signature == WINDOW and f.names == NAMES
    first, second = greedy.sequence.actions[:2]
    expected = np.concatenate([models["goToPose"].features(first.values()[None, :])[0],
                               models["dribbleBall"].features(second.values()[None, :])[0]])
    assert np.array_equal(f.values, expected)
    other = window_features(greedy.sequence, models, 1)  # another window: the meta model does not judge it
    decision = decide(_one_leaf("worse"), dataclasses.replace(greedy.refined, sequence=greedy.sequence.__class__(
        greedy.sequence.domain, greedy.sequence.problem, greedy.sequence.actions[:1], greedy.sequence.scene,
        greedy.sequence.simulator)), models)
    assert other.signature == WINDOW[:1] and decision.prediction is None and decision.refine


@pytest.mark.parametrize("judges_refinement", [False, True])
def test_refine_cli_filter_and_bad_meta_file(tmp_path, capsys, judges_refinement):
    equal = _models_with_meta(tmp_path, "equal", judges_refinement)
    assert main(["refine", "soccer", "score", "--models", str(equal), "--filter", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["filter"]["refine"] is False and out["filter"]["prediction"] == "equal"
    assert [p["value"] for p in out["free_parameters"]] == [p["greedy"] for p in out["free_parameters"]]
    assert main(["refine", "soccer", "score", "--models", str(equal), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert "filter" not in out and [p["value"] for p in out["free_parameters"]] != \
        [p["greedy"] for p in out["free_parameters"]]
    (equal / "meta.json").write_text('{"schema": "tailor.meta_model/1", "horizon": 2}')
    assert main(["refine", "soccer", "score", "--models", str(equal), "--filter"]) == 12
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(equal / "meta.json") in err[0] and "Traceback" not in err[0]


def test_binding_filter_option(tmp_path):
    domain = tmp_path / "soccer"
    shutil.copytree(SOCCER, domain)
    (domain / "models" / "meta.json").write_text(json.dumps(_one_leaf("worse").to_json()))
    binding = (domain / "actions.toml").read_text()
    (domain / "actions.toml").write_text(binding + "filter = true\n")  # the last table is [refinement]
    pddl = domain / "domain.pddl"
    greedy = tailor.refine(pddl, "score", horizon=1, risk=0, neighbourhood=0)  # the filter's greedy: plain h = 1
    kept = tailor.refine(pddl, "score")
    assert kept.filter is not None and kept.chosen == greedy.chosen
    assert tailor.refine(pddl, "score", filter=False).chosen != greedy.chosen
    (domain / "actions.toml").write_text(binding + "filter = \"yes\"\n")
    with pytest.raises(BindingError, match="filter must be true or false"):
        tailor.refine(pddl, "score")


def test_evaluate_filter_and_tiny_meta_run(tmp_path, capsys):
    equal = _models_with_meta(tmp_path, "equal", judges_refinement=True)
    assert main(["-q", "evaluate", "soccer", "--episodes", "2", "--oracle-episodes", "0", "--horizon-episodes", "0",
                 "--models", str(equal), "--filter", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["filter"] is True and report["filter_decisions"] == {"refined": 0, "kept_greedy": 2,
                                                                        "not_judged": 0}
    for row in report["situations"]:
        assert row["filter"]["refine"] is False and row["refined"]["simulated"] == row["greedy"]["simulated"]
    out = tmp_path / "out"
    plot = tmp_path / "fig.png"
    assert main(["-q", "evaluate", "soccer", "--meta", "--episodes", "20", "--fresh-episodes", "2", "--seed", "5",
                 "--out", str(out), "--plot", str(plot), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["schema"] == "tailor.evaluate_meta/1" and report["training"]["situations"] == [0, 20]
    assert report["fresh"]["situations"] == [20, 22] and report["fresh"]["unfiltered"]["scenarios"] == 2
    assert len(report["episodes"]["fresh"]) == 2 and plot.stat().st_size > 0
    model = load_meta_model(out / "models")  # beside copies of the action models it judges
    assert model.window == WINDOW and (out / "models" / "goToPose.json").is_file()
    assert model.judges_refinement and report["features"] == list(NAMES + REFINEMENT_FEATURES)
    assert report["rules"] == model.rules_text().splitlines()


def test_simplified_tree_merges_agreeing_leaves():
    counts = np.array([[5, 2, 3], [4, 0, 1], [1, 2, 2], [0, 0, 0]][:3], dtype=np.int64)
    tree = LabelTree(np.array([1, -1, -1]), np.array([2, -1, -1]), np.array([0, -1, -1]), np.array([0.5, 0.0, 0.0]),
                     np.array([0, 0, 0]), counts, CLASSES)
    simple = tree.simplified()
    assert simple.n_leaves == 1 and simple.counts.tolist() == [[5, 2, 3]]
    assert simple.export_text(("a",)) == ": better (5/2/3)"
    X = np.array([[0.0], [1.0]])
    assert list(simple.predict(X)) == list(tree.predict(X)) == ["better", "better"]
    mixed = LabelTree(tree.children_left, tree.children_right, tree.feature, tree.threshold, np.array([0, 0, 2]),
                      counts, CLASSES)
    assert mixed.simplified().n_leaves == 2 and list(mixed.predict(X)) == ["better", "worse"]


def test_meta_options_belong_to_meta(capsys):
    assert main(["evaluate", "soccer", "--episodes", "2", "--fresh-episodes", "3"]) == 2
    assert "belong to --meta" in capsys.readouterr().err
    assert main(["evaluate", "soccer", "--meta", "--episodes", "5"]) == 2
    assert "at least 20" in capsys.readouterr().err


def test_meta_model_must_sit_beside_the_models_it_judges(tmp_path):
    from tailor.errors import OutputFileError
    from tailor.cli.evaluate_meta import _check_companions

    target = tmp_path / "models"
    target.mkdir()
    assert [p.name for p in _check_companions(target, SOCCER / "models")] == sorted(
        p.name for p in (SOCCER / "models").glob("*.json") if p.name != "meta.json")
    shutil.copy(SOCCER / "models" / "goToPose.json", target / "goToPose.json")  # the same file: not copied again
    assert "goToPose.json" not in [p.name for p in _check_companions(target, SOCCER / "models")]
    (target / "goToPose.json").write_text("{}")  # another model of the same name
    with pytest.raises(OutputFileError, match="holds another goToPose.json"):
        _check_companions(target, SOCCER / "models")
    assert _check_companions(SOCCER / "models", SOCCER / "models") == []


def _planted_on_prediction(n, rng):
    """The window's features are noise; refinement helps where it predicts a gain above 3%, hurts below 1%."""
    rows = []
    for _ in range(n):
        x = rng.uniform(0, 4, len(NAMES))
        predicted = rng.uniform(-0.02, 0.1)
        gain = 0.08 if predicted > 0.03 else -0.04 if predicted < 0.01 else 0.0
        row = _row(10.0, 10.0 * (1 - gain), np.concatenate([x, [predicted, 10.0 * predicted]]))
        row["feature_names"] = list(NAMES + REFINEMENT_FEATURES)
        rows.append(row)
    return rows


def test_meta_model_learns_where_refinement_predicts_too_little():
    rng = np.random.default_rng(4)
    model = learn_meta_model(_planted_on_prediction(400, rng), horizon=2, seed=0).model
    assert model.judges_refinement and model.feature_names == NAMES + REFINEMENT_FEATURES
    assert "refinement.predicted" in model.rules_text()
    report = fresh_report(model, _planted_on_prediction(200, rng))
    assert report["floor"]["worse_drop_met"] and report["floor"]["improvement_kept"]
    assert report["filtered"]["worse"] == 0 < report["unfiltered"]["worse"]
    data = json.loads(json.dumps(model.to_json()))
    assert data["schema"] == "tailor.meta_model/2" and MetaModel.from_json(data, "m.json").to_json() == data
    window_only = learn_meta_model(_planted(100, rng), horizon=2, seed=0).model  # the older files still read
    assert not window_only.judges_refinement and window_only.to_json()["schema"] == "tailor.meta_model/1"
    with pytest.raises(ModelFileError, match="feature_names"):  # /2 names the refinement block
        MetaModel.from_json(dict(data, feature_names=list(NAMES)), "m.json")


def test_meta_features_add_refinements_predicted_gain():
    greedy = tailor.refine("soccer", "score", horizon=1)
    refined = tailor.refine("soccer", "score")
    models = load_action_models(SOCCER / "models", ("dribbleBall", "goToPose"))
    f = meta_features(greedy.refined, refined.refined, models, 2)
    t_greedy = sum(predicted_durations(greedy.sequence, models))
    t_refined = sum(predicted_durations(refined.sequence, models))
    assert f.names == NAMES + REFINEMENT_FEATURES and t_refined < t_greedy
    assert np.array_equal(f.values[:len(NAMES)], window_features(greedy.sequence, models, 2).values)
    assert f.values[-2:] == pytest.approx([1 - t_refined / t_greedy, t_greedy - t_refined], abs=1e-12)
    # a meta model that keeps greedy where refinement predicts less than its gain on this problem
    gain = 1 - t_refined / t_greedy
    tree = LabelTree(np.array([1, -1, -1]), np.array([2, -1, -1]), np.array([len(NAMES), -1, -1]),
                     np.array([gain + 0.001, 0.0, 0.0]), np.array([0, 1, 0]),
                     np.array([[10, 10, 0], [0, 10, 0], [10, 0, 0]], dtype=np.int64), CLASSES)
    meta = MetaModel(WINDOW, NAMES + REFINEMENT_FEATURES, tree, 2, 0.01)
    decision = decide(meta, greedy.refined, models, refined.refined)
    assert (decision.prediction, decision.refine) == ("equal", False)
    assert decide(meta, greedy.refined, models, greedy.refined).refine is False  # no predicted gain either
    stricter = MetaModel(WINDOW, NAMES + REFINEMENT_FEATURES, LabelTree(
        tree.children_left, tree.children_right, tree.feature, np.array([gain - 0.001, 0.0, 0.0]), tree.label,
        tree.counts, CLASSES), 2, 0.01)
    assert decide(stricter, greedy.refined, models, refined.refined).refine
    with pytest.raises(ValueError, match="give the refined sequence"):
        decide(meta, greedy.refined, models)


def test_meta_model_for_another_domain_judges_refinements_prediction(tmp_path, capsys):
    """No soccer names: the kitchen's meta model learns from its own window and refinement's prediction, and the
    filter judges a kitchen plan with it."""
    out = tmp_path / "out"
    assert main(["-q", "evaluate", "kitchen", "--meta", "--episodes", "20", "--fresh-episodes", "1", "--seed", "5",
                 "--out", str(out), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    model = load_meta_model(out / "models")
    assert model.judges_refinement and model.window == (("navigate", "route"), ("grip", "grasp"))
    assert report["features"] == list(model.feature_names) and report["features"][-2:] == list(REFINEMENT_FEATURES)
    kitchen = DOMAINS_DIR / "kitchen" / "domain.pddl"
    judged = tailor.refine(kitchen, "scenario1", models=out / "models", filter=True)
    assert judged.filter.prediction in CLASSES and judged.filter.leaf is not None
