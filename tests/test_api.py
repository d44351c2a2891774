"""The Python API (`import tailor`): one call per stage, unified-planning objects in and out, one exception
base whose TypeError/ValueError subclasses name the argument."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import tailor
from tailor.errors import ArgumentTypeError, ArgumentValueError, BeliefError, NoPlanError

ROOT = Path(__file__).resolve().parents[1]
SOCCER = ROOT / "domains" / "soccer"
GOLDEN = ROOT / "tests" / "golden"


@pytest.fixture(scope="module")
def score_problem():
    from unified_planning.io import PDDLReader

    return PDDLReader().parse_problem(str(SOCCER / "domain.pddl"), str(SOCCER / "problems" / "score.pddl"))


def _golden_plan(domain: str, problem: str) -> dict:
    data = json.loads((GOLDEN / "plan" / domain / f"{problem}.json").read_text())
    return {k: v for k, v in data.items() if k not in ("schema", "units")}


def test_plan_of_files_is_the_golden_plan_and_reuses_one_planner_process():
    from tailor.refinement import api

    assert tailor.plan("soccer", "score").to_json() == _golden_plan("soccer", "score")
    child = api._PLANNER._child.pid
    assert tailor.plan("arm", "letter-s").to_json() == _golden_plan("arm", "letter-s")
    assert api._PLANNER._child.pid == child  # no new interpreter for the second plan


def test_a_planner_error_keeps_the_process_and_a_timeout_replaces_it():
    from tailor.refinement import api

    bad = ROOT / "tests" / "fixtures" / "pddl" / "bad"
    tailor.plan("soccer", "score")
    child = api._PLANNER._child.pid
    with pytest.raises(NoPlanError):
        tailor.plan(bad / "domain.pddl", bad / "unsolvable_problem.pddl")
    assert api._PLANNER._child.pid == child
    with pytest.raises(tailor.TailorError, match="timeout"):
        tailor.plan(bad / "hard_domain.pddl", bad / "hard_problem.pddl", planner="pocl", timeout=0.5)
    assert tailor.plan("soccer", "score").to_json() == _golden_plan("soccer", "score")
    assert api._PLANNER._child.pid != child


def test_a_unified_planning_problem_plans_in_process_and_comes_back_as_a_partial_order_plan(score_problem):
    from unified_planning.plans import PartialOrderPlan, PlanKind
    from unified_planning.shortcuts import PlanValidator

    plan = tailor.plan(score_problem)
    assert [(s.action, s.args) for s in plan.steps] == [("approachball", ("pos1", "pos2")),
                                                        ("dribbleball", ("pos2", "pos3"))]
    assert {(k.producer, k.fact, k.consumer) for k in plan.links} == {
        (k["from"], tuple(k["fact"]), k["to"]) for k in _golden_plan("soccer", "score")["links"]}
    po = tailor.to_partial_order_plan(plan, score_problem)
    assert isinstance(po, PartialOrderPlan)
    orders = [[str(a) for a in p.actions] for p in po.all_sequential_plans()]
    assert orders == [["approachball(pos1, pos2)", "dribbleball(pos2, pos3)"]]
    with PlanValidator(problem_kind=score_problem.kind) as validator:
        assert validator.validate(score_problem, po.convert_to(PlanKind.SEQUENTIAL_PLAN, score_problem)).status.name == "VALID"


def test_a_plan_from_any_engine_is_linked_and_refined_like_ours(score_problem):
    from unified_planning.shortcuts import OneshotPlanner

    with OneshotPlanner(name="pyperplan") as engine:
        found = engine.solve(score_problem).plan
    linked = tailor.link_plan(score_problem, found)
    assert linked.links == tailor.plan(score_problem).links and linked.planner == "given"
    belief = SOCCER / "problems" / "score.toml"
    ours = tailor.refine("soccer", "score")
    theirs = tailor.refine("soccer", score_problem, belief=belief, plan=found)
    assert theirs.chosen == ours.chosen and theirs.predicted_total == ours.predicted_total
    named = tailor.refine("soccer", "score", plan=found)  # the problem by name, its belief file beside it
    assert named.chosen == ours.chosen and named.plan.planner == "given"


def test_refine_reports_what_was_free_and_what_it_was_set_to():
    golden = json.loads((GOLDEN / "refine" / "soccer" / "score.json").read_text())
    refined = tailor.refine("soccer", "score")
    assert list(refined.free) == [p["id"] for p in golden["free_parameters"]]
    assert refined.free == {p["id"]: (p["low"], p["high"]) for p in golden["free_parameters"]}
    assert refined.chosen == pytest.approx({p["id"]: p["value"] for p in golden["free_parameters"]}, abs=1e-6)
    assert refined.predicted_total == pytest.approx(golden["refined"]["predicted_total"], abs=1e-3)
    greedy = tailor.refine("soccer", "score", horizon=1, risk=0, neighbourhood=0)  # the CLI's greedy: h = 1, plain
    assert greedy.chosen == pytest.approx({p["id"]: p["greedy"] for p in golden["free_parameters"]}, abs=1e-6)
    result = tailor.dispatch(refined, seed=0)
    assert result.succeeded and result.duration == pytest.approx(golden["refined"]["simulated_total"], abs=1e-3)
    # the default optimizer is auto, as the CLI's: each window says which optimizer's choice it took
    assert golden["optimizer"] == "auto"
    assert [w.method for w in refined.refined.windows] == [w["method"] for w in golden["refined"]["optimization"]]


def test_a_belief_given_as_a_dict_is_the_file_and_is_checked():
    import tomllib

    table = tomllib.loads((SOCCER / "problems" / "score.toml").read_text())["objects"]
    assert tailor.refine("soccer", "score", belief=table).chosen == tailor.refine("soccer", "score").chosen
    moved = {**table, "pos1": {**table["pos1"], "x": table["pos1"]["x"] + 1.0}}
    assert tailor.refine("soccer", "score", belief=moved).predicted_total != tailor.refine("soccer", "score").predicted_total
    with pytest.raises(BeliefError, match=r"<belief argument>: \[objects.pos1\] x = 'far' is not a number"):
        tailor.refine("soccer", "score", belief={**table, "pos1": {**table["pos1"], "x": "far"}})
    with pytest.raises(BeliefError, match="'nowhere' is not an object"):
        tailor.refine("soccer", "score", belief={**table, "nowhere": {"x": 0.0}})


def test_numbers_out_of_numpy_are_numbers():
    """A belief filled from arrays (np.float32, np.int64) and a horizon or seed taken from one are accepted, and
    give what Python's numbers give."""
    import tomllib

    import numpy as np

    table = tomllib.loads((SOCCER / "problems" / "score.toml").read_text())["objects"]
    as_numpy = {name: {q: np.float64(v) if isinstance(v, float) else np.int64(v) for q, v in values.items()}
                for name, values in table.items()}
    plain = tailor.refine("soccer", "score", belief=table, horizon=2, seed=3)
    numpy = tailor.refine("soccer", "score", belief=as_numpy, horizon=np.int64(2), seed=np.int64(3))
    assert numpy.chosen == plain.chosen and numpy.predicted_total == plain.predicted_total
    assert tailor.refine("soccer", "score", belief={**table, "pos1": {**table["pos1"], "x": np.float32(-2.0)}})


@pytest.mark.parametrize("call, error, named", [
    (lambda: tailor.refine("soccer", "score", horizon="2"), TypeError, "horizon"),
    (lambda: tailor.refine("soccer", "score", horizon=0), ValueError, "horizon"),
    (lambda: tailor.refine("soccer", "score", optimizer="newton"), ValueError, "optimizer"),
    (lambda: tailor.refine("soccer", 42), TypeError, "problem"),
    (lambda: tailor.refine(3.0, "score"), TypeError, "domain"),
    (lambda: tailor.refine("soccer", "score", belief=[1, 2]), TypeError, "belief"),
    (lambda: tailor.refine("soccer", "score", seed=1.5), TypeError, "seed"),
    (lambda: tailor.plan("soccer"), ValueError, "problem"),
    (lambda: tailor.plan("soccer", "score", timeout=-1), ValueError, "timeout"),
    (lambda: tailor.dispatch("a plan"), TypeError, "refined"),
    (lambda: tailor.refine("soccer", "score", seed=-1, optimizer="sample"), ValueError, "seed"),
    (lambda: tailor.refine("soccer", "score", seed=2**63), ValueError, "seed"),
    (lambda: tailor.refine("soccer", "score", models=5), TypeError, "models"),
    (lambda: tailor.refine("soccer", "score", plan="a plan"), TypeError, "plan"),
    (lambda: tailor.refine("soccer", "waypoints", plan=tailor.plan("soccer", "score")), ValueError,
     "plan is a plan of problem 'score', not of 'waypoints'"),
    (lambda: tailor.refinement.load_action_models(5), TypeError, "models_dir"),
    (lambda: tailor.refinement.load_domain_binding(5), TypeError, "domain_dir"),
])
def test_wrong_arguments_name_themselves_and_share_the_base(call, error, named):
    with pytest.raises(error, match=named) as caught:
        call()
    assert isinstance(caught.value, tailor.TailorError)
    assert isinstance(caught.value, (ArgumentTypeError, ArgumentValueError))


def test_an_unrefined_sequence_is_not_dispatched():
    refined = tailor.refine("soccer", "score")
    with pytest.raises(ArgumentValueError, match="pos2.phi, pos2.v"):
        tailor.dispatch(refined.instantiated)


def test_import_tailor_stays_light():
    import subprocess
    import sys

    code = "import sys, tailor; print(sorted(m for m in sys.modules if m.startswith(('unified_planning', 'sklearn', 'pymunk'))))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
