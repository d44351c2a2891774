"""Subgoal assertion (Ch. 6, Algorithms 4-6): the assert stage, guarded terms in every optimizer, provenance."""

import json

import numpy as np
import pytest
from sklearn.tree import DecisionTreeClassifier

from tailor.errors import BindingError
from tailor.refinement.assertion import assert_subgoals
from tailor.refinement.binding import parse_binding
from tailor.refinement.learning.classifiers import tree_arrays
from tailor.refinement.models.rules import Rule
from tailor.refinement.optimizers import Objective, brute_force, optimize
from tailor.refinement.optimizers import analytic
from tailor.refinement.optimizers.synthetic import random_objective
from tailor.refinement.belief import parse_belief
from tailor.refinement.instantiate import instantiate
from tailor.refinement.pipeline import Options, assert_task, prepare, read_task, resolve_task
from tailor.refinement.refine import predicted_success, refine


class Region:
    """A success classifier over a term's features: a fitted decision tree as plain arrays."""

    def __init__(self, tree, n_features):
        self.tree, self.n_features = tree, n_features

    def predict_success(self, F):
        return self.tree.predict(F)

    def success_rules(self):
        boxes = self.tree.success_boxes(self.n_features)
        return [Rule(b.lower, b.upper, np.zeros(len(b.lower)), 0.0) for b in boxes]


def guarded_objective(seed: int) -> Objective:
    """A random two-term objective over two free parameters; the first term guarded by a random classifier."""
    rng = np.random.default_rng(seed)
    objective = random_objective(rng, n_free=2, n_terms=2, n_leaves=25)
    term = objective.terms[0]
    theta = rng.uniform(objective.low, objective.high, size=(400, 2))
    F = term.features(theta)
    centre = rng.uniform(objective.low, objective.high)
    labels = (np.abs(theta - centre) / (objective.high - objective.low)).sum(axis=1) > 0.35  # fail near centre
    tree = tree_arrays(DecisionTreeClassifier(max_leaf_nodes=8, random_state=0).fit(F, labels.astype(int)))
    region = Region(tree, F.shape[1])
    guarded = type(term)(model=term.model, features=term.features, label=term.label,
                         valid=lambda t: region.predict_success(term.features(t)), region=region,
                         region_features=term.features)
    return Objective(objective.free, (guarded, objective.terms[1]))


@pytest.mark.parametrize("seed", range(8))
def test_analytic_within_the_success_region_matches_brute_force(seed):
    objective = guarded_objective(seed)
    result = optimize(objective, "analytic", seed=0)
    grid = brute_force(objective, 401)
    assert result.method == "analytic" and "success region" in result.note
    assert objective.valid(np.array([result.values]))[0]
    # the exact minimum over the valid boxes is at least as good as the best valid grid point, and close to it
    assert result.cost <= grid.cost + 1e-9
    assert result.cost >= grid.cost - 0.05 * abs(grid.cost) - 0.05


def test_analytic_uses_the_region_not_only_the_validity_check(monkeypatch):
    """Switched off (the region covering everything), the corners of the unconstrained boxes are tried instead;
    with the region the merged rule set is smaller: the classifier's leaves cut the boxes."""
    objective = guarded_objective(3)
    with_region = optimize(objective, "analytic", seed=0)
    monkeypatch.setattr(Region, "success_rules", lambda self: [
        Rule(np.full(self.n_features, -np.inf), np.full(self.n_features, np.inf), np.zeros(self.n_features), 0.0)])
    analytic._region_cache.clear()
    without = optimize(objective, "analytic", seed=0)
    merged = lambda r: int(r.note.split()[0])  # noqa: E731
    assert merged(with_region) != merged(without)


@pytest.mark.parametrize("method", ["ga", "sample"])
def test_ga_and_sampling_return_valid_parameterizations(method):
    objective = guarded_objective(5)
    result = optimize(objective, method, seed=1)
    assert objective.valid(np.array([result.values]))[0]
    unguarded = Objective(objective.free, tuple(type(t)(model=t.model, features=t.features, label=t.label)
                                                for t in objective.terms))
    if method == "sample":  # rejection: more draws than the plain sampler where some are invalid
        assert result.evaluations > optimize(unguarded, method, seed=1).evaluations
        assert "rejection" in result.note


# --- the assert stage on the soccer robot's learned classifier -------------------------------------------------

@pytest.fixture(scope="module")
def soccer():
    """The approach problem planned and its models loaded once (its own belief file asserts a subgoal)."""
    return prepare(read_task(resolve_task("soccer", "approach")))


def approach(prepared, robot, ball):
    """The approach problem instantiated for another situation, subgoals asserted (Alg. 4 after planning)."""
    x, y, phi, v = robot
    bx, by, bphi, bv = ball
    belief = parse_belief({"objects": {"pos1": {"x": x, "y": y, "phi": phi, "v": v},
                                       "pos2": {"x": bx, "y": by, "phi": bphi, "v": bv}}})
    plain = instantiate(prepared.plan, prepared.binding, belief)
    return plain, assert_task(plain, prepared.binding, prepared.success_models, prepared.plan)


@pytest.mark.parametrize("robot, ball", [
    ((-1.0, 0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.1)),  # from behind, heading along: no bump
    ((-1.0, 0.0, 0.0, 0.0), (1.0, 0.0, 3.14159, 0.1)),  # from the far side: goToPose crosses the ball
    ((2.0, 1.5, -2.0, 0.2), (-1.0, -1.0, 0.5, 0.0)),
    ((0.0, -2.0, 1.57, 0.0), (0.5, 1.0, -1.6, 0.2)),
])
def test_subgoal_inserted_exactly_when_the_classifier_predicts_failure(soccer, robot, ball):
    plain, asserted = approach(soccer, robot, ball)
    classifier = soccer.success_models["goToPose"]
    fails = not classifier.predict_success(plain.actions[0].values()[None, :])[0]
    (check,) = asserted.assertions
    assert check.inserted == fails == (not check.predicted_success)
    sequence = asserted.sequence
    assert len(sequence.actions) == (2 if fails else 1)
    assert all(a.step == 1 and a.action == "goToPose" for a in sequence.actions)
    assert sequence.actions[-1].guard == "goToPose"
    if fails:
        first, second = sequence.actions
        assert [p.id for p in first.free_parameters()] == [f"subgoal1.{q}" for q in ("x", "y", "phi", "v")]
        assert [p.id for p in second.free_parameters()] == [p.id for p in first.free_parameters()]
        assert (first.params[-1].low, first.params[-1].high) == (0.0, 0.6)  # the binding's subgoal range
        assert (first.params[4].low, first.params[4].high) == (-4.0, 4.0)  # the type's default range
        assert "predicts failure" in first.origin and "subgoal1" in second.origin
        # refined with h=1 or 2, the subgoal lies where the classifier predicts success (Alg. 6)
        for horizon in (1, 2):
            refined = refine(sequence, soccer.models, horizon, "analytic", 0, soccer.success_models)
            assert predicted_success(refined.sequence, soccer.success_models) == (True, True)


def test_assert_stage_switched_off_leaves_the_plain_action(soccer):
    assert soccer.assertions[0].inserted and len(soccer.sequence.actions) == 2
    plain = prepare(read_task(resolve_task("soccer", "approach")), Options(assertion=False))
    assert plain.assertions == () and len(plain.sequence.actions) == 1 and not plain.sequence.actions[0].guard


def test_a_stub_classifier_decides_alone(soccer):
    """The stage consults only the classifier: one predicting success everywhere asserts nothing, one predicting
    failure everywhere always asserts (and names the leaf it came from)."""
    real = soccer.success_models["goToPose"]

    class Always:
        def __init__(self, verdict):
            self.verdict, self.tree = verdict, real.tree

        def predict_success(self, params):
            return np.full(len(params), self.verdict)

        def leaf(self, params):
            return real.leaf(params)

    for verdict in (True, False):
        out = assert_subgoals(soccer.instantiated, soccer.binding, {"goToPose": Always(verdict)})
        assert out.assertions[0].inserted is (not verdict)
        assert len(out.sequence.actions) == (1 if verdict else 2)


def test_refine_json_carries_provenance(capsys):
    from tailor.cli.main import main

    assert main(["refine", "soccer", "approach", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    (check,) = data["assertions"]
    assert check["inserted"] and check["subgoal"] == "subgoal1" and check["step"] == 1
    assert isinstance(check["leaf"], int) and "predicts failure" in check["reason"]
    first, second = data["refined"]["actions"]
    assert first["step"] == second["step"] == 1 and "subgoal1" in first["origin"]
    assert second["guard"] == "goToPose" and second["predicted_success"] is True
    assert data["refined"]["optimization"][0]["method"] in ("ga", "analytic")


# --- the binding ---------------------------------------------------------------------------------------------

def binding_data(**action):
    return {"schema": 2, "simulator": "soccer",
            "actions": {"approachball": {"executable": "goToPose", "observed": 0, "internal": 1, **action}}}


def test_binding_reads_success_model_and_subgoal_ranges():
    b = parse_binding(binding_data(success_model="goToPose", subgoal={"v": [0.0, 0.6]}), "b.toml")
    assert b.actions["approachball"].success_model == "goToPose"
    assert dict(b.actions["approachball"].subgoal) == {"v": (0.0, 0.6)}
    assert parse_binding(binding_data(), "b.toml").actions["approachball"].success_model is None


@pytest.mark.parametrize("action, message", [
    ({"success_model": 3}, "success_model must name"),
    ({"subgoal": {"v": [0.0, 0.6]}}, "need a success_model"),
    ({"success_model": "goToPose", "subgoal": {"speed": [0, 1]}}, "unknown key 'speed'"),
    ({"success_model": "goToPose", "subgoal": {"v": [1.0, 0.0]}}, "is empty"),
])
def test_binding_rejects_bad_assertion_keys(action, message):
    with pytest.raises(BindingError, match=message):
        parse_binding(binding_data(**action), "b.toml")


# --- the evaluation's arithmetic (Table 6.1) ---------------------------------------------------------------

def _row(inserted, predicted, plain, with_, plain_t=10.0, with_t=10.0, leg=None):
    return {"inserted": inserted, "predicted_success": predicted, "plain_ok": plain == "success",
            "plain_outcome": plain, "plain_time": plain_t, "with_ok": with_ == "success", "with_outcome": with_,
            "with_time": with_t, "with_failed_leg": leg, "methods": ["ga"] if inserted else [],
            "optimizer_seconds": 0.1 if inserted else 0.0}


def test_summary_counts_avoided_collisions_needless_assertions_and_table_6_1():
    from tailor.refinement.evaluation.assertion_experiment import summarize_assertion

    rows = [_row(True, False, "collision", "success"),  # avoided
            _row(True, False, "collision", "collision", leg="final"),  # not avoided
            _row(True, False, "success", "success", 10.0, 12.0),  # needless, 20% slower
            _row(True, False, "success", "success", 10.0, 11.0),  # needless, 10% slower
            _row(False, True, "success", "success"), _row(False, True, "success", "success"),
            _row(False, True, "collision", "collision", leg="final"),  # a false success
            _row(False, True, "success", "success")]
    s = summarize_assertion(rows)
    assert s["episodes"] == 8 and s["success_without"] == 5 / 8 and s["success_with"] == 6 / 8
    assert s["collisions"] == 3 and s["collisions_avoided"] == pytest.approx(1 / 3)
    assert s["collision_outcome"] == "collision"
    other = [{**r, "plain_outcome": "off_table" if r["plain_outcome"] == "collision" else r["plain_outcome"],
              "with_outcome": "off_table" if r["with_outcome"] == "collision" else r["with_outcome"]} for r in rows]
    assert summarize_assertion(other)["collision_outcome"] == "any failure"  # a robot that does not collide
    assert summarize_assertion(other)["collisions"] == 3
    assert s["needless_assertions"] == 2 / 8 and s["needless_cost"] == pytest.approx(0.15)
    assert s["asserted"] == 4 / 8 and s["new_failures"] == 0 and s["failed_legs_with"] == {"final": 2}
    assert s["table_before"] == {"predicted_fail_observed_fail": 2 / 8, "predicted_fail_observed_success": 2 / 8,
                                 "predicted_success_observed_fail": 1 / 8,
                                 "predicted_success_observed_success": 3 / 8}
    assert s["table_after"]["predicted_fail_observed_success"] == 3 / 8
    assert s["table_after"]["predicted_success_observed_fail"] == 1 / 8


def test_evaluate_assertion_json_has_the_issue_keys(capsys):
    from tailor.cli.main import main

    assert main(["evaluate", "soccer", "--assertion", "--episodes", "3", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    for key in ("episodes", "success_without", "success_with", "collisions_avoided", "needless_assertions",
                "needless_cost", "table_before", "table_after"):
        assert key in data
    assert data["episodes"] == 3 and data["generator"] == "approach"


def test_success_margin_keeps_choices_off_the_edge_of_the_region(soccer):
    """With the binding's margin the refined approach heading of `score` is predicted to succeed also 5% of the
    heading range to either side; without it the optimizer may sit on the very edge."""
    from dataclasses import replace as copy

    score = prepare(read_task(resolve_task("soccer", "score")))
    guarded = score.sequence.actions[0]
    assert guarded.guard == "goToPose" and guarded.guard_margin == 0.05
    classifier = score.success_models["goToPose"]
    refined = refine(score.sequence, score.models, 2, "analytic", 0, score.success_models)
    phi = next(p for p in refined.sequence.actions[0].params if p.id == "pos2.phi")
    width = 0.05 * (phi.high - phi.low)
    for shift in (-width, 0.0, width):
        row = refined.sequence.actions[0].values()
        row[6] = min(max(phi.value + shift, phi.low), phi.high)
        assert classifier.predict_success(row[None, :])[0]
    edge = copy(score.sequence, actions=(copy(guarded, guard_margin=0.0), *score.sequence.actions[1:]))
    plain = refine(edge, score.models, 2, "analytic", 0, score.success_models)
    # the margin costs predicted time, never gains it: up to the GA's own spread (the window choosing the
    # dribble's start is the GA's, the `dribble` features not being piecewise affine)
    assert plain.predicted_total <= refined.predicted_total + 0.01


def test_binding_rejects_a_bad_margin():
    with pytest.raises(BindingError, match="success_margin must be a share"):
        parse_binding(binding_data(success_model="goToPose", success_margin=0.7), "b.toml")
    with pytest.raises(BindingError, match="success_margin needs a success_model"):
        parse_binding(binding_data(success_margin=0.1), "b.toml")
    b = parse_binding(binding_data(success_model="goToPose", success_margin=0.1), "b.toml")
    assert b.actions["approachball"].success_margin == 0.1


def test_a_missing_or_broken_success_model_is_one_line(tmp_path, capsys):
    import shutil
    from pathlib import Path

    from tailor.cli.main import main

    domain = tmp_path / "soccer"
    shutil.copytree(Path(__file__).parent.parent / "domains" / "soccer", domain,
                    ignore=shutil.ignore_patterns("training"))
    model = domain / "models" / "goToPose.collision.json"
    model.write_text('{"schema": "tailor.collision_model/1", "action": "goToPose"}')
    assert main(["refine", str(domain / "domain.pddl"), "approach"]) == 12
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(model) in err[0]
    model.unlink()
    assert main(["refine", str(domain / "domain.pddl"), "approach"]) == 12
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no success classifier goToPose.collision.json" in err[0]
