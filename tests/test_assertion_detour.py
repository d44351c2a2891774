"""Subgoal assertion weighs the detour (issue 35): a subgoal is asserted only where the predicted cost of failing
(failure probability x a second attempt through the subgoal) exceeds the predicted cost of the detour (the two
actions through the subgoal, refined, against the plain action), and every assertion says why."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from tailor.refinement.assertion import Detour, Weighing, failure_probability
from tailor.refinement.belief import parse_belief
from tailor.refinement.instantiate import instantiate
from tailor.refinement.pipeline import assert_task, prepare, read_task, resolve_task

# a ball approach the classifier predicts to fail from (leaf "angle_at > -0.693: Fail"), where the detour through
# a subgoal is predicted to take seconds longer than the plain approach (which succeeds in the simulator)
SHORT_APPROACH = {"pos1": {"x": 1.3177, "y": 0.9186, "phi": -2.4115, "v": 0.5363},
                  "pos2": {"x": 0.5689, "y": 0.0689, "phi": -2.8890, "v": 0.1234}}


class WithFailureRate:
    """The soccer robot's success classifier with a failure probability of its own, as a classifier that keeps
    its leaves' shares of failed training episodes gives one."""

    def __init__(self, real, probability: float):
        self._real, self._probability = real, probability

    def __getattr__(self, name):
        if name.startswith("_"):  # (not yet set while being copied)
            raise AttributeError(name)
        return getattr(self._real, name)

    def failure_probability(self, params):
        return np.full(len(params), self._probability)


@pytest.fixture(scope="module")
def soccer():
    return prepare(read_task(resolve_task("soccer", "approach")))


def _assert(soccer, sequence, probability, weigh=True):
    classifier = WithFailureRate(soccer.success_models["goToPose"], probability)
    detour = Detour(soccer.models, "sample", 0) if weigh else None  # (sampling: fast, and the same every run)
    return assert_task(sequence, soccer.binding, {"goToPose": classifier}, soccer.plan, detour)


def _short(soccer):
    return instantiate(soccer.plan, soccer.binding, parse_belief({"objects": SHORT_APPROACH}))


def test_no_subgoal_where_the_detour_costs_more_than_the_predicted_failure(soccer):
    plain = _short(soccer)
    out = _assert(soccer, plain, 0.05)
    (check,) = out.assertions
    w = check.weighing
    assert not check.predicted_success and w is not None
    assert w.detour > 1.0 and w.expected_failure_cost == pytest.approx(0.05 * w.asserted)
    assert w.expected_failure_cost < w.detour and not w.pays
    assert not check.inserted and out.sequence.actions == plain.actions  # the plain action, unguarded
    assert "detour" in check.reason() and "plain action kept" in check.reason()
    assert check.to_json()["weighing"]["subgoal_pays"] is False


def test_a_subgoal_where_the_predicted_failure_costs_more_than_the_detour(soccer):
    out = _assert(soccer, _short(soccer), 0.95)
    (check,) = out.assertions
    w = check.weighing
    assert w.pays and w.expected_failure_cost > w.detour > 1.0
    assert check.inserted and len(out.sequence.actions) == 2 and out.sequence.actions[1].guard == "goToPose"
    assert f"subgoal {check.subgoal} asserted" in check.reason() and "expected cost of failing" in check.reason()
    assert "expected cost of failing" in out.sequence.actions[0].origin  # the inserted actions say why too


def test_a_detour_faster_than_the_plain_action_is_taken_whatever_the_risk(soccer):
    """The plain approach from the wrong side is predicted slower than the two actions through a subgoal: even a
    small failure probability pays for a detour that costs nothing."""
    (check,) = _assert(soccer, soccer.instantiated, 0.01).assertions
    assert check.weighing.detour < 0 and check.inserted


def test_without_the_duration_models_every_predicted_failure_gets_its_subgoal(soccer):
    """Alg. 5 as the dissertation has it (and assertion before this issue): no weighing, a subgoal wherever
    failure is predicted."""
    (check,) = _assert(soccer, _short(soccer), 0.05, weigh=False).assertions
    assert check.weighing is None and check.inserted


def test_the_failure_probability_comes_from_the_classifier(soccer):
    real = soccer.success_models["goToPose"]
    row = soccer.instantiated.actions[0].values()
    assert failure_probability(WithFailureRate(real, 0.3), row) == (0.3, "the classifier's leaf")
    # its leaf's share of failed training episodes (the bundled classifier counts them)
    p, source = failure_probability(real, row)
    assert 0.0 < p < 1.0 and source.startswith("leaf ")
    # a classifier without counts: the share that failed of the fresh episodes it predicted to fail (Table 4.4)
    counts = real.report["confusion"]["counts"]
    failed, succeeded = counts["predicted_fail_observed_fail"], counts["predicted_fail_observed_success"]
    p, source = failure_probability(replace(real, tree=replace(real.tree, failures=None)), row)
    assert p == pytest.approx(failed / (failed + succeeded)) and "fresh episodes" in source
    assert failure_probability(object(), row)[0] == 1.0  # nothing known: a failure is taken as certain


def test_weighing_arithmetic():
    w = Weighing(0.5, "test", plain=4.0, asserted=6.0)
    assert w.detour == 2.0 and w.failure_cost == 6.0 and w.expected_failure_cost == 3.0 and w.pays
    assert not Weighing(0.3, "test", plain=4.0, asserted=6.0).pays  # 1.8 s expected against a 2 s detour
    assert Weighing(0.0, "test", plain=4.0, asserted=3.0).pays  # a detour predicted faster pays without any risk
    assert not Weighing(0.0, "test", plain=4.0, asserted=4.0).pays


def test_tailor_refine_says_why_in_text_and_json(capsys):
    from tailor.cli.main import main

    assert main(["refine", "soccer", "approach", "--optimizer", "sample", "--json"]) == 0
    (check,) = json.loads(capsys.readouterr().out)["assertions"]
    w = check["weighing"]
    assert check["inserted"] and w["subgoal_pays"] and w["expected_failure_cost"] > w["detour"]
    assert set(w) >= {"failure_probability", "failure_probability_source", "predicted_plain",
                      "predicted_with_subgoal", "detour", "failure_cost", "expected_failure_cost"}
    assert "expected cost of failing" in check["reason"] and "detour" in check["reason"]
    assert main(["refine", "soccer", "approach", "--optimizer", "sample"]) == 0
    text = capsys.readouterr().out
    line = next(line for line in text.splitlines() if line.startswith("Subgoal assertion, step 1"))
    assert "expected cost of failing" in line and "detour" in line and "subgoal subgoal1 asserted" in line


def test_the_assertion_summary_counts_the_predicted_failures_left_plain():
    from tailor.refinement.evaluation.assertion_experiment import summarize_assertion

    def row(inserted, weighed_out, plain_ok, detour):
        with_ok = plain_ok or not weighed_out  # left plain: the plain execution
        return {"inserted": inserted, "predicted_success": False, "plain_ok": plain_ok,
                "plain_outcome": "success" if plain_ok else "collision", "plain_time": 10.0, "with_ok": with_ok,
                "with_outcome": "success" if with_ok else "collision", "with_time": 10.0 if weighed_out else 11.0,
                "with_failed_leg": None if with_ok else "final",
                "methods": [], "optimizer_seconds": 0.0, "assertion_seconds": 0.01, "weighed_out": weighed_out,
                "weighings": [{"failure_probability_source": "leaf", "detour": detour}]}

    s = summarize_assertion([row(True, False, False, -1.0), row(False, True, True, 3.0), row(False, True, False, 2.0)])
    assert s["predicted_fail"] == 1.0 and s["weighed_out"] == pytest.approx(2 / 3) and s["weighed_out_failed"] == 1
    assert s["detour_predicted_median"] == 2.0 and s["failure_probability_sources"] == ["leaf"]
    assert s["asserted"] == pytest.approx(1 / 3) and s["needless_assertions"] == 0.0
