"""The POCL planner (planner_bridge.pocl, engine tailor-pocl): golden plans of the bundled problems, sound
partial-order plans on the classic domains (every linearization checked by unified-planning's validator),
threats resolved (and harmful when left alone), the engine's contract, aliases, errors and timeouts."""

from __future__ import annotations

import itertools
import subprocess
import sys
from pathlib import Path

import pytest
from regenerate_golden import bundled_pairs, pocl_golden_path
from test_planner_bridge import check_plan, files, read

from tailor.planner_bridge import NoPlanError, PlannerTimeoutError, plan_files, plan_here, render_text
from tailor.planner_bridge.benchmark import width
from tailor.planner_bridge.pocl import Planner, flaws_of, linearization
from tailor.planner_bridge.pocl_ground import ground

ROOT = Path(__file__).resolve().parent.parent
CLASSIC = [("gripper", "p01"), ("gripper", "p02"), ("blocks", "p01"), ("blocks", "p02"), ("logistics", "p01"),
           ("logistics", "p02")]
MAX_LINEARIZATIONS = 120  # per plan, enumerated in unified-planning's order; all of them for most plans


def bundled(domain: str, problem: str) -> tuple[Path, Path]:
    return ROOT / "domains" / domain / "domain.pddl", ROOT / "domains" / domain / "problems" / f"{problem}.pddl"


def search(domain: str, problem: str, **options):
    task = ground(read(domain, problem))
    return task, Planner(task, **options).search(timeout=20)


def all_linearizations_valid(problem, plan) -> int:
    """Validate every linearization (up to MAX_LINEARIZATIONS) of a PartialOrderPlan; return how many."""
    from unified_planning.shortcuts import PlanValidator

    count = 0
    with PlanValidator(name="sequential_plan_validator") as validator:
        for sequence in itertools.islice(plan.all_sequential_plans(), MAX_LINEARIZATIONS):
            assert validator.validate(problem, sequence).status.name == "VALID", f"invalid linearization {sequence}"
            count += 1
    return count


@pytest.mark.parametrize("domain, problem", bundled_pairs())
def test_bundled_plans_match_golden(domain, problem):
    # in this process (any hash seed) the plan equals the golden one made in a child with PYTHONHASHSEED=0
    plan = plan_here(*bundled(domain, problem), planner="pocl")
    assert render_text(plan) == pocl_golden_path(domain, problem).read_text(encoding="utf-8")


def test_score_is_the_plan_of_figure_5_6():
    plan = plan_here(*bundled("soccer", "score"), planner="pocl")
    assert render_text(plan) == (
        ";; domain soccer, problem score, planner tailor-pocl\n"
        "Initial 0 : (robot pos1) (ball pos2) (final pos3)\n"
        "Step 1 : (approachball pos1 pos2)\n"
        "    0 -> (robot pos1)\n"
        "    0 -> (ball pos2)\n"
        "Step 2 : (dribbleball pos2 pos3)\n"
        "    1 -> (atball pos2)\n"
        "Goal :\n"
        "    0 -> (final pos3)\n"
        "    2 -> (atball pos3)\n"
        "Orderings : 1<2\n"
    )


@pytest.mark.parametrize("domain, problem", CLASSIC)
def test_classic_domains_give_sound_plans(domain, problem):
    plan = plan_here(*files(domain, problem), planner="pocl")
    assert plan.planner == "tailor-pocl" and plan.steps
    check_plan(read(domain, problem), plan)  # the independent checks the deordered plans pass


def test_briefcase_solves_through_the_compilers():
    # conditional effects under forall: compiled away; the links of the compiled conditions stay in the plan
    plan = plan_here(*files("briefcase", "p01"), planner="pocl")
    assert [s.action for s in plan.steps] == ["put-in", "move-briefcase", "take-out"]
    assert any(link.fact == ("at", "dictionary", "office") and link.producer == 2 for link in plan.links)


@pytest.mark.parametrize("domain, problem", CLASSIC + [("briefcase", "p01")])
def test_engine_returns_a_partial_order_plan_whose_linearizations_are_all_valid(domain, problem):
    from unified_planning.engines import CompilationKind
    from unified_planning.plans import PartialOrderPlan
    from unified_planning.shortcuts import Compiler, OneshotPlanner

    from tailor.planner_bridge.pocl_engine import register

    register()
    original = read(domain, problem)
    parsed = original
    for kind in (CompilationKind.QUANTIFIERS_REMOVING, CompilationKind.CONDITIONAL_EFFECTS_REMOVING):
        if not OneshotPlanner(name="tailor-pocl").supports(parsed.kind):
            with Compiler(problem_kind=parsed.kind, compilation_kind=kind) as compiler:
                parsed = compiler.compile(parsed, kind).problem
    with OneshotPlanner(name="tailor-pocl") as engine:
        result = engine.solve(parsed)
    assert result.status.name == "SOLVED_SATISFICING" and isinstance(result.plan, PartialOrderPlan)
    assert all_linearizations_valid(parsed, result.plan) >= 1


def test_engine_declares_typed_strips_with_negative_preconditions():
    from tailor.planner_bridge.pocl_engine import POCLEngine

    assert POCLEngine.supports(read("gripper", "p01").kind)  # negative preconditions, natively
    assert POCLEngine.supports(read("logistics", "p01").kind)  # hierarchical types
    assert not POCLEngine.supports(read("briefcase", "p01").kind)  # conditional effects: compiled first


@pytest.mark.parametrize("domain, problem", CLASSIC)
def test_no_threat_is_left_and_the_step_ids_follow_a_linearization(domain, problem):
    task, result = search(domain, problem)
    assert result.status == "solved" and flaws_of(task, result.plan) == []
    order = linearization(result.plan)
    assert all(not result.plan.precedes(b, a) for a, b in itertools.combinations(order, 2))


def test_without_threat_resolution_plans_are_unsound():
    # Sussman's anomaly and gripper need promotion or demotion: switched off, some link is threatened
    unsound = []
    for domain, problem in [("blocks", "p01"), ("blocks", "p02"), ("gripper", "p01")]:
        task, result = search(domain, problem, resolve_threats=False)
        if result.plan is not None and flaws_of(task, result.plan):
            unsound.append(problem)
    assert unsound


def test_flaw_selection_and_heuristics_are_named_and_all_solve():
    for strategy, heuristic in itertools.product(["lcfr", "lifo"], ["add", "addr"]):
        task, result = search("logistics", "p01", strategy=strategy, heuristic=heuristic)
        assert result.status == "solved" and flaws_of(task, result.plan) == []


def test_least_commitment_on_parallel_deliveries():
    pocl = plan_here(*files("logistics", "p02"), planner="pocl")
    deordered = plan_here(*files("logistics", "p02"), planner="pyperplan")
    assert len(pocl.orderings) <= len(deordered.orderings) and width(pocl) >= 4


def test_search_honours_its_timeout():
    task = ground(read("gripper", "p01"))
    assert Planner(task, strategy="lifo", heuristic="add").search(timeout=0.05).status == "timeout"


def test_unsolvable_problem_is_no_plan():
    bad = ROOT / "tests" / "fixtures" / "pddl" / "bad"
    with pytest.raises(NoPlanError, match="tailor-pocl"):
        plan_here(bad / "domain.pddl", bad / "unsolvable_problem.pddl", planner="pocl")


def test_worker_timeout_applies_to_pocl():
    bad = ROOT / "tests" / "fixtures" / "pddl" / "bad"
    with pytest.raises(PlannerTimeoutError, match="tailor-pocl"):
        plan_files(bad / "hard_domain.pddl", bad / "hard_problem.pddl", planner="pocl", timeout=0.5)


def test_cli_plan_with_the_pocl_alias_prints_the_golden_text():
    command = [sys.executable, "-m", "tailor.refinement.cli", "plan", "soccer", "waypoints", "--planner", "pocl"]
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout == pocl_golden_path("soccer", "waypoints").read_text(encoding="utf-8")


def test_cli_refine_with_pocl(capsys):
    import json

    from tailor.refinement.cli.main import main

    assert main(["refine", "soccer", "score", "--planner", "pocl", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["planner"] == "tailor-pocl"
    assert [a["action"] for a in data["actions"]] == ["goToPose", "dribbleBall"]  # approachball: goToPose (Ch. 6)
