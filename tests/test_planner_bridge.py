"""The planner bridge on classic STRIPS domains written for the tests, each plan checked independently:
the steps simulated by unified-planning, every precondition and goal supported by a link from a step that
makes it true, no threatened link, and random linearizations of the partial order valid plans."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from tailor.planner_bridge import (GOAL, INITIAL, AbstractPlan, PDDLTask, plan_files, plan_here, plan_pddl, plan_pddl_here,
                                   read_pddl, render_text)
from tailor.planner_bridge.worker import PlannerProcess

FIXTURES = Path(__file__).parent / "fixtures" / "pddl"
CLASSIC = [
    ("gripper", "p01"),  # negative preconditions and a negative goal: compiled away for pyperplan
    ("gripper", "p02"),
    ("blocks", "p01"),  # Sussman's anomaly
    ("blocks", "p02"),
    ("logistics", "p01"),  # hierarchical types, independent sub-plans
    ("briefcase", "p01"),  # conditional effects under forall: compiled away, plan kept in sequence
]
LINEARIZATIONS = 25  # random linearizations validated per plan
SEED = 20240611


def files(domain: str, problem: str) -> tuple[Path, Path]:
    return FIXTURES / domain / "domain.pddl", FIXTURES / domain / f"{problem}.pddl"


def read(domain: str, problem: str):
    from unified_planning.io import PDDLReader

    return PDDLReader().parse_problem(*map(str, files(domain, problem)))


def instances(problem, plan: AbstractPlan, order: list[int]):
    """The plan's steps, in `order`, as unified-planning action instances of `problem`."""
    from unified_planning.plans import ActionInstance

    objects = problem.environment.expression_manager
    return [
        ActionInstance(
            problem.action(plan.step(i).action), tuple(objects.ObjectExp(problem.object(o)) for o in plan.step(i).args)
        )
        for i in order
    ]


def is_valid(problem, actions) -> bool:
    from unified_planning.plans import SequentialPlan
    from unified_planning.shortcuts import PlanValidator

    with PlanValidator(name="sequential_plan_validator") as validator:
        return validator.validate(problem, SequentialPlan(actions)).status.name == "VALID"


def states_along(problem, actions):
    """The states before the first step and after each step, by unified-planning's simulator."""
    from unified_planning.shortcuts import SequentialSimulator

    with SequentialSimulator(problem) as simulator:
        states = [simulator.get_initial_state()]
        for action in actions:
            states.append(simulator.apply(states[-1], action))
    return states


def conjuncts(node):
    """Top-level conjuncts of a condition."""
    return [c for arg in node.args for c in conjuncts(arg)] if node.is_and() else [node]


def fact_of(node) -> tuple[str, ...]:
    return (node.fluent().name, *(a.object().name for a in node.args))


def grounded(problem, action_instance, state=None):
    """(positive precondition atoms, atoms the step deletes), both as FNodes; a conditional delete counts when
    its condition holds in `state`, the state the step is applied in."""
    action = action_instance.action
    manager = problem.environment.expression_manager
    binding = {manager.ParameterExp(p): v for p, v in zip(action.parameters, action_instance.actual_parameters)}
    needs = [c for p in action.preconditions for c in conjuncts(p.substitute(binding)) if c.is_fluent_exp()]
    may_delete = []
    for effect in action.effects:
        for e in effect.expand_effect(problem) if effect.is_forall() else [effect]:
            condition = e.condition.substitute(binding)
            fired = not e.is_conditional() or state.get_value(condition).is_true()
            if e.is_conditional() and fired:  # what a fired conditional effect needed is linked too
                needs += [c for c in conjuncts(condition) if c.is_fluent_exp()]
            if e.value.is_false() and fired:
                may_delete.append(e.fluent.substitute(binding))
    return needs, may_delete


def closure(plan: AbstractPlan) -> set[tuple[int, int]]:
    before = set(plan.orderings)
    changed = True
    while changed:
        extra = {(a, d) for a, b in before for c, d in before if b == c} - before
        before |= extra
        changed = bool(extra)
    return before


def random_linearization(plan: AbstractPlan, rng: np.random.Generator) -> list[int]:
    preds = {s.id: {a for a, b in plan.orderings if b == s.id} for s in plan.steps}
    order: list[int] = []
    while len(order) < len(plan.steps):
        ready = sorted(i for i, p in preds.items() if i not in order and p <= set(order))
        order.append(ready[rng.integers(len(ready))])
    return order


def check_plan(problem, plan: AbstractPlan) -> None:
    """Every property of a partial-order plan with causal links the issue asks for, computed independently."""
    n = len(plan.steps)
    assert [s.id for s in plan.steps] == list(range(1, n + 1))
    sequence = instances(problem, plan, list(range(1, n + 1)))
    assert is_valid(problem, sequence), "the steps in id order are not a valid plan"
    states = states_along(problem, sequence)

    # every positive precondition and goal conjunct has exactly one link, from a step that makes it true
    expected = []
    for step, instance, state in zip(plan.steps, sequence, states):
        expected += [(fact_of(f), step.id) for f in dict.fromkeys(grounded(problem, instance, state)[0])]
    expected += [(fact_of(g), GOAL) for g in dict.fromkeys(c for g in problem.goals for c in conjuncts(g)) if g.is_fluent_exp()]
    assert sorted((k.fact, str(k.consumer)) for k in plan.links) == sorted((f, str(c)) for f, c in expected)
    manager = problem.environment.expression_manager
    for link in plan.links:
        atom = manager.FluentExp(problem.fluent(link.fact[0]), [problem.object(o) for o in link.fact[1:]])
        at = n + 1 if link.consumer == GOAL else link.consumer
        assert INITIAL <= link.producer < at
        assert states[link.producer].get_value(atom).is_true(), f"{link} producer does not make the fact true"

    # orderings follow the ids, keep producers before consumers, and leave no link threatened
    before = closure(plan)
    assert all(a < b for a, b in before)
    for link in plan.links:
        if link.producer != INITIAL and link.consumer != GOAL:
            assert (link.producer, link.consumer) in before, f"{link} is not ordered"
        for step, instance, state in zip(plan.steps, sequence, states):
            if step.id in (link.producer, link.consumer):
                continue
            if link.fact in {fact_of(d) for d in grounded(problem, instance, state)[1]}:
                first = link.producer != INITIAL and (step.id, link.producer) in before
                last = link.consumer != GOAL and (link.consumer, step.id) in before
                assert first or last, f"step {step.id} threatens {link}"

    rng = np.random.default_rng(SEED)
    for _ in range(LINEARIZATIONS):
        order = random_linearization(plan, rng)
        assert is_valid(problem, instances(problem, plan, order)), f"linearization {order} is not a valid plan"


@pytest.mark.parametrize("domain,problem", CLASSIC)
def test_classic_domains_give_sound_partial_order_plans(domain, problem):
    plan = plan_here(*files(domain, problem))
    assert plan.planner == "pyperplan" and plan.steps
    check_plan(read(domain, problem), plan)


def test_deordering_leaves_independent_steps_unordered():
    # two packages in two cities: moving one does not wait for the other (deterministic plan: plan_files)
    plan = plan_files(*files("logistics", "p01"))
    check_plan(read("logistics", "p01"), plan)
    before = closure(plan)
    n = len(plan.steps)
    unordered = [(a, b) for a in range(1, n + 1) for b in range(a + 1, n + 1) if (a, b) not in before]
    assert unordered, "the logistics plan was left totally ordered"


def test_conditional_effects_keep_the_sequence():
    plan = plan_here(*files("briefcase", "p01"))
    assert plan.orderings == tuple((k, k + 1) for k in range(1, len(plan.steps)))


def test_json_round_trip_is_exact():
    plan = plan_here(*files("blocks", "p01"))
    assert plan.objects and plan.initial  # the plan carries the problem's objects and initial facts
    assert AbstractPlan.from_json(json.loads(json.dumps(plan.to_json(facts=True)))) == plan
    without_facts = AbstractPlan.from_json(plan.to_json())  # the default JSON leaves them out
    assert "objects" not in plan.to_json() and without_facts == dataclasses.replace(plan, objects=(), initial=())


def test_text_rendering_lists_each_steps_links_like_vhpop():
    plan = AbstractPlan.from_json(
        {
            "domain": "d", "problem": "p", "planner": "x",
            "steps": [{"id": 1, "action": "a", "args": ["o1"]}, {"id": 2, "action": "b", "args": []}],
            "links": [
                {"from": 0, "fact": ["p", "o1"], "to": 1},
                {"from": 1, "fact": ["q"], "to": 2},
                {"from": 0, "fact": ["p", "o1"], "to": "goal"},
                {"from": 2, "fact": ["r", "o1", "o2"], "to": "goal"},
            ],
            "orderings": [[1, 2]],
        }
    )
    assert render_text(plan) == (
        ";; domain d, problem p, planner x\n"
        "Initial 0 : (p o1)\n"
        "Step 1 : (a o1)\n"
        "    0 -> (p o1)\n"
        "Step 2 : (b)\n"
        "    1 -> (q)\n"
        "Goal :\n"
        "    0 -> (p o1)\n"
        "    2 -> (r o1 o2)\n"
        "Orderings : 1<2\n"
    )
    assert plan.to_text() == render_text(plan)


def test_a_pair_is_read_once_into_a_task_that_plans_like_the_files():
    domain, problem = files("logistics", "p01")
    task = read_pddl(domain, problem)
    assert (task.domain, task.problem) == (domain, problem)
    assert task.domain_text == domain.read_text(encoding="utf-8") and task.problem_text == problem.read_text(encoding="utf-8")
    assert (task.domain_name, task.problem_name) == (task.signature.name, plan_files(domain, problem).problem)
    assert {"in", "at"} <= set(task.signature.predicates) and "load-truck" in task.signature.actions
    with pytest.raises(dataclasses.FrozenInstanceError):
        task.signature.name = "other"  # type: ignore[misc]
    assert PDDLTask.from_json(json.loads(json.dumps(task.to_json()))) == task  # what the planner child receives
    assert hash(task) == hash(PDDLTask.from_json(task.to_json()))
    assert plan_pddl(task) == plan_files(domain, problem)
    assert plan_pddl_here(task) == plan_here(domain, problem)


def test_a_kept_planner_process_plans_tasks_and_files_alike():
    task = read_pddl(*files("blocks", "p01"))
    with PlannerProcess() as process:
        first = plan_pddl(task, process=process)
        assert process.plan(*files("blocks", "p01"), "pyperplan", None) == first
        assert plan_pddl(read_pddl(*files("gripper", "p01")), process=process).problem == "gripper-four"
