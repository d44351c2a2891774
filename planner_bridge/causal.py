"""Causal links and ordering constraints of a partial-order plan, built from a valid sequential plan.

For each positive precondition of each step (and each goal fact) the producer is the latest earlier step that
adds the fact, or the initial state (0). The orderings keep every producer before its consumer and every step
that deletes a linked fact outside the link (before the producer or after the consumer, on the side where the
sequential plan has it); negative preconditions are protected the same way against steps that add the fact.
Then no link is threatened and every linearization of the orderings is a valid plan (Sec. 5.2, Fig. 5.6).
Plans of actions with conditional or quantified effects, or with conditions other than conjunctions of
literals, keep their sequential order: a total order is a valid partial order and cannot threaten a link;
their links name the facts the chosen disjunct, quantifier instance or fired conditional effect used.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import product

from tailor.planner_bridge.abstract_plan import GOAL, INITIAL, CausalLink, Step

Fact = tuple[str, ...]


@dataclass
class Needs:
    """What a step (or the goal) requires: positive facts with their ground expressions, negated facts."""

    positive: list[tuple[Fact, object]] = field(default_factory=list)
    negative: list[Fact] = field(default_factory=list)
    simple: bool = True  # a conjunction of literals only


@dataclass
class GroundStep:
    step: Step
    needs: Needs
    adds: set[Fact]
    deletes: set[Fact]
    simple: bool


def _fact(node) -> Fact | None:
    if not node.is_fluent_exp() or not all(arg.is_object_exp() for arg in node.args):
        return None
    return (node.fluent().name, *(arg.object().name for arg in node.args))


def _needs(node, needs: Needs) -> Needs:
    """Collect the literals of a ground condition; anything else marks it as not simple."""
    if node.is_and():
        for arg in node.args:
            _needs(arg, needs)
    elif node.is_bool_constant() and node.bool_constant_value():
        pass
    elif _fact(node) is not None:
        needs.positive.append((_fact(node), node))
    elif node.is_not() and _fact(node.arg(0)) is not None:
        needs.negative.append(_fact(node.arg(0)))
    else:
        needs.simple = False
    return needs


def ground_steps(plan) -> list[GroundStep]:
    """Substitute each action instance's objects into its action's conditions and effects."""
    steps = []
    for number, instance in enumerate(plan.actions, start=1):
        action = instance.action
        manager = action.environment.expression_manager
        binding = {manager.ParameterExp(p): v for p, v in zip(action.parameters, instance.actual_parameters)}
        needs = Needs()
        for condition in action.preconditions:
            _needs(condition.substitute(binding), needs)
        adds, deletes, simple = set(), set(), needs.simple
        for effect in action.effects:
            fact = _fact(effect.fluent.substitute(binding))
            if effect.is_conditional() or effect.is_forall() or fact is None or not effect.value.is_bool_constant():
                simple = False
                continue
            (adds if effect.value.bool_constant_value() else deletes).add(fact)
        deletes -= adds  # PDDL applies deletes before adds
        args = tuple(str(p.object().name) if p.is_object_exp() else str(p) for p in instance.actual_parameters)
        steps.append(GroundStep(Step(number, action.name, args), needs, adds, deletes, simple))
    return steps


def _goal_needs(problem) -> Needs:
    needs = Needs()
    for goal in problem.goals:
        _needs(goal, needs)
    return needs


def _unique(facts):
    seen = []
    for fact in facts:
        if fact not in seen:
            seen.append(fact)
    return seen


def _consumers(steps: list[GroundStep], goal: Needs):
    """(consumer id, sequence position, needs) for every step, then the goal at position n + 1."""
    yield from ((s.step.id, s.step.id, s.needs) for s in steps)
    yield GOAL, len(steps) + 1, goal


def _protect(steps, producer: int, at: int, threats, orderings: set[tuple[int, int]]) -> None:
    """Order producer before the consumer at position `at`, and each threat outside the link."""
    n = len(steps)
    if producer != INITIAL and at <= n:
        orderings.add((producer, at))
    for t in threats:
        if t in (producer, at):
            continue
        if t < producer:
            orderings.add((t, producer))
        elif t > at and at <= n:
            orderings.add((at, t))
        elif producer < t < at:  # impossible in a valid sequential plan
            raise AssertionError(f"step {t} threatens a link from {producer} to {at}")


def partial_order(problem, plan) -> tuple[tuple[Step, ...], tuple[CausalLink, ...], tuple[tuple[int, int], ...]]:
    """Steps, causal links and (transitively reduced) orderings of the validated sequential `plan`."""
    steps = ground_steps(plan)
    goal = _goal_needs(problem)
    if not (goal.simple and all(s.simple for s in steps)):
        return _total_order(problem, plan, steps, goal)
    links: list[CausalLink] = []
    orderings: set[tuple[int, int]] = set()
    for consumer, at, needs in _consumers(steps, goal):
        for fact in _unique(f for f, _ in needs.positive):
            producer = max((s.step.id for s in steps[: at - 1] if fact in s.adds), default=INITIAL)
            links.append(CausalLink(producer, fact, consumer))
            _protect(steps, producer, at, [s.step.id for s in steps if fact in s.deletes], orderings)
        for fact in _unique(needs.negative):
            producer = max((s.step.id for s in steps[: at - 1] if fact in s.deletes), default=INITIAL)
            _protect(steps, producer, at, [s.step.id for s in steps if fact in s.adds], orderings)
    return tuple(s.step for s in steps), sorted_links(links), transitive_reduction(orderings)


def _total_order(problem, plan, steps, goal):
    """Sequential order kept; each fact a step (or the goal) used is linked to the last step that made it true.
    The facts used are found in the state the step was applied in: all conjuncts, the first disjunct (or
    existential instance) that held, every universal instance, the consequent of an implication whose
    antecedent held, and the conditions of the conditional effects that fired."""
    from unified_planning.model.walkers import StateEvaluator
    from unified_planning.shortcuts import SequentialSimulator

    with SequentialSimulator(problem) as simulator:
        states = [simulator.get_initial_state()]
        for instance in plan.actions:
            states.append(simulator.apply(states[-1], instance))
    evaluator = StateEvaluator(problem)

    def holds(node, index: int) -> bool:
        return evaluator.evaluate(node, states[index]).bool_constant_value()

    links = []
    for consumer, at, _ in _consumers(steps, goal):
        conditions = _goal_conditions(problem) if consumer == GOAL else _step_conditions(problem, plan.actions[at - 1])
        used: dict[Fact, object] = {}
        for condition in conditions:
            for fact, node in _used_facts(problem, condition, lambda n, at=at: holds(n, at - 1)):
                used.setdefault(fact, node)
        for fact, node in used.items():
            made_true = [k for k in range(1, at) if holds(node, k) and not holds(node, k - 1)]
            links.append(CausalLink(made_true[-1] if made_true else INITIAL, fact, consumer))
    chain = tuple((k, k + 1) for k in range(1, len(steps)))
    return tuple(s.step for s in steps), sorted_links(links), chain


def _goal_conditions(problem) -> list:
    return list(problem.goals)


def _step_conditions(problem, instance) -> list:
    """A ground step's preconditions, then the conditions of its conditional effects (universal ones expanded);
    an effect's condition that does not hold is skipped by _used_facts' caller (it is evaluated false)."""
    action = instance.action
    manager = action.environment.expression_manager
    binding = {manager.ParameterExp(p): v for p, v in zip(action.parameters, instance.actual_parameters)}
    conditions = [c.substitute(binding) for c in action.preconditions]
    for effect in action.effects:
        for expanded in effect.expand_effect(problem):
            if expanded.is_conditional():
                conditions.append(_Fired(expanded.condition.substitute(binding)))
    return conditions


@dataclass(frozen=True)
class _Fired:
    """The condition of a conditional effect: it was needed only if it held (the effect fired)."""

    condition: object


def _used_facts(problem, node, true) -> list[tuple[Fact, object]]:
    """The positive ground facts that made `node` true (see _total_order); `true(n)` evaluates n in the state."""
    if isinstance(node, _Fired):
        return _used_facts(problem, node.condition, true) if true(node.condition) else []
    fact = _fact(node)
    if fact is not None:
        return [(fact, node)] if true(node) else []
    if node.is_and():
        return [used for arg in node.args for used in _used_facts(problem, arg, true)]
    if node.is_or():
        chosen = next((arg for arg in node.args if true(arg)), None)
        return [] if chosen is None else _used_facts(problem, chosen, true)
    if node.is_implies():
        return _used_facts(problem, node.arg(1), true) if true(node.arg(0)) else []
    if node.is_exists() or node.is_forall():
        instances = _instances(problem, node)
        if node.is_exists():
            chosen = next((i for i in instances if true(i)), None)
            return [] if chosen is None else _used_facts(problem, chosen, true)
        return [used for i in instances for used in _used_facts(problem, i, true)]
    return []  # negations, equalities, constants: no positive fact to link


def _instances(problem, node) -> list:
    """The ground instances of a quantified formula's body, one per combination of objects."""
    manager = problem.environment.expression_manager
    variables = node.variables()
    choices = [list(problem.objects(v.type)) for v in variables]
    return [
        node.arg(0).substitute({manager.VariableExp(v): manager.ObjectExp(o) for v, o in zip(variables, objects)})
        for objects in product(*choices)
    ]


def sorted_links(links: list[CausalLink]) -> tuple[CausalLink, ...]:
    """Links grouped by consumer (steps in order, then the goal), each group by producer; stable otherwise."""

    def key(link: CausalLink) -> tuple[int, int]:
        return (10**9 if link.consumer == GOAL else int(link.consumer), link.producer)

    return tuple(sorted(links, key=key))


def transitive_reduction(orderings: set[tuple[int, int]]) -> tuple[tuple[int, int], ...]:
    """The fewest pairs with the same transitive closure, sorted (orderings always go from lower to higher id)."""
    after: dict[int, set[int]] = {}
    for a, b in orderings:
        after.setdefault(a, set()).add(b)

    def reachable(start: int) -> set[int]:
        seen, todo = set(), list(after.get(start, ()))
        while todo:
            node = todo.pop()
            if node not in seen:
                seen.add(node)
                todo.extend(after.get(node, ()))
        return seen

    kept = set()
    for a, b in orderings:
        if not any(b in reachable(c) for c in after[a] if c != b):
            kept.add((a, b))
    return tuple(sorted(kept))
