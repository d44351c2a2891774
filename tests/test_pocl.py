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

from tailor.planner_bridge import (
    NoPlanError,
    PlannerError,
    PlannerTimeoutError,
    plan_files,
    plan_here,
    render_text,
)
from tailor.planner_bridge.benchmark import closure, compare, orderings, render, width
from tailor.planner_bridge.pocl import GOAL, INIT, Planner, flaws_of, linearization
from tailor.planner_bridge.pocl_engine import ALTERNATIVES, scored
from tailor.planner_bridge.pocl_ground import ground
from tailor.planner_bridge.pocl_order import least_commitment, pairs, reorder, sequence_plan
from tailor.planner_bridge.reading import read_problem

ROOT = Path(__file__).resolve().parent.parent
CLASSIC = [("gripper", "p01"), ("gripper", "p02"), ("blocks", "p01"), ("blocks", "p02"), ("logistics", "p01"),
           ("logistics", "p02")]
PARALLEL = ROOT / "tests" / "benchmarks" / "pocl"  # problems with parallel structure (the benchmark's)
MAX_LINEARIZATIONS = 120  # per plan, enumerated in unified-planning's order; all of them for most plans


def bundled(domain: str, problem: str) -> tuple[Path, Path]:
    return ROOT / "domains" / domain / "domain.pddl", ROOT / "domains" / domain / "problems" / f"{problem}.pddl"


def parallel(domain: str, problem: str) -> tuple[Path, Path]:
    folder = PARALLEL / domain
    own = folder / "domain.pddl"
    return own if own.exists() else files(domain, problem)[0], folder / f"{problem}.pddl"


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


# --- issue 34: negative preconditions on static predicates, and engines that give up -----------------------


FERRY_PLAN = (
    ";; domain ferry2, problem ferry2-1, planner tailor-pocl\n"
    "Initial 0 : (boat-at a) (box-at x a) (free) (box-at y b)\n"
    "Step 1 : (pick x a)\n"
    "    0 -> (boat-at a)\n"
    "    0 -> (box-at x a)\n"
    "    0 -> (free)\n"
    "Step 2 : (sail a b)\n"
    "    0 -> (boat-at a)\n"
    "Step 3 : (drop x b)\n"
    "    1 -> (holding x)\n"
    "    2 -> (boat-at b)\n"
    "Step 4 : (pick y b)\n"
    "    0 -> (box-at y b)\n"
    "    2 -> (boat-at b)\n"
    "    3 -> (free)\n"
    "Step 5 : (sail b a)\n"
    "    2 -> (boat-at b)\n"
    "Step 6 : (drop y a)\n"
    "    4 -> (holding y)\n"
    "    5 -> (boat-at a)\n"
    "Goal :\n"
    "    3 -> (box-at x b)\n"
    "    6 -> (box-at y a)\n"
    "Orderings : 1<2 2<3 3<4 4<5 5<6\n"
)


def test_a_negative_precondition_on_a_static_predicate_is_supported_initially():
    # (not (closed ?b)) of sail: no action changes `closed`, and the closed world makes it true initially of
    # every port but c. The grounder had the negation inverted: it kept only the sails *to* c, and POCL said
    # "no plan". (No sail leaves c: the boat never gets there.)
    task = ground(read("ferry2", "p01"))
    sails = {action.args: action for action in task.actions if action.name == "sail"}
    assert sorted(sails) == [("a", "b"), ("b", "a")]
    closed_b = 2 * task.facts.index(("closed", "b")) + 1  # the literal (not (closed b))
    assert closed_b in sails[("a", "b")].static and closed_b not in sails[("a", "b")].preconditions
    assert task.initially(closed_b)


def test_ferry_with_a_closed_port_plans_as_pyperplan_does():
    plan = plan_here(*files("ferry2", "p01"), planner="pocl")
    assert render_text(plan) == FERRY_PLAN
    check_plan(read("ferry2", "p01"), plan)  # valid, and links and orderings checked independently
    optimal = plan_here(*files("ferry2", "p01"), planner="pyperplan-opt")  # A* with LM-cut
    assert len(plan.steps) == len(optimal.steps) == 6


def test_cli_plans_the_ferry_with_pocl(capsys):
    from tailor.cli.main import main

    assert main(["plan", *map(str, files("ferry2", "p01")), "--planner", "pocl"]) == 0
    assert capsys.readouterr().out == FERRY_PLAN


def test_the_engine_gives_up_at_its_node_limit():
    from unified_planning.shortcuts import OneshotPlanner

    from tailor.planner_bridge.pocl_engine import register

    register()
    with OneshotPlanner(name="tailor-pocl", params={"node_limit": 5}) as engine:
        result = engine.solve(read("ferry2", "p01"))
    assert result.status.name == "UNSOLVABLE_INCOMPLETELY" and result.plan is None


@pytest.mark.parametrize("planner", ["pocl", "tailor-pocl"])
def test_an_engine_that_gives_up_is_not_said_to_have_proved_no_plan(monkeypatch, planner):
    from tailor.planner_bridge import solving

    monkeypatch.setattr(solving, "_search", lambda name, problem: ("UNSOLVABLE_INCOMPLETELY", None))
    with pytest.raises(PlannerError) as info:
        plan_here(*files("ferry2", "p01"), planner=planner)
    assert not isinstance(info.value, NoPlanError) and info.value.exit_code == 1
    assert info.value.message == ("planner 'tailor-pocl' gave up without a plan (it did not prove the goal "
                                  "unreachable)")


def test_pyperplan_ending_its_search_is_a_proof(monkeypatch):
    # up-pyperplan reports UNSOLVABLE_INCOMPLETELY even when its complete search has exhausted the states
    from tailor.planner_bridge import solving

    monkeypatch.setattr(solving, "_search", lambda name, problem: ("UNSOLVABLE_INCOMPLETELY", None))
    with pytest.raises(NoPlanError, match="ended its search without one"):
        plan_here(*files("ferry2", "p01"), planner="pyperplan")


def test_worker_timeout_applies_to_pocl():
    bad = ROOT / "tests" / "fixtures" / "pddl" / "bad"
    with pytest.raises(PlannerTimeoutError, match="tailor-pocl"):
        plan_files(bad / "hard_domain.pddl", bad / "hard_problem.pddl", planner="pocl", timeout=0.5)


def test_cli_plan_with_the_pocl_alias_prints_the_golden_text():
    command = [sys.executable, "-m", "tailor.cli", "plan", "soccer", "waypoints", "--planner", "pocl"]
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout == pocl_golden_path("soccer", "waypoints").read_text(encoding="utf-8")


def test_cli_refine_with_pocl(capsys):
    import json

    from tailor.cli.main import main

    assert main(["refine", "soccer", "score", "--planner", "pocl", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["planner"] == "tailor-pocl"
    assert [a["action"] for a in data["refined"]["actions"]] == ["goToPose", "dribbleBall"]  # approachball: goToPose (Ch. 6)


# --- least commitment (planner_bridge.pocl_order and the engine's search for alternatives) ---------------------


def engine_plan(paths: tuple[Path, Path], **params):
    """The engine's CausalLinkPlan of a typed STRIPS problem (no compilation needed) and the parsed problem."""
    from unified_planning.shortcuts import OneshotPlanner

    from tailor.planner_bridge.pocl_engine import register

    register()
    problem = read_problem(*paths)[0]
    with OneshotPlanner(name="tailor-pocl", params=params) as engine:
        result = engine.solve(problem)
    assert result.status.name == "SOLVED_SATISFICING"
    return problem, result.plan


def test_two_towers_are_rebuilt_in_parallel_only_with_least_commitment():
    # two towers of the three-operator blocks world, each reversed: two independent goals. The search's first
    # plan puts c onto d, which ties the towers into one chain; the least-commitment search keeps them apart
    paths = parallel("blocks3", "p01")
    plan = plan_here(*paths, planner="pocl")
    assert (len(plan.steps), orderings(plan), len(closure(plan)), width(plan)) == (6, 4, 6, 2)
    assert plan.orderings == ((1, 2), (2, 3), (4, 5), (5, 6))
    towers = [{a for step in plan.steps[k:k + 3] for a in step.args} for k in (0, 3)]
    assert towers == [{"a", "b", "c"}, {"d", "e", "f"}]
    problem, off = engine_plan(paths, least_commitment=False)  # switched off: the search's first plan
    assert len(off.orderings) == 5 and len(off.steps) == 6  # one chain of six steps: width 1
    assert any({p.object().name for p in step.actual_parameters} >= {"c", "d"} for step in off.steps)
    assert all_linearizations_valid(problem, engine_plan(paths)[1]) == 20  # 6! / (3! 3!): every interleaving


@pytest.mark.parametrize("domain, problem", [("blocks3", "p01"), ("blocks3", "p02"), ("blocks3", "p03"),
                                             ("logistics", "p04")])
def test_parallel_problems_give_sound_plans(domain, problem):
    paths = parallel(domain, problem)
    check_plan(read_problem(*paths)[0], plan_here(*paths, planner="pocl"))


def brute_force_least_pairs(task, steps: tuple[int, ...]) -> int:
    """The fewest ordered pairs of steps over every choice of producers and threat sides (an independent
    enumeration: plain edge sets and a reachability closure, not the post-pass's bit masks)."""
    count = len(steps)
    needs = [(literal, GOAL) for literal in task.goal]
    needs += [(literal, s) for s in range(2, count) for literal in task.actions[steps[s]].preconditions]
    producers = [([INIT] if task.initially(literal) else [])
                 + [s for s in range(2, count) if s != consumer and literal in task.actions[steps[s]].effects]
                 for literal, consumer in needs]
    best = None
    for choice in itertools.product(*producers):
        edges, threats = set(), []
        for (literal, consumer), producer in zip(needs, choice):
            if producer != INIT and consumer != GOAL:
                edges.add((producer, consumer))
            for step in range(2, count):
                if step not in (producer, consumer) and literal ^ 1 in task.actions[steps[step]].effects:
                    threats.append(([(step, producer)] if producer != INIT else [])
                                   + ([(consumer, step)] if consumer != GOAL else []))
        for sides in itertools.product(*threats):
            later = {s: set() for s in range(2, count)}
            for first, second in edges | set(sides):
                later[first].add(second)
            for middle, beyond in later.items():  # Warshall
                for after in later.values():
                    if middle in after:
                        after |= beyond
            if any(s in later[s] for s in later):
                continue  # cyclic
            total = sum(len(after) for after in later.values())
            best = total if best is None else min(best, total)
    return best


@pytest.mark.parametrize("domain, problem", [("blocks3", "p01"), ("blocks3", "p03"), ("logistics", "p04")])
def test_post_pass_deorders_a_total_order_as_far_as_brute_force_can(domain, problem):
    # the least-committed plan's steps, totally ordered and linked from the latest achievers (what a
    # sequential planner gives): the post-pass must reach the fewest ordered pairs any choice of producers
    # and threat sides allows, found by enumerating them all
    paths = parallel(domain, problem)
    task = ground(read_problem(*paths)[0])
    found = Planner(task).search(20, None, ALTERNATIVES, lambda plan: scored(task, plan)).plan
    steps = [found.steps[s] for s in linearization(found)]
    total = sequence_plan(task, steps)
    assert flaws_of(task, total) == [] and pairs(total.before) == len(steps) * (len(steps) - 1) // 2
    stats: dict = {}
    better = reorder(task, total, stats=stats)
    assert flaws_of(task, better) == [] and stats["exact"]
    assert pairs(better.before) == brute_force_least_pairs(task, total.steps) < pairs(total.before)


def test_post_pass_drops_steps_that_support_nothing(tmp_path):
    # e onto f and back again supports nothing the goal needs: the post-pass drops both (the second first)
    problem = tmp_path / "p.pddl"
    problem.write_text("(define (problem detour) (:domain blocks3) (:objects a b e f - block)\n"
                       " (:init (ontable a) (ontable b) (ontable e) (ontable f) (clear a) (clear b) (clear e) (clear f))\n"
                       " (:goal (on a b)))\n", encoding="utf-8")
    task = ground(read_problem(PARALLEL / "blocks3" / "domain.pddl", problem)[0])
    number = {(action.name, action.args): k for k, action in enumerate(task.actions)}
    detour = [number[("move-t-to-b", ("e", "f"))], number[("move-b-to-t", ("e", "f"))],
              number[("move-t-to-b", ("a", "b"))]]
    plan = least_commitment(task, sequence_plan(task, detour))
    assert plan.steps[2:] == (number[("move-t-to-b", ("a", "b"))],) and flaws_of(task, plan) == []
    assert len(reorder(task, sequence_plan(task, detour)).steps) == 5  # reorder alone keeps every step


def test_benchmark_table_compares_side_by_side():
    row = compare([bundled("soccer", "score")])[0]
    assert row["name"] == "soccer/score" and row["first"]["plan"].planner == "tailor-pocl"
    for key in ("first", "search", "second", "post"):  # pocl, its first plan, pyperplan, pyperplan + post-pass
        assert {k: row[key][k] for k in ("steps", "orderings", "pairs", "width")} == \
            {"steps": 2, "orderings": 1, "pairs": 1, "width": 1}

    def counts(steps, orderings, pairs, width):
        return {"steps": steps, "orderings": orderings, "pairs": pairs, "width": width, "seconds": 0.5}

    rows = [{"name": "a/p1", "first": counts(9, 10, 34, 2), "second": counts(11, 10, 55, 1), "post": None},
            {"name": "a/p2", "first": counts(4, 3, 6, 1), "second": counts(4, 3, 6, 1), "post": None},
            {"name": "a/p3", "first": counts(5, 2, 2, 3), "second": counts(5, 3, 4, 2), "post": None},
            {"name": "a/p4", "first": {"error": "no plan within 30 s", "seconds": 30.0}, "second": counts(2, 1, 1, 1),
             "post": None}]
    lines = render(rows).splitlines()
    assert [line.rsplit("|", 1)[1].strip() for line in lines[2:6]] == ["same", "same", "fewer", "-"]
    assert lines[7:] == [
        ("pocl vs pyperplan, 2 problems with parallel structure (width >= 2 in either plan): orderings 1 fewer, "
         "1 same, 0 more; pairs 2 fewer, 0 same, 0 more; width 2 wider, 0 same, 0 narrower"),
        ("pocl vs pyperplan, 3 problems all: orderings 1 fewer, 2 same, 0 more; pairs 2 fewer, 1 same, 0 more; "
         "width 2 wider, 1 same, 0 narrower"),
        "not solved by both: a/p4",
    ]
