"""A leaf's failure probability from episodes that chose no split (issue 35, needless assertions): the success
classifier's training counts the fresh episodes it is evaluated on into every node too (report.fresh_leaves), and
the probability of failing in a leaf is their failures with the training episodes' Laplace estimate as a prior worth
FRESH_PRIOR of them. A small leaf cut around a chance cluster of failed training episodes then no longer buys a
detour that the episodes after training do not justify."""

from __future__ import annotations

import copy
from dataclasses import replace

import numpy as np
import pytest

from tailor.refinement.assertion import Detour, failure_probability
from tailor.refinement.belief import parse_belief
from tailor.refinement.instantiate import instantiate
from tailor.refinement.learning.classifiers import FAIL, labels, train_collision_model
from tailor.refinement.models.action_models import FRESH_PRIOR, load_collision_model, write_json_atomic
from tailor.refinement.models.features import compute_features, first_examples
from tailor.refinement.pipeline import assert_task, prepare, read_task, resolve_task
from synthetic_episodes import gather
from test_leaf_failures import assert_one_line_tree_error

# a ball approach the classifier predicts to fail from, the detour through a subgoal predicted seconds longer than
# the plain approach (tests/test_assertion_detour.py)
SHORT_APPROACH = {"pos1": {"x": 1.3177, "y": 0.9186, "phi": -2.4115, "v": 0.5363},
                  "pos2": {"x": 0.5689, "y": 0.0689, "phi": -2.8890, "v": 0.1234}}


@pytest.fixture(scope="module")
def trained():
    """A classifier trained on synthetic approaches with every 7th outcome flipped (mixed leaves), and its fresh
    episodes."""
    flip = {"success": "collision", "collision": "success"}
    episodes = [replace(e, outcome=flip[e.outcome]) if k % 7 == 3 else e
                for k, e in enumerate(gather("soccer", "goToPoseAtBall", 500, seed=4))]
    fresh = gather("soccer", "goToPoseAtBall", 200, seed=5)
    return fresh, train_collision_model("goToPose", episodes, fresh, seed=0, feature_space="pose").model


def test_training_counts_the_fresh_episodes_into_every_node(trained, tmp_path):
    fresh, model = trained
    counts = model.report["fresh_leaves"]
    reached = model.tree.apply(compute_features("pose", first_examples(fresh)[0]))
    failed = labels(fresh) == FAIL
    for leaf in np.flatnonzero(model.tree.children_left == -1):
        assert counts["samples"][leaf] == np.sum(reached == leaf)
        assert counts["failures"][leaf] == np.sum(failed[reached == leaf])
    assert (counts["samples"][0], counts["failures"][0]) == (len(fresh), failed.sum())
    write_json_atomic(tmp_path / "goToPose.collision.json", model.to_json())
    assert load_collision_model(tmp_path / "goToPose.collision.json").report["fresh_leaves"] == counts  # kept


def _with_counts(model, leaf: int, trained_failed: int, fresh: tuple[int, int] | None):
    """`model` where `leaf` held `trained_failed` of its training episodes failed and (failed, samples) of fresh
    ones (None: no fresh counts, a file written before they were kept)."""
    tree = model.tree
    failures = np.minimum(tree.failures, tree.samples)
    failures[leaf] = trained_failed
    report = {k: v for k, v in model.report.items() if k != "fresh_leaves"}
    if fresh is not None:
        samples = np.zeros(len(tree.children_left), dtype=int)
        failed = np.zeros_like(samples)
        failed[leaf], samples[leaf] = fresh
        report["fresh_leaves"] = {"samples": samples.tolist(), "failures": failed.tolist()}
    return replace(model, tree=replace(tree, failures=failures), report=report)


def test_fresh_episodes_temper_the_training_estimate(trained):
    _, model = trained
    row = first_examples(trained[0])[0][:1]
    leaf = int(model.leaf(row)[0])
    n = int(model.tree.samples[leaf])
    laplace = (n // 2 + 1) / (n + 2)
    alone, _ = _with_counts(model, leaf, n // 2, None).failure_probability(row)
    assert alone[0] == pytest.approx(laplace)
    p, (source,) = _with_counts(model, leaf, n // 2, (0, 30)).failure_probability(row)
    assert p[0] == pytest.approx(FRESH_PRIOR * laplace / (30 + FRESH_PRIOR)) and p[0] < laplace / 3
    assert f"{n // 2} of its {n} training episodes failed" in source and "0 of its 30 fresh episodes" in source
    p, _ = _with_counts(model, leaf, n // 2, (30, 30)).failure_probability(row)
    assert p[0] > 0.9  # every fresh episode failed there: the leaf fails more than its training episodes said
    p, _ = _with_counts(model, leaf, n // 2, (0, 0)).failure_probability(row)
    assert p[0] == pytest.approx(laplace)  # no fresh episode reached the leaf: the training estimate


@pytest.mark.parametrize("fresh, message", [
    (lambda s, f: {"samples": s[:-1], "failures": f[:-1]}, r"report\.fresh_leaves must hold samples and failures"),
    (lambda s, f: {"samples": s}, r"report\.fresh_leaves must hold samples and failures"),
    (lambda s, f: [s, f], r"report\.fresh_leaves must hold samples and failures"),
    (lambda s, f: {"samples": s, "failures": [1.5, *f[1:]]}, r"report\.fresh_leaves must hold"),
    (lambda s, f: {"samples": s, "failures": [s[0] + 1, *f[1:]]}, r"failures at node 0 \(\d+\) must lie in 0\.\."),
])
def test_malformed_fresh_counts_are_one_line_naming_the_file(trained, tmp_path, fresh, message):
    _, model = trained
    data = copy.deepcopy(model.to_json())  # (the module's model shares its report)
    counts = data["report"]["fresh_leaves"]
    data["report"]["fresh_leaves"] = fresh(counts["samples"], counts["failures"])
    assert_one_line_tree_error(tmp_path, data, message)


@pytest.fixture(scope="module")
def soccer():
    return prepare(read_task(resolve_task("soccer", "approach")))


def test_a_leaf_whose_training_failures_the_fresh_episodes_do_not_repeat_buys_no_detour(soccer):
    """The soccer classifier's leaf for a short approach with most of its training episodes failed: alone, that
    pays for the detour (> 1 s); when none of 40 fresh episodes there failed, the plain approach is kept."""
    real = soccer.success_models["goToPose"]
    plain = instantiate(soccer.plan, soccer.binding, parse_belief({"objects": SHORT_APPROACH}))
    row = plain.actions[0].values()
    leaf = int(real.leaf(row[None])[0])
    assert not real.tree.success[leaf]
    n = int(real.tree.samples[leaf])
    detour = Detour(soccer.models, "sample", 0)
    decisions = {}
    for name, fresh in (("training alone", None), ("fresh agree", (36, 40)), ("fresh contradict", (0, 40))):
        classifier = _with_counts(real, leaf, n * 9 // 10, fresh)
        (check,) = assert_task(plain, soccer.binding, {"goToPose": classifier}, soccer.plan, detour).assertions
        assert check.weighing.failure_probability == pytest.approx(failure_probability(classifier, row)[0])
        decisions[name] = check.inserted
    assert decisions == {"training alone": True, "fresh agree": True, "fresh contradict": False}
