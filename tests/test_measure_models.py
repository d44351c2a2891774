"""Measures besides the duration (Ch. 8.1), learned and refined: a model tree per declared measure in the action
model's file (schema 2, schema-1 files still load), trained by the duration's protocol and reported with its
held-out MAE; refinement minimizing a weighted sum of measures and keeping limits on them, checked on models
whose optima are known: the tests fail where a weight is ignored (or taken as 1), a measure dropped, or a limit
not kept."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
import synthetic_episodes
from rule_models import RuleModel, identity, rule
from tailor.cli.main import main
from tailor.errors import BindingError, DataError, ModelFileError
from tailor.refinement.binding import parse_binding
from tailor.refinement.learning.recipe import recipe_from_binding
from tailor.refinement.learning.report import format_report, summary_lines
from tailor.refinement.learning.training import measure_episodes, train_domain
from tailor.refinement.models.action_models import (
    ACTION_MODEL_SCHEMA,
    MEASURES_SCHEMA,
    ActionModel,
    MeasureModel,
    load_action_models,
    write_json_atomic,
)
from tailor.refinement.models.features import compute_features, feature_names
from tailor.refinement.models.model_tree import ModelTree
from tailor.refinement.objective_grammar import MeasureBound, parse_objective
from tailor.refinement.optimizers import FreeParameter, Objective, Term, brute_force, certified, optimize
from tailor.refinement.optimizers.objective import Scaled, scaled
from tailor.refinement.refine import refine

ROOT = Path(__file__).resolve().parent.parent
INF = np.inf


# --- the models of a constructed soccer task -----------------------------------------------------------------
# The score plan (approach the ball at pos2, dribble it to pos3) leaves the heading and the speed at pos2 free
# (v in [0, 0.3]). Over the pose features (v, vg, dist, angle_to, angle_at):
#   duration: a travel time, + 5 s per m/s arrived at (vg), - 8 s per m/s started with (v): over both actions
#             -3 s per m/s at pos2: the duration alone wants the fastest, 0.3 m/s;
#   energy:   goToPose + 20 J per m/s arrived at: duration + w * energy wants 0.3 m/s for w < 0.15, 0 beyond;
#   error:    goToPose 1 cm + 20 cm per m/s arrived at (7 cm at 0.3 m/s), dribbleBall 2 cm.
def _travel_time(F):
    v, vg, dist, angle_to, angle_at = F.T
    return 3.0 + dist / 0.8 + 0.9 * angle_to + 0.6 * np.abs(angle_at) - 8.0 * v + 5.0 * vg


def _energy(F, arriving: bool):
    return 2.0 + 5.0 * F[:, 2] + (20.0 * F[:, 1] if arriving else 0.0)


def _error(F, arriving: bool):
    return 0.01 + 0.2 * F[:, 1] if arriving else np.full(len(F), 0.02)


def _pose_model(action: str, seed: int, arriving: bool, n: int = 6000) -> ActionModel:
    rng = np.random.default_rng(seed)
    params = np.column_stack([
        rng.uniform(-3, 3, n), rng.uniform(-2, 2, n), rng.uniform(-math.pi, math.pi, n), rng.uniform(0, 0.3, n),
        rng.uniform(-3, 3, n), rng.uniform(-2, 2, n), rng.uniform(-math.pi, math.pi, n), rng.uniform(0, 0.3, n),
    ])
    F = compute_features("pose", params)

    def fitted(y):
        return ModelTree(min_samples_leaf=20).fit(F, y)

    def measure(name, unit, y):
        return MeasureModel(name, unit, fitted(y), 1, {"range": [float(y.min()), float(y.max())], "mae": 0.0})

    return ActionModel(action, "pose", feature_names("pose"), fitted(_travel_time(F)), n_i=1,
                       report={"duration_range": [0.0, 30.0]},
                       measures={"energy": measure("energy", "J", _energy(F, arriving)),
                                 "error": measure("error", "m", _error(F, arriving))})


@pytest.fixture(scope="module")
def models():
    goto = _pose_model("goToPose", 2, arriving=True)
    return {"approachBall": goto, "goToPose": goto, "dribbleBall": _pose_model("dribbleBall", 1, arriving=False)}


@pytest.fixture(scope="module")
def score():
    from test_refine import SCORE, _sequence

    return _sequence("score_plan.json", SCORE)


def _speed(refined) -> float:
    return next(p.value for a in refined.sequence.actions for p in a.params if p.id == "pos2.v")


# --- model files ---------------------------------------------------------------------------------------------
def test_an_action_model_file_holds_its_measures_and_reads_back_predicting_the_same(models, tmp_path):
    model = models["goToPose"]
    write_json_atomic(tmp_path / "goToPose.json", model.to_json())
    data = json.loads((tmp_path / "goToPose.json").read_text())
    assert data["schema"] == MEASURES_SCHEMA and set(data["measures"]) == {"energy", "error"}
    assert data["measures"]["energy"]["unit"] == "J" and data["measures"]["energy"]["rules"]  # readable rules
    loaded = load_action_models(tmp_path)["goToPose"]
    assert loaded.measure_names == ("duration", "energy", "error")
    params = np.random.default_rng(3).uniform(0, 0.3, (50, 8))
    for name in loaded.measure_names:
        np.testing.assert_array_equal(loaded.predict_measure(name, params), model.predict_measure(name, params))
    assert loaded.to_json() == model.to_json()


def test_a_file_of_the_duration_alone_stays_schema_1_and_old_files_load(models, tmp_path):
    plain = ActionModel("goToPose", "pose", feature_names("pose"), models["goToPose"].duration, n_i=1)
    assert plain.to_json()["schema"] == ACTION_MODEL_SCHEMA and "measures" not in plain.to_json()
    for name in ("soccer", "arm"):  # the bundled files of the duration alone
        for model in load_action_models(ROOT / "domains" / name / "models").values():
            assert model.measure_names[0] == "duration"
    with pytest.raises(ModelFileError, match=r"^m.json: the action model of goToPose has no model of 'energy' "
                                             r"\(it predicts duration\): declare it in the binding's "
                                             r"\[training.models.goToPose\] measures"):
        ActionModel.from_json(plain.to_json(), "m.json").tree_of("energy")


def _tree_of_three_features() -> dict:
    X = np.random.default_rng(0).uniform(0, 1, (40, 3))
    return ModelTree(min_samples_leaf=10).fit(X, X.sum(axis=1)).to_json()


@pytest.mark.parametrize("mutate, message", [
    (lambda d: d.update(schema=ACTION_MODEL_SCHEMA), "'measures' needs schema 'tailor.action_model/2'"),
    (lambda d: d.update(schema="tailor.action_model/3"),
     "schema is 'tailor.action_model/3', expected 'tailor.action_model/1' or 'tailor.action_model/2'"),
    (lambda d: d.update(measures={}), "'measures' must be an object of measure -> model"),
    (lambda d: d["measures"].update(duration=d["measures"]["energy"]), "'measures' names 'duration'"),
    (lambda d: d["measures"]["energy"].update(n_i=0), "'measures.energy.n_i' must be a positive integer"),
    (lambda d: d["measures"]["energy"].update(tree=[1]), "'measures.energy.tree' must be a model tree object"),
    (lambda d: d["measures"]["energy"]["report"].update(range=[2, 1]), "'measures.energy.report.range' must be"),
    (lambda d: d["measures"]["error"].update(tree=_tree_of_three_features()), "error model tree takes 3 features"),
])
def test_malformed_measures_are_one_line_naming_the_file(models, tmp_path, mutate, message):
    data = json.loads(json.dumps(models["goToPose"].to_json()))
    mutate(data)
    (tmp_path / "goToPose.json").write_text(json.dumps(data))
    with pytest.raises(ModelFileError, match=f"goToPose.json: {message}".replace("(", r"\(").replace(")", r"\)")):
        load_action_models(tmp_path)


def test_an_absurd_measure_prediction_is_refused_as_a_broken_file(models):
    energy = models["goToPose"].measures["energy"]
    low, high = energy.plausible_range()
    assert energy.check(high, "step 1", "m.json") == high
    assert energy.check(low, "step 1", "m.json") == 0.0  # plausible, below 0: clipped, as a duration
    with pytest.raises(ModelFileError, match=r"^m.json: step 1: the energy model predicts 1e\+06 J, outside the "
                                             r"plausible"):
        energy.check(1e6, "step 1", "m.json")
    with pytest.raises(ModelFileError, match="predicts nan J: its coefficients are broken"):
        energy.check(float("nan"), "step 1", "m.json")


# --- the recipe and training ---------------------------------------------------------------------------------
def _recipe(measures):
    models = {"goToPose": {"scenario": "goToPose", "feature_space": "pose", "measures": measures}}
    binding = parse_binding({"schema": 2, "simulator": "soccer", "training": {"models": models}}, "b.toml")
    return recipe_from_binding(binding, ROOT / "domains" / "soccer")


def test_the_recipe_declares_measures_per_model():
    assert _recipe(["energy", "duration", "error"]).models[0].measures == ("duration", "energy", "error")
    assert _recipe(["duration"]).models[0].further_measures == ()
    for measures, message in ((["duration", "enrgy"], (r"'enrgy' is not a measure of simulator 'soccer' \(known: "
                                                       r"duration, energy, error, heading_error\); did you mean 'energy'")),
                              (["energy"], 'must include "duration"'),
                              (["duration", "duration"], "names a measure twice"),
                              ("energy", "must be a non-empty list"), ([], "must be a non-empty list"),
                              (["duration", "ball_x"], "'ball_x' is not a measure")):
        with pytest.raises(BindingError, match=f"^b.toml: \\[training\\] models.goToPose measures.*{message}"):
            _recipe(measures)


def test_a_measure_learns_from_the_first_example_and_needs_every_success_to_report_it():
    episodes = [synthetic_episodes.synthetic_episode("goToPose", seed) for seed in range(5)]
    learned = measure_episodes("goToPose", episodes, "energy")
    assert [e.duration for e in learned] == [e.measures["energy"] for e in episodes]
    assert all(len(e.t) == 1 and e.t[0] == 0.0 for e in learned)
    old = [synthetic_episodes.synthetic_episode("goToPose", 9)]
    old = [type(old[0])(*[getattr(old[0], f) for f in ("action", "params", "t", "state", "columns", "outcome",
                                                         "duration", "seed")])]  # written before measures
    with pytest.raises(DataError, match=r"goToPose: 1 of its 1 successful episodes report no measure 'energy' "
                                        r"\(experience gathered, or a log written, before measures"):
        measure_episodes("goToPose", old, "energy")


def test_training_fits_a_tree_per_measure_and_the_report_lists_each_held_out_mae(tmp_path):
    recipe = _recipe(["duration", "energy", "error"])
    report = train_domain(recipe, 160, seed=0, out=tmp_path, progress=False, gather=synthetic_episodes.gather,
                          n_i_candidates=(1, 3), episode_fractions=(0.5, 1.0))
    model = load_action_models(tmp_path / "models")["goToPose"]
    assert model.measure_names == ("duration", "energy", "error")
    rows = report["measures"]["goToPose"]
    for name, truth, unit in (("energy", synthetic_episodes.synthetic_energy, "J"),
                              ("error", synthetic_episodes.synthetic_error, "m")):
        row = rows[name]
        assert (row["measure"], row["unit"], row["n_i"], row["test_episodes"]) == (name, unit, 1, 40)
        assert row["mae"] > 0 and row["mae_hgb"] > 0 and row["range"][0] <= row["mean"] <= row["range"][1]
        assert row == model.measures[name].report
        # it learned the measure: far closer than its spread around the mean
        params = synthetic_episodes.random_params(200, 5)
        params[:, 7] = np.random.default_rng(6).uniform(0, 0.5, 200)
        error = np.abs(model.predict_measure(name, params) - truth(params))
        assert np.median(error) < 0.25 * np.std(truth(params))
    text = format_report(report, {"goToPose": model}, {})
    assert "Models of further measures (Ch. 8.1)" in text
    for name in ("energy", "error"):
        assert f"goToPose      {name:<14}" in text and f"Rules of goToPose {name} (" in text
    summary = "\n".join(summary_lines(report))
    assert f"goToPose measures: energy MAE {rows['energy']['mae']:.4g} J" in summary
    assert f"error MAE {rows['error']['mae']:.4g} m" in summary
    # the seconds of the duration model's protocol and of the measures' models are given apart
    seconds = report["model_seconds"]["goToPose"]
    assert seconds["protocol"] > 0 and seconds["measures"] > 0


def test_a_model_of_the_duration_alone_spends_no_time_on_measures(tmp_path):
    report = train_domain(_recipe(["duration"]), 160, seed=0, out=tmp_path, progress=False,
                          gather=synthetic_episodes.gather, n_i_candidates=(1,), episode_fractions=(1.0,))
    seconds = report["model_seconds"]["goToPose"]
    assert seconds["protocol"] > 0 and seconds["measures"] == 0.0


# --- refinement: weights -------------------------------------------------------------------------------------
def test_the_duration_alone_takes_the_fastest_arrival(models, score):
    refined = refine(score, models, horizon=2, method="analytic")
    assert _speed(refined) == pytest.approx(0.3, abs=0.005)
    assert refined.objective.plain and not refined.violations
    assert [set(m) for m in refined.measures] == [{"duration", "energy", "error"}] * 2
    assert refined.measures[0]["duration"] == pytest.approx(refined.predicted[0])


@pytest.mark.parametrize("method", ["analytic", "certified", "ga"])
def test_the_energy_weight_decides_the_arrival_speed(models, score, method):
    """3 s per m/s saved against 20 J per m/s spent: a weight of 0.05 keeps the fastest arrival (ignoring the
    weight, i.e. taking it as 1, would not), 0.3 chooses the slowest (dropping the measure would not)."""
    light = refine(score, models, horizon=2, method=method, seed=1,
                   objective=parse_objective("duration + 0.05*energy"))
    heavy = refine(score, models, horizon=2, method=method, seed=1,
                   objective=parse_objective("duration + 0.3*energy"))
    assert _speed(light) == pytest.approx(0.3, abs=0.02)
    assert _speed(heavy) == pytest.approx(0.0, abs=0.02)
    assert heavy.measure_total("energy") < light.measure_total("energy") - 4.0  # 20 J/(m/s) * 0.28 m/s less
    assert heavy.predicted_total > light.predicted_total  # ... for a slower execution
    # the window's cost is the weighted sum of the actions' predictions at the choice
    window = heavy.windows[0]
    assert window.cost == pytest.approx(heavy.predicted_total + 0.3 * heavy.measure_total("energy"), rel=1e-6)


def _weighted_objective(weight: float, bounds: bool = True) -> Objective:
    """x in [0, 1]: a duration falling to its cheapest 2.0 at the split 0.5, an energy of 4 J per unit of x."""
    duration = RuleModel([rule([-INF], [0.5], [-2.0], 3.0), rule([0.5], [INF], [1.0], 1.5)])
    energy = RuleModel([rule([-INF], [INF], [4.0], 0.0)])
    enclosure = (lambda lo, hi: (lo, hi)) if bounds else None
    terms = (Term(scaled(duration, 1.0), identity, feature_bounds=enclosure),
             Term(scaled(energy, weight), identity, feature_bounds=enclosure))
    return Objective((FreeParameter("x", 0.0, 1.0),), terms)


@pytest.mark.parametrize("method", ["analytic", "certified", "ga", "sample"])
@pytest.mark.parametrize("weight, best_x, best_cost", [(0.1, 0.5, 2.2), (0.7, 0.0, 3.0)])
def test_every_optimizer_minimizes_the_weighted_sum_as_brute_force_finds(method, weight, best_x, best_cost):
    objective = _weighted_objective(weight)
    result = optimize(objective, method=method, seed=2)
    grid = brute_force(objective, 2001)
    assert grid.values[0] == pytest.approx(best_x, abs=1e-3) and grid.cost == pytest.approx(best_cost, abs=1e-3)
    tolerance = {"analytic": 1e-6, "certified": certified.tolerance_of(best_cost)}.get(method, 0.05)  # its own
    assert result.method == method
    assert result.values[0] == pytest.approx(best_x, abs=0.02 if tolerance == 0.05 else 1e-3)
    assert result.cost == pytest.approx(best_cost, abs=tolerance)
    if method in ("analytic", "certified"):  # its bound is a bound of the weighted sum: no choice below it
        assert result.lower_bound <= grid.cost + 1e-9 and result.gap <= tolerance + 1e-9


def test_a_scaled_model_scales_predictions_and_rules_and_refuses_a_negative_weight():
    model = RuleModel([rule([-INF], [0.5], [-2.0], 3.0), rule([0.5], [INF], [1.0], 1.5)])
    half = scaled(model, 0.5)
    assert scaled(model, 1.0) is model and scaled(model, 0.5) is half  # one per weight: the caches last
    X = np.array([[0.2], [0.9]])
    np.testing.assert_allclose(half.predict(X), 0.5 * model.predict(X))
    assert [(r.coef[0], r.intercept) for r in half.rules()] == [(-1.0, 1.5), (0.5, 0.75)]
    assert [(r.lower[0], r.upper[0]) for r in half.rules()] == [(r.lower[0], r.upper[0]) for r in model.rules()]
    with pytest.raises(ValueError, match="weight must be a finite number >= 0"):
        Scaled(model, -0.3)


# --- refinement: limits --------------------------------------------------------------------------------------
@pytest.mark.parametrize("method", ["auto", "ga"])
def test_a_limit_that_binds_keeps_every_action_within_it(models, score, method):
    free = refine(score, models, horizon=2, method=method, seed=4)
    assert free.measures[0]["error"] > 0.06  # the fastest arrival misses by 7 cm
    kept = refine(score, models, horizon=2, method=method, seed=4, limits=(MeasureBound("error", 0.04),))
    assert not kept.violations
    assert all(m["error"] <= 0.04 for m in kept.measures)  # dropping the limit would choose 0.3 m/s (7 cm)
    assert _speed(kept) <= 0.15 + 1e-6 and kept.predicted_total >= free.predicted_total - 1e-9
    if method == "ga":  # near the best the limit leaves: the duration wants the fastest arrival it allows
        assert _speed(kept) == pytest.approx(0.15, abs=0.02)
    greedy = refine(score, models, horizon=1, method=method, seed=4, limits=(MeasureBound("error", 0.04),))
    assert all(m["error"] <= 0.04 for m in greedy.measures)  # an action beyond the horizon keeps it too


def test_a_limit_no_subgoal_can_keep_is_reported_and_kept_as_closely_as_possible(models, score):
    # the approach ends at least 1 cm off (arriving at rest), the dribble 2 cm whatever is chosen at pos2
    refined = refine(score, models, horizon=2, seed=4, limits=(MeasureBound("error", 0.005),))
    approach, dribble = refined.violations
    assert (approach.step, approach.action, approach.measure, approach.bound) == (1, "goToPose", "error", 0.005)
    # kept near the least error attainable (1 cm arriving at rest; within 5% of its 6 cm spread), not at the
    # fastest arrival's 7 cm: an unkeepable limit does not leave the choice to chance
    assert 0.01 - 1e-3 <= approach.predicted <= 0.01 + 0.05 * 0.06 + 1e-3
    assert _speed(refined) <= 0.02
    assert (dribble.step, dribble.measure) == (2, "error") and dribble.predicted == pytest.approx(0.02, abs=1e-3)
    assert "step 1 goToPose: no subgoal within its ranges keeps the predicted error <= 0.005" in approach.reason()
    assert "the least attainable" in refined.windows[0].note
    # a limit only the dribble breaks: the approach keeps its own, and is otherwise as fast as it allows
    partly = refine(score, models, horizon=2, method="ga", seed=4, limits=(MeasureBound("error", 0.015),))
    assert [(v.step, v.measure) for v in partly.violations] == [(2, "error")]
    assert partly.measures[0]["error"] <= 0.015 and _speed(partly) == pytest.approx(0.025, abs=0.01)


def test_a_measure_without_a_model_is_a_one_line_model_file_error(models, score):
    plain = {a: ActionModel(a, "pose", feature_names("pose"), m.duration, n_i=1, source=f"{a}.json")
             for a, m in models.items()}
    with pytest.raises(ModelFileError, match=r"^goToPose.json: the action model of goToPose has no model of "
                                             r"'energy'"):
        refine(score, plain, objective=parse_objective("duration + energy"))
    with pytest.raises(ModelFileError, match="has no model of 'error'"):
        refine(score, plain, limits=(MeasureBound("error", 0.1),))


# --- the command line ----------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def model_folder(models, tmp_path_factory):
    folder = tmp_path_factory.mktemp("measure_models")
    for action in ("goToPose", "dribbleBall"):
        write_json_atomic(folder / f"{action}.json", models[action].to_json())
    shutil.copy(ROOT / "domains" / "soccer" / "models" / "goToPose.collision.json", folder)
    return folder


def test_refine_reports_every_measure_predicted_and_measured(model_folder, capsys):
    args = ["refine", "soccer", "score", "--models", str(model_folder), "--objective", "duration + 0.05*energy",
            "--max", "error=0.04", "--simulate"]
    assert main([*args, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["measure_units"] == {"duration": "s", "energy": "J", "error": "m"}
    for key in ("refined", "greedy"):
        execution = data[key]
        assert execution["objective"] == {"duration": 1.0, "energy": 0.05} and execution["limits"] == {"error": 0.04}
        assert execution["violations"] == []
        for action in execution["actions"]:
            assert set(action["measures"]) == {"duration", "energy", "error"} and action["measures"]["error"] <= 0.04
            assert {"duration", "energy", "error"} <= set(action["simulated_measures"])  # what the simulator measured
        assert execution["simulated_measures_total"]["energy"] == pytest.approx(
            sum(a["simulated_measures"]["energy"] for a in execution["actions"]), abs=1e-5)
        assert set(execution["predicted_measures_total"]) == {"duration", "energy", "error"}
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "Objective: duration + 0.05*energy; every action's predicted error <= 0.04 m" in text
    assert "Energy (J), predicted / simulated:" in text and "Error (m), predicted / simulated:" in text


def test_a_limit_no_subgoal_keeps_ends_with_status_9_after_the_output(model_folder, capsys):
    code = main(["refine", "soccer", "score", "--models", str(model_folder), "--max", "error=0.005", "--json"])
    captured = capsys.readouterr()
    assert code == 9
    assert json.loads(captured.out)["refined"]["violations"][0]["step"] == 1  # the output is complete
    (line,) = captured.err.strip().splitlines()[-1:]
    assert line.startswith("tailor refine: error: limit not kept: step 1 goToPose: no subgoal within its ranges "
                           "keeps the predicted error <= 0.005")
    assert "Traceback" not in captured.err


@pytest.mark.parametrize("extra, status, message", [
    (["--objective", "duration + 0.3*enrgy"], 2,
     ("tailor refine: error: --objective: unknown measure 'enrgy': the measures of simulator 'soccer' are duration, "
      "energy, error, heading_error; did you mean 'energy'?")),
    (["--objective", "duration +"], 2,
     ("tailor refine: error: argument --objective: 'duration +': col 11: expected a measure or a number, found the "
      "end")),
    (["--objective", "duration - energy"], 2, "col 10: '-': weights are >= 0"),
    (["--max", "error"], 2, "tailor refine: error: argument --max: 'error': col 6: expected '='"),
    (["--max", "error=0.1", "--max", "error=0.2"], 2,
     "tailor refine: error: --max: error is limited twice (0.1 and 0.2): give one bound"),
    (["--max", "precision=0.1"], 2, "tailor refine: error: --max: unknown measure 'precision'"),
    (["--objective", "duration + heading_error"], 12,
     "goToPose.json: the action model of goToPose has no model of 'heading_error'"),
])
def test_objective_and_limit_mistakes_are_one_clean_line(model_folder, capsys, extra, status, message):
    try:
        code = main(["refine", "soccer", "score", "--models", str(model_folder), *extra])
    except SystemExit as exc:  # argparse's own errors (a malformed value) exit from the parser
        code = exc.code
    err = capsys.readouterr().err
    errors = [line for line in err.splitlines() if line.startswith("tailor refine: error:")]
    assert code == status
    assert len(errors) == 1 and message in errors[0], err
    assert "Traceback" not in err
