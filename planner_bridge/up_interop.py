"""unified-planning objects in and out: plan a `Problem` built in Python, link a plan any UP engine found, and
give our partial-order plan back as a UP `PartialOrderPlan`, so results feed UP's own tools.

A Problem is planned in this process (no child interpreter: there are no files to hand over). The engines'
choice among equally good plans can depend on Python's string hash seed; start Python with PYTHONHASHSEED=0
for the same plan across runs (files planned through planner_bridge.plan_files always are).
"""

from __future__ import annotations

from tailor.errors import ArgumentTypeError, ArgumentValueError, PlannerError
from tailor.planner_bridge.abstract_plan import GOAL, INITIAL, AbstractPlan
from tailor.planner_bridge.causal import partial_order
from tailor.planner_bridge.in_process import DEFAULT_PLANNER, plan_parsed, problem_facts
from tailor.planner_bridge.solving import validate

GIVEN = "given"  # the planner name of an AbstractPlan made from a plan the caller brought


def check_problem(problem, argument: str = "problem") -> None:
    """A unified-planning Problem, or an ArgumentTypeError naming the argument."""
    from unified_planning.model import Problem

    if not isinstance(problem, Problem):
        raise ArgumentTypeError(f"{argument} must be a unified_planning.model.Problem, not {type(problem).__name__}")


def plan_problem(problem, planner: str = DEFAULT_PLANNER, domain: str | None = None) -> AbstractPlan:
    """Plan a unified-planning Problem with any installed engine (compiling what it lacks), validate the plan
    and link it (Sec. 5.2). `domain` names the domain in the plan (default: the problem's name)."""
    check_problem(problem)
    return plan_parsed(problem, domain or problem.name, planner, file=f"<problem {problem.name}>")


def link_plan(problem, plan, domain: str | None = None, planner: str = GIVEN) -> AbstractPlan:
    """Our partial-order plan with causal links from a plan any unified-planning engine found for `problem`:
    a SequentialPlan, or a PartialOrderPlan (read in one of its linearizations, then deordered). The plan is
    validated first; an invalid plan is a PlannerError."""
    from unified_planning.plans import PartialOrderPlan, PlanKind, SequentialPlan

    check_problem(problem)
    if isinstance(plan, PartialOrderPlan):
        plan = plan.convert_to(PlanKind.SEQUENTIAL_PLAN, problem)
    if not isinstance(plan, SequentialPlan):
        raise ArgumentTypeError("plan must be a unified_planning SequentialPlan or PartialOrderPlan, "
                                f"not {type(plan).__name__}")
    file = f"<problem {problem.name}>"
    validate(problem, plan, planner, file)
    steps, links, orderings = partial_order(problem, plan)
    objects, initial = problem_facts(problem)
    return AbstractPlan(domain or problem.name, problem.name, planner, steps, links, orderings, objects, initial)


def to_partial_order_plan(plan: AbstractPlan, problem):
    """The plan as a unified-planning PartialOrderPlan of `problem`'s actions: an edge for every ordering and
    every causal link between two steps (the links themselves stay in the AbstractPlan)."""
    from unified_planning.plans import ActionInstance, PartialOrderPlan

    check_problem(problem)
    if not isinstance(plan, AbstractPlan):
        raise ArgumentTypeError(f"plan must be a tailor AbstractPlan, not {type(plan).__name__}")
    instances = {}
    for step in plan.steps:
        try:
            action = problem.action(step.action)
            args = tuple(problem.object(name) for name in step.args)
        except Exception:  # UPValueError: the plan is of another problem
            raise ArgumentValueError(f"step {step.id} ({step.action} {' '.join(step.args)}) is not an action "
                                     f"of problem {problem.name!r}") from None
        instances[step.id] = ActionInstance(action, args)
    edges = {(a, b) for a, b in plan.orderings}
    edges |= {(k.producer, k.consumer) for k in plan.links if k.producer != INITIAL and k.consumer != GOAL}
    adjacency = {instances[s.id]: [] for s in plan.steps}
    for a, b in sorted(edges):
        if a not in instances or b not in instances:
            raise PlannerError(f"the plan orders step {a} before {b}, which it does not have")
        adjacency[instances[a]].append(instances[b])
    return PartialOrderPlan(adjacency, problem.environment)
