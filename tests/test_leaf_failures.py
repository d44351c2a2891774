"""Per-leaf failure counts of the success classifier (issue 35, needless assertions): every node of the trained tree
keeps how many training episodes reached it and how many of them failed, counted by routing the training rows
through the final tree; the model file carries them (checked on load); subgoal assertion weighs a predicted failure
with its leaf's Laplace estimate (failed + 1) / (samples + 2) instead of one global share."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from tailor.errors import ModelFileError
from tailor.refinement.assertion import Detour, failure_probability
from tailor.refinement.belief import parse_belief
from tailor.refinement.instantiate import instantiate
from tailor.refinement.learning.classifiers import FAIL, labels, train_collision_model
from tailor.refinement.models.action_models import (
    FRESH_PRIOR,
    CollisionModel,
    load_collision_model,
    write_json_atomic,
)
from tailor.refinement.models.decision_tree import DecisionTree
from tailor.refinement.models.features import compute_features, first_examples
from tailor.refinement.pipeline import assert_task, prepare, read_task, resolve_task
from synthetic_episodes import gather

# a ball approach the bundled classifier predicts to fail from (a leaf where a minority of the training episodes
# failed), the detour through a subgoal predicted seconds longer than the plain approach (test_assertion_detour.py)
SHORT_APPROACH = {"pos1": {"x": 1.3177, "y": 0.9186, "phi": -2.4115, "v": 0.5363},
                  "pos2": {"x": 0.5689, "y": 0.0689, "phi": -2.8890, "v": 0.1234}}


def _hand_built() -> DecisionTree:
    """0: dist <= 2 ? 1 : 2;  2: angle_at <= 0 ? 3 (Success) : 4 (Fail);  1: Fail."""
    return DecisionTree(children_left=np.array([1, -1, 3, -1, -1]), children_right=np.array([2, -1, 4, -1, -1]),
                        feature=np.array([2, -1, 4, -1, -1]), threshold=np.array([2.0, 0, 0.0, 0, 0]),
                        success=np.array([False, False, True, True, False]), samples=np.array([9, 9, 9, 9, 9]))


def test_counting_routes_the_rows_through_the_tree():
    rows = [(1.0, -1.0, True), (1.5, 1.0, False), (3.0, -1.0, False), (3.0, -0.5, False), (3.0, -2.0, True),
            (4.0, 1.0, True), (4.0, 2.0, True), (5.0, 0.5, False)]  # (dist, angle_at, failed)
    X = np.zeros((len(rows), 5))
    X[:, 2], X[:, 4] = [r[0] for r in rows], [r[1] for r in rows]
    tree = _hand_built().counted(X, np.array([r[2] for r in rows]))
    np.testing.assert_array_equal(tree.samples, [8, 2, 6, 3, 3])
    np.testing.assert_array_equal(tree.failures, [4, 1, 3, 1, 2])
    np.testing.assert_allclose(tree.failure_probability([1, 3, 4]), [2 / 4, 2 / 5, 3 / 5])  # Laplace
    assert _hand_built().failure_probability([1]) is None  # not recorded
    simple = replace(tree, success=np.array([False, False, False, False, False])).simplified()  # one leaf
    np.testing.assert_array_equal(simple.samples, [8])
    np.testing.assert_array_equal(simple.failures, [4])


@pytest.fixture(scope="module")
def trained():
    """A classifier trained on synthetic approaches (collision iff |angle_at| > 2) with every 7th outcome flipped,
    so the leaves hold both outcomes and the class weights make the weighted counts differ from the episodes."""
    episodes = gather("soccer", "goToPoseAtBall", 500, seed=4)
    flip = {"success": "collision", "collision": "success"}
    episodes = [replace(e, outcome=flip[e.outcome]) if k % 7 == 3 else e for k, e in enumerate(episodes)]
    fresh = gather("soccer", "goToPoseAtBall", 200, seed=5)
    return episodes, train_collision_model("goToPose", episodes, fresh, seed=0, feature_space="pose").model


def test_a_trained_classifier_keeps_each_leafs_episodes_and_failures(trained):
    episodes, model = trained
    tree = model.tree
    failed = labels(episodes) == FAIL
    reached = tree.apply(compute_features("pose", first_examples(episodes)[0]))
    leaves = np.flatnonzero(tree.children_left == -1)
    assert tree.failures is not None and len(leaves) > 1
    for leaf in leaves:
        assert tree.samples[leaf] == np.sum(reached == leaf)
        assert tree.failures[leaf] == np.sum(failed[reached == leaf])
    assert (tree.samples[0], tree.failures[0]) == (len(episodes), failed.sum())
    assert any(0 < tree.failures[leaf] < tree.samples[leaf] for leaf in leaves)  # mixed leaves, counted as they are
    params = first_examples(episodes)[0][:50]
    probability, sources = model.failure_probability(params)
    leaf = model.leaf(params)
    laplace = (tree.failures[leaf] + 1) / (tree.samples[leaf] + 2)  # tempered by the fresh episodes there
    fresh = {key: np.array(counts)[leaf] for key, counts in model.report["fresh_leaves"].items()}
    expected = (fresh["failures"] + FRESH_PRIOR * laplace) / (fresh["samples"] + FRESH_PRIOR)
    np.testing.assert_allclose(probability, expected)
    assert f"leaf {leaf[0]} " in sources[0] and f"{tree.failures[leaf[0]]} of its {tree.samples[leaf[0]]}" in sources[0]


def test_the_counts_survive_the_model_file(trained, tmp_path):
    _, model = trained
    path = tmp_path / "goToPose.collision.json"
    write_json_atomic(path, model.to_json())
    loaded = load_collision_model(path)
    np.testing.assert_array_equal(loaded.tree.failures, model.tree.failures)
    assert loaded.to_json() == model.to_json()


def test_a_file_without_counts_loads_and_assertion_falls_back_to_the_fresh_episodes(trained, tmp_path):
    _, model = trained
    data = model.to_json()
    del data["tree"]["failures"]
    path = tmp_path / "goToPose.collision.json"
    path.write_text(json.dumps(data), encoding="utf-8")
    old = load_collision_model(path)
    assert old.tree.failures is None and old.failure_probability(np.zeros((1, 8))) is None
    assert "failures" not in old.to_json()["tree"]  # written as it was read
    p, source = failure_probability(old, np.zeros(8))
    counts = model.report["confusion"]["counts"]
    failed = counts["predicted_fail_observed_fail"]
    assert p == pytest.approx(failed / (failed + counts["predicted_fail_observed_success"]))
    assert "fresh episodes" in source


@pytest.mark.parametrize("failures, message", [
    (lambda f, s: f[:-1], r"failures must have one count per node"),
    (lambda f, s: [-1, *f[1:]], r"failures at node 0 \(-1\) must lie in 0\.\.samples"),
    (lambda f, s: [s[0] + 1, *f[1:]], r"failures at node 0 \(\d+\) must lie in 0\.\.samples \(\d+\)"),
    (lambda f, s: [0.5, *f[1:]], r"failures must be a list of integers"),
    (lambda f, s: [True, *f[1:]], r"failures must be a list of integers"),
    (lambda f, s: "12", r"failures must be a list of integers"),
])
def test_malformed_counts_are_one_line_naming_the_file(trained, tmp_path, failures, message):
    _, model = trained
    data = model.to_json()
    data["tree"]["failures"] = failures(data["tree"]["failures"], data["tree"]["samples"])
    assert_one_line_tree_error(tmp_path, data, message)


def assert_one_line_tree_error(tmp_path, data: dict, message: str) -> None:
    """Loading the classifier file `data` fails with one line naming the file and `message` (a regex)."""
    path = tmp_path / "goToPose.collision.json"
    path.write_text(json.dumps(data), encoding="utf-8")
    with pytest.raises(ModelFileError, match="goToPose.collision.json: invalid decision tree: " + message) as error:
        load_collision_model(path)
    assert "\n" not in str(error.value)


@pytest.fixture(scope="module")
def soccer():
    return prepare(read_task(resolve_task("soccer", "approach")))


def _with_failures(classifier: CollisionModel, leaf: int, failed: int) -> CollisionModel:
    """The soccer classifier with counts where `leaf` holds `failed` failures (the rest: all failed at a Fail leaf,
    none at a Success leaf; inner nodes are not read), and no fresh episodes counted (the training counts alone)."""
    tree = classifier.tree
    failures = np.where(tree.success, 0, tree.samples)
    failures[leaf] = failed
    report = {k: v for k, v in classifier.report.items() if k != "fresh_leaves"}
    return replace(classifier, tree=replace(tree, failures=failures), report=report)


def test_assertion_weighs_with_the_leafs_probability(soccer):
    real = soccer.success_models["goToPose"]
    plain = instantiate(soccer.plan, soccer.binding, parse_belief({"objects": SHORT_APPROACH}))
    row = plain.actions[0].values()
    leaf = int(real.leaf(row[None])[0])
    n = int(real.tree.samples[leaf])
    assert not real.tree.success[leaf] and n >= 40
    detour = Detour(soccer.models, "sample", 0)
    decisions = {}
    for failed in (n // 16, n * 15 // 16):  # a leaf that rarely fails, and one that nearly always does
        classifier = _with_failures(real, leaf, failed)
        p, source = failure_probability(classifier, row)
        assert p == pytest.approx((failed + 1) / (n + 2)) and f"leaf {leaf} " in source
        (check,) = assert_task(plain, soccer.binding, {"goToPose": classifier}, soccer.plan, detour).assertions
        assert check.weighing.failure_probability == pytest.approx((failed + 1) / (n + 2))
        assert f"{failed} of its {n} training episodes failed" in check.reason()
        decisions[failed > n // 2] = check.inserted
    # the detour (> 1 s) pays for a leaf that fails nearly always, not for one that fails 6% of the time: neither a
    # failure taken as certain nor the global share of the fresh episodes predicted to fail could tell the two apart
    assert decisions == {False: False, True: True}
