"""The POCL planner (planner_bridge.pocl) as a unified-planning engine, `OneshotPlanner(name="tailor-pocl")`.

It declares typed STRIPS with negative preconditions and equality, and returns a `CausalLinkPlan`: a
unified-planning PartialOrderPlan that also carries the plan's causal links, so that the AbstractPlan takes
them from the planner instead of deordering a sequence. `register()` adds it to unified-planning's factory.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import IO

import unified_planning as up
from unified_planning.engines import Engine, PlanGenerationResult, PlanGenerationResultStatus
from unified_planning.engines.mixins import OneshotPlannerMixin
from unified_planning.model import ProblemKind
from unified_planning.plans import ActionInstance, PartialOrderPlan

from tailor.planner_bridge.abstract_plan import GOAL, INITIAL, CausalLink
from tailor.planner_bridge.causal import transitive_reduction
from tailor.engine_registration import ENGINE_NAME
from tailor.planner_bridge.pocl import GOAL as POCL_GOAL
from tailor.planner_bridge.pocl import INIT as POCL_INIT
from tailor.planner_bridge.pocl import Planner, flaws_of, linearization
from tailor.planner_bridge.pocl_ground import UnsupportedCondition, ground
from tailor.planner_bridge.pocl_order import least_commitment, pairs, reduced_orderings

# With least commitment on: expansions after the first plan, looking for other plans of no more steps that the
# post-pass can leave less ordered (a node budget, not a clock: the same problem gives the same plan).
ALTERNATIVES = 1000
ALIASES = {"pocl": ENGINE_NAME}
STATUS = {
    "solved": PlanGenerationResultStatus.SOLVED_SATISFICING,
    "unsolvable": PlanGenerationResultStatus.UNSOLVABLE_PROVEN,
    "timeout": PlanGenerationResultStatus.TIMEOUT,
    "limit": PlanGenerationResultStatus.UNSOLVABLE_INCOMPLETELY,
}


class CausalLinkPlan(PartialOrderPlan):
    """A partial-order plan with its causal links: step k is `steps[k - 1]` (1..n, a valid order), producer 0
    the initial state, consumer "goal" the goal; `orderings` are pairs (earlier, later) of step numbers."""

    def __init__(self, steps: list[ActionInstance], orderings, causal_links, environment=None):
        after: dict[ActionInstance, list[ActionInstance]] = {step: [] for step in steps}
        for first, second in orderings:
            after[steps[first - 1]].append(steps[second - 1])
        super().__init__(after, environment)
        self.steps = tuple(steps)
        self.orderings = tuple(orderings)
        self.causal_links = tuple(causal_links)

    def replace_action_instances(self, replace_function: Callable[[ActionInstance], ActionInstance | None]):
        """The same plan over the mapped steps (a compiler's map back); a step mapped to None leaves the plan,
        with its causal links, and the orderings through it are kept."""
        mapped = [replace_function(step) for step in self.steps]
        keep = [k for k, step in enumerate(mapped, start=1) if step is not None]
        number = {old: new for new, old in enumerate(keep, start=1)}
        closure = _closure(self.orderings)
        orderings = transitive_reduction({(number[a], number[b]) for a, b in closure if a in number and b in number})
        links = [
            CausalLink(INITIAL if link.producer == INITIAL else number[link.producer], link.fact,
                       GOAL if link.consumer == GOAL else number[link.consumer])
            for link in self.causal_links
            if link.producer in (INITIAL, *number) and link.consumer in (GOAL, *number)
        ]
        steps = [mapped[k - 1] for k in keep]
        return CausalLinkPlan(steps, orderings, links, steps[0].action.environment if steps else self._environment)


def _closure(orderings) -> set[tuple[int, int]]:
    closure = set(orderings)
    while True:
        extra = {(a, d) for a, b in closure for c, d in closure if b == c} - closure
        if not extra:
            return closure
        closure |= extra


class POCLEngine(Engine, OneshotPlannerMixin):
    """Partial-order causal-link planning (VHPOP's approach): ADDR heuristic, LCFR flaw selection, A*, then
    the least-commitment post-pass (planner_bridge.pocl_order; `least_commitment=False` returns the search's
    plan as found)."""

    def __init__(self, heuristic: str = "addr", flaw_selection: str = "lcfr", weight: float = 1.0,
                 node_limit: int | None = None, least_commitment: bool = True, alternatives: int = ALTERNATIVES,
                 **kwargs):
        Engine.__init__(self)
        OneshotPlannerMixin.__init__(self)
        self._options = {"heuristic": heuristic, "strategy": flaw_selection, "weight": weight}
        self._node_limit = node_limit
        self._least_commitment = least_commitment
        self._alternatives = alternatives

    @property
    def name(self) -> str:
        return ENGINE_NAME

    @staticmethod
    def supported_kind() -> ProblemKind:
        kind = ProblemKind(version=2)
        kind.set_problem_class("ACTION_BASED")
        kind.set_typing("FLAT_TYPING")
        kind.set_typing("HIERARCHICAL_TYPING")
        kind.set_conditions_kind("NEGATIVE_CONDITIONS")
        kind.set_conditions_kind("EQUALITIES")
        kind.set_quality_metrics("PLAN_LENGTH")
        return kind

    @staticmethod
    def supports(problem_kind: ProblemKind) -> bool:
        return problem_kind <= POCLEngine.supported_kind()

    @staticmethod
    def satisfies(optimality_guarantee) -> bool:
        return optimality_guarantee == up.engines.OptimalityGuarantee.SATISFICING

    def _solve(self, problem, heuristic=None, timeout: float | None = None, output_stream: IO[str] | None = None):
        start = time.monotonic()
        try:
            task = ground(problem)
        except UnsupportedCondition:
            return PlanGenerationResult(PlanGenerationResultStatus.UNSUPPORTED_PROBLEM, None, self.name)
        planner = Planner(task, **self._options)
        remaining = None if timeout is None else max(0.0, timeout - (time.monotonic() - start))
        if self._least_commitment:
            result = planner.search(remaining, self._node_limit, self._alternatives, lambda plan: scored(task, plan))
        else:
            result = planner.search(remaining, self._node_limit)
        metrics = {"expanded": str(result.expanded), "generated": str(result.generated),
                   "solutions": str(result.solutions), "engine_internal_time": f"{time.monotonic() - start:.6f}"}
        if result.plan is None:
            return PlanGenerationResult(STATUS[result.status], None, self.name, metrics=metrics)
        plan = result.plan
        problems = flaws_of(task, plan)
        if problems:
            return PlanGenerationResult(PlanGenerationResultStatus.INTERNAL_ERROR, None, self.name, metrics=metrics,
                                        log_messages=[up.engines.LogMessage(up.engines.LogLevel.ERROR, problems[0])])
        return PlanGenerationResult(STATUS["solved"], causal_link_plan(problem, task, plan), self.name,
                                    metrics=metrics)


def scored(task, plan):
    """The plan after the least-commitment post-pass, scored: fewer steps, then fewer ordered pairs, then
    fewer orderings after transitive reduction."""
    better = least_commitment(task, plan)
    return (len(better.steps), pairs(better.before), reduced_orderings(better.before)), better


def causal_link_plan(problem, task, plan) -> CausalLinkPlan:
    """The search's partial plan as a CausalLinkPlan of `problem`'s actions, steps numbered in a valid order."""
    order = linearization(plan)
    number = {step: k for k, step in enumerate(order, start=1)} | {POCL_INIT: INITIAL, POCL_GOAL: GOAL}
    objects = problem.environment.expression_manager
    steps = []
    for step in order:
        action = task.actions[plan.steps[step]]
        arguments = tuple(objects.ObjectExp(problem.object(name)) for name in action.args)
        steps.append(ActionInstance(problem.action(action.name), arguments))
    orderings = transitive_reduction({(number[a], number[b]) for b in order for a in order if plan.precedes(a, b)})
    by_consumer: dict = {}
    for producer, literal, consumer in plan.links:
        if not literal & 1:  # AbstractPlan links hold facts; negative literals are protected by the orderings
            by_consumer.setdefault(consumer, {})[literal] = producer
    links = []
    for consumer in [*order, POCL_GOAL]:
        needs = task.goal
        if consumer != POCL_GOAL:
            needs = task.actions[plan.steps[consumer]].conditions  # static ones too: supported initially
        for literal in needs:
            if literal & 1:
                continue
            producer = by_consumer.get(consumer, {}).get(literal, POCL_INIT)
            links.append(CausalLink(number[producer], task.facts[literal >> 1], number[consumer]))
    return CausalLinkPlan(steps, orderings, links, problem.environment)


def register() -> None:
    """Add the engine to unified-planning's factory (once per environment)."""
    factory = up.environment.get_environment().factory
    if ENGINE_NAME not in factory.engines:
        factory.add_engine(ENGINE_NAME, __name__, "POCLEngine")
