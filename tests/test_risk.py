"""Risk-aware refinement: knife-edge margins, the models' uncertainty and the objective duration + lambda * spread.

Constructed models with known leaves, checked against brute force; the plumbing through `refine` on the
soccer binding with model trees fitted to a known travel time (as in test_refine), so nothing here depends
on the trained models.
"""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from rule_models import RuleModel, identity, rule
from tailor.errors import ArgumentValueError, ModelFileError
from tailor.refinement.models.action_models import ActionModel
from tailor.refinement.models.features import compute_features, feature_names
from tailor.refinement.models.model_tree import ModelTree
from tailor.refinement.models.uncertainty import LeafUncertainty, RiskAdjusted
from tailor.refinement.optimizers import FreeParameter, Objective, Term, brute_force, optimize
from tailor.refinement.refine import DEFAULT_RISK, refine

INF = np.inf


# x in [0, 1]: a slope down to 4 s at the split 0.5, then a cheap leaf 0.01 wide (1 s rising to 1.2 s), then 6 s
KNIFE = RuleModel([rule([-INF], [0.5], [-2.0], 5.0), rule([0.5], [0.51], [20.0], -9.0),
                   rule([0.51], [INF], [0.0], 6.0)])
FREE_X = (FreeParameter("x", 0.0, 1.0),)


def test_without_a_margin_the_optimum_sits_on_the_knife_edge():
    result = optimize(Objective(FREE_X, (Term(KNIFE, identity),)))
    x = result.values[0]
    assert result.cost == pytest.approx(1.0) and abs(x - 0.5) < 1e-6
    assert KNIFE.predict([[x - 0.005]])[0] == pytest.approx(4.01)  # half a hundredth away: 4 s, not 1 s


def test_with_a_margin_the_chosen_value_keeps_its_predicted_time_under_perturbation():
    margin = 0.01
    result = optimize(Objective(FREE_X, (Term(KNIFE, identity),), margin=(margin,)))
    x = result.values[0]
    assert result.method == "analytic" and "margin" in result.note
    assert x == pytest.approx(0.49, abs=1e-6)  # the thin leaf is gone; the slope stops the margin before 0.5
    perturbed = KNIFE.predict(np.array([[x + d] for d in np.linspace(-margin, margin, 201)]))
    # the same leaf everywhere within the margin: the prediction moves along its plane (slope 2), never jumps
    np.testing.assert_allclose(perturbed, 5.0 - 2.0 * (x + np.linspace(-margin, margin, 201)), atol=1e-12)
    assert np.all(np.abs(perturbed - result.cost) <= 2.0 * margin + 1e-9)


def test_the_margin_keeps_off_splits_not_off_kinks_of_the_feature_map():
    """|x - 0.3| has a kink at 0.3 where the prediction is continuous: its minimum stays exactly there."""
    model = RuleModel([rule([-INF], [INF], [1.0], 2.0)])
    term = Term(model, lambda theta: np.abs(np.atleast_2d(theta) - 0.3))
    result = optimize(Objective(FREE_X, (term,), margin=(0.05,)))
    assert result.values[0] == pytest.approx(0.3, abs=1e-9) and result.cost == pytest.approx(2.0)


def test_a_margin_wider_than_every_box_falls_back_to_choosing_without_it():
    model = RuleModel([rule([-INF], [0.5], [-1.0], 3.0), rule([0.5], [INF], [1.0], 2.0)])
    result = optimize(Objective(FREE_X, (Term(model, identity),), margin=(0.6,)))
    assert result.method == "analytic" and "without it" in result.note
    assert result.cost == pytest.approx(2.5, abs=1e-6)


def test_leaf_spread_is_the_shrunk_mean_absolute_held_out_error():
    residual = np.array([1.0, -3.0, 0.5, -0.5, 2.0])
    leaf = np.array([0, 0, 1, 1, 1])
    u = LeafUncertainty.from_residuals(leaf, residual, n_leaves=3, prior_episodes=2.0)
    overall = 7.0 / 5
    np.testing.assert_allclose(u.spread, [(4.0 + 2 * overall) / 4, (3.0 + 2 * overall) / 5, overall])
    assert list(u.held_out) == [2, 3, 0] and u.overall == pytest.approx(overall)
    again = LeafUncertainty.from_json(json.loads(json.dumps(u.to_json())), 3, "m.json")
    np.testing.assert_array_equal(again.spread, u.spread)
    assert list(again.held_out) == [2, 3, 0] and again.prior_episodes == 2.0


def _fitted_tree(seed: int = 0) -> tuple[ModelTree, np.ndarray]:
    """A small model tree over (a, b) with steps and slopes, and the data it was fitted on."""
    rng = np.random.default_rng(seed)
    X = rng.uniform(0, 1, size=(1500, 2))
    y = 3 + 2 * (X[:, 0] > 0.4) - 1.5 * X[:, 1] + 1.2 * (X[:, 1] > 0.7) + 0.5 * X[:, 0]
    return ModelTree(min_samples_leaf=60).fit(X, y), X


def test_an_action_model_file_keeps_its_uncertainty_and_old_files_load_without_it(tmp_path):
    F = compute_features("pose", np.zeros((1, 8)))
    steps = (np.arange(40) >= 20) * 5.0 + (np.arange(40) >= 30) * 3.0
    pose_tree = ModelTree(min_samples_leaf=5).fit(np.repeat(F, 40, axis=0) + np.arange(40)[:, None], steps)
    assert pose_tree.n_leaves_ > 1
    spread = np.linspace(0.1, 0.5, pose_tree.n_leaves_)
    model = ActionModel("goToPose", "pose", feature_names("pose"), pose_tree, n_i=1,
                        uncertainty=LeafUncertainty(spread, np.ones(pose_tree.n_leaves_, dtype=int), 0.3))
    data = json.loads(json.dumps(model.to_json()))
    loaded = ActionModel.from_json(data, "m.json")
    np.testing.assert_array_equal(loaded.uncertainty.spread, spread)
    params = np.zeros((3, 8))
    np.testing.assert_array_equal(loaded.predict_spread(params), model.predict_spread(params))
    old = ActionModel.from_json({k: v for k, v in data.items() if k != "uncertainty"}, "old.json")
    assert old.uncertainty is None
    with pytest.raises(ModelFileError, match=r"^old.json: .*no uncertainty.*--risk 0"):
        old.predict_spread(params)
    bad = {**data, "uncertainty": {**data["uncertainty"], "spread": [0.1] * (pose_tree.n_leaves_ + 1)}}
    with pytest.raises(ModelFileError, match=r"^bad.json: uncertainty: spread must be a list of \d+ finite"):
        ActionModel.from_json(bad, "bad.json")


def _risk_objective(risk: float, margin=()) -> tuple[Objective, ModelTree]:
    """Two terms sharing the free parameter a (b is the second's own): each a tree with a known spread per leaf."""
    tree, _ = _fitted_tree()
    spread = np.random.default_rng(7).uniform(0.0, 1.5, tree.n_leaves_)
    u = LeafUncertainty(spread, np.ones(tree.n_leaves_, dtype=int), float(spread.mean()))
    first = RiskAdjusted(tree, u, risk)
    second = RiskAdjusted(tree, u, risk)
    free = (FreeParameter("a", 0.0, 1.0), FreeParameter("b", 0.0, 1.0))
    terms = (Term(first, lambda t: np.atleast_2d(t)[:, [0, 1]]),
             Term(second, lambda t: np.column_stack([1.0 - np.atleast_2d(t)[:, 0], np.atleast_2d(t)[:, 1]])))
    return Objective(free, terms, margin=margin), tree


@pytest.mark.parametrize("risk", [0.0, 0.5, 2.0])
def test_the_risk_objective_is_minimized_exactly_as_brute_force_finds(risk):
    objective, tree = _risk_objective(risk)
    result = optimize(objective, method="analytic")
    grid = brute_force(objective, 401)
    assert result.method == "analytic"
    assert result.cost <= grid.cost + 1e-9  # exact: nothing on a fine grid beats it
    assert result.cost >= grid.cost - 0.05
    # the objective it minimized is the duration plus risk times the spread of each term's leaf
    theta = np.array([result.values])
    plain = tree.predict(theta) + tree.predict(np.array([[1 - theta[0, 0], theta[0, 1]]]))
    spreads = (objective.terms[0].model.penalty[tree.apply(theta)]
               + objective.terms[1].model.penalty[tree.apply(np.array([[1 - theta[0, 0], theta[0, 1]]]))])
    assert result.cost == pytest.approx(float(plain[0] + spreads[0]))
    for method in ("ga", "sample"):  # the other optimizers minimize the same objective
        other = optimize(objective, method=method, seed=3)
        assert other.cost == pytest.approx(float(objective.cost(np.array([other.values]))[0]))
        assert other.cost >= result.cost - 1e-9


# -- through refine() on the soccer binding ------------------------------------------------------------------

def _model(action: str, seed: int) -> ActionModel:
    """test_refine's model of a known travel time, coarser (fewer examples, larger leaves)."""
    from test_refine import _model as travel_time_model

    return travel_time_model(action, seed, n=4000, min_samples_leaf=40)


@pytest.fixture(scope="module")
def score():
    from test_refine import SCORE, _sequence

    return _sequence("score_plan.json", SCORE)


def _with_spread(models: dict, distrust: dict[str, np.ndarray]) -> dict:
    """The models with a spread of 0.05 s in every leaf, and 3 s in the leaves `distrust` names."""
    out = {}
    for action, model in models.items():
        spread = np.full(model.duration.n_leaves_, 0.05)
        spread[distrust.get(action, [])] = 3.0
        out[action] = replace(model, uncertainty=LeafUncertainty(spread, np.ones(len(spread), dtype=int), 0.05))
    return out


def test_refine_with_risk_leaves_the_leaves_the_models_do_not_know(score):
    models = {"approachBall": _model("approachBall", 0), "dribbleBall": _model("dribbleBall", 1),
              "goToPose": _model("goToPose", 2)}
    plain = refine(score, _with_spread(models, {}), horizon=2)
    # distrust exactly the leaves the plain optimum uses
    used = {a.action: models[a.action].duration.apply(models[a.action].features(a.values()[None, :]))
            for a in plain.sequence.actions}
    distrusting = _with_spread(models, used)
    same = refine(score, distrusting, horizon=2, risk=0.0)
    risky = refine(score, distrusting, horizon=2, risk=1.0)
    chosen = lambda r: [p.value for a in r.sequence.actions for p in a.params if p.id.startswith("pos2")]
    assert chosen(same) == chosen(plain) and same.risk == 0.0  # lambda 0: the spread changes nothing
    assert chosen(risky) != chosen(plain) and risky.risk == 1.0
    assert risky.predicted_total >= plain.predicted_total - 1e-9  # a little slower, as predicted ...
    assert sum(risky.spread) < sum(same.spread)  # ... where the models know better what they predict
    assert risky.predicted_total + sum(risky.spread) < same.predicted_total + sum(same.spread)


def test_refine_with_risk_needs_models_with_uncertainty(score):
    models = {"approachBall": _model("approachBall", 0), "dribbleBall": _model("dribbleBall", 1),
              "goToPose": _model("goToPose", 2)}
    assert refine(score, models, horizon=2).spread is None
    with pytest.raises(ModelFileError, match="no uncertainty"):
        refine(score, models, horizon=2, risk=0.5)
    with pytest.raises(ArgumentValueError, match="number from 0 to 1e"):
        refine(score, models, horizon=2, risk=-1.0)


def test_the_risk_sweep_summarizes_each_lambda_on_the_same_situations():
    from tailor.refinement.evaluation.experiments import summarize_comparison, summarize_risk_sweep

    def row(greedy, refined, sweep, oracle=None):
        out = {"problem": "p", "greedy": greedy, "refined": refined, "greedy_ok": True, "refined_ok": True,
               "greedy_outcome": "success", "refined_outcome": "success", "predicted_greedy": greedy,
               "predicted_refined": refined, "analytic_seconds": 0.001, "analytic_method": "analytic",
               "ga_seconds": 0.01, "analytic_cost": refined, "ga_cost": refined,
               "sweep": {repr(lam): {"refined": t, "refined_ok": ok, "refined_outcome": "success" if ok else "timeout",
                                     "predicted_refined": t} for lam, (t, ok) in sweep.items()}}
        if oracle is not None:
            out["oracle"], out["oracle_method"] = oracle, "grid"
        return out

    rows = [row(10.0, 8.0, {0.0: (8.0, True), 1.0: (9.0, True)}, oracle=8.0),
            row(10.0, 11.0, {0.0: (11.0, True), 1.0: (10.0, True)}, oracle=9.0),
            row(10.0, 9.0, {0.0: (9.0, True), 1.0: (30.0, False)})]
    sweep = summarize_risk_sweep(rows)
    assert [r["risk"] for r in sweep] == [0.0, 1.0]
    plain = summarize_comparison(rows)
    assert sweep[0]["improvement"] == pytest.approx(plain["improvement"])  # lambda 0 ran as the main refined
    assert (sweep[0]["better"], sweep[0]["equal"], sweep[0]["worse"]) == (2, 0, 1)
    assert sweep[0]["worse_share"] == pytest.approx(1 / 3) and sweep[0]["oracle_ratio"] == pytest.approx(19 / 17)
    assert (sweep[1]["better"], sweep[1]["equal"], sweep[1]["worse"], sweep[1]["episodes"]) == (1, 1, 0, 2)
    assert sweep[1]["failure_rate_refined"] == pytest.approx(1 / 3) and sweep[1]["improvement"] == pytest.approx(0.05)
    assert sweep[1]["oracle_ratio"] == pytest.approx(19 / 17)


def test_refine_cli_charges_the_uncertainty_with_risk(capsys):
    from tailor.cli.main import main

    runs = {}
    for risk in ("0", "1.5"):
        assert main(["refine", "soccer", "score", "--risk", risk, "--neighbourhood", "0", "--json"]) == 0
        runs[risk] = json.loads(capsys.readouterr().out)
    plain, risky = runs["0"]["refined"], runs["1.5"]["refined"]
    assert (plain["risk"], risky["risk"], runs["1.5"]["greedy"]["risk"]) == (0.0, 1.5, 0.0)  # greedy stays plain
    assert all(a["uncertainty"] > 0 for a in risky["actions"])
    # one window covers both actions: its cost is the predicted total plus lambda times the summed uncertainty
    assert len(risky["optimization"]) == 1
    charged = risky["predicted_total"] + 1.5 * sum(a["uncertainty"] for a in risky["actions"])
    assert risky["optimization"][0]["cost"] == pytest.approx(charged, abs=1e-3)
    assert plain["optimization"][0]["cost"] == pytest.approx(plain["predicted_total"], abs=1e-3)
    assert risky["predicted_total"] + 1.5 * sum(a["uncertainty"] for a in risky["actions"]) <= (
        plain["predicted_total"] + 1.5 * sum(a["uncertainty"] for a in plain["actions"]) + 1e-3)


def test_the_api_takes_risk_and_checks_it():
    import tailor
    from tailor.errors import ArgumentTypeError

    assert tailor.refine("soccer", "score", risk=1.0).refined.risk == 1.0
    with pytest.raises(ArgumentTypeError, match="risk must be a number or None"):
        tailor.refine("soccer", "score", risk="1")
    assert tailor.refine("soccer", "score").refined.risk == DEFAULT_RISK  # the bundled models store it
    with pytest.raises(ArgumentValueError, match="risk lambda must be a number from 0 to 1e"):
        tailor.refine("soccer", "score", risk=float("nan"))


def test_models_without_uncertainty_refine_plainly_by_default_and_refuse_an_explicit_risk(tmp_path, capsys):
    """A model folder trained before the uncertainty existed: the default risk is dropped with a warning,
    --risk > 0 is a one-line error naming the file."""
    from tailor.planner_bridge.bundled import DOMAINS_DIR
    from tailor.cli.main import main

    for path in (DOMAINS_DIR / "kitchen" / "models").glob("*.json"):
        data = json.loads(path.read_text())
        data.pop("uncertainty", None)
        (tmp_path / path.name).write_text(json.dumps(data))
    assert main(["refine", "kitchen", "scenario1", "--models", str(tmp_path), "--json"]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["refined"]["risk"] == 0.0
    assert "no uncertainty stored" in captured.err and "refining without the default risk" in captured.err
    assert main(["refine", "kitchen", "scenario1", "--models", str(tmp_path), "--risk", "0.5"]) == 12
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and ".json: the action model of" in err[0] and "no uncertainty" in err[0]
    assert "--risk 0" in err[0]


@pytest.mark.parametrize("argv, message", [
    (["refine", "soccer", "score", "--risk", "1e308"], "argument --risk: must be a number from 0 to 1e+06, not 1e308"),
    (["evaluate", "soccer", "--risk-sweep", "0,,1"], "argument --risk-sweep: expected comma-separated risk lambdas"),
])
def test_a_risk_lambda_beyond_use_or_a_typo_in_the_sweep_is_a_usage_error(argv, message, capsys):
    """A lambda so large the objective overflows (numpy's warnings on stderr) and an empty item in a sweep
    are refused before any work, as --n-i 1,,2 is."""
    from tailor.cli.main import main

    with pytest.raises(SystemExit) as exit:
        main(argv)
    assert exit.value.code == 2 and message in capsys.readouterr().err
