"""Solve a unified-planning Problem with any installed OneshotPlanner and return a validated sequential plan.

When the engine cannot handle a feature of the problem (negative conditions, conditional effects, ...) the
problem goes through unified-planning's compilers first and the plan is mapped back to the original actions.
Timeouts are enforced by planner_bridge.worker, which runs all of this in a child process.
"""

from __future__ import annotations

import contextlib
import io
import warnings
from typing import Callable

from tailor.planner_bridge.errors import NoPlanError, PlannerError, PlannerTimeoutError, PlannerUnavailableError

# Other names accepted for an engine: `--planner pocl` is our POCL engine (planner_bridge.pocl_engine).
ALIASES = {"pocl": "tailor-pocl"}

# Compilations tried, in this order, until the engine supports what is left of the problem.
REMOVALS = (
    "QUANTIFIERS_REMOVING",
    "CONDITIONAL_EFFECTS_REMOVING",
    "DISJUNCTIVE_CONDITIONS_REMOVING",
    "NEGATIVE_CONDITIONS_REMOVING",
    "USERTYPE_FLUENTS_REMOVING",
    "BOUNDED_TYPES_REMOVING",
    "STATE_INVARIANTS_REMOVING",
)


def canonical(planner: str) -> str:
    """The engine name behind an alias (`pocl` is `tailor-pocl`); other names are kept."""
    return ALIASES.get(planner, planner)


def oneshot_planners() -> list[str]:
    """Names of the installed unified-planning engines that can plan (OneshotPlanner), ours included."""
    from unified_planning.engines.mixins import OneshotPlannerMixin
    from unified_planning.shortcuts import get_environment

    from tailor.planner_bridge.pocl_engine import register

    register()
    factory = get_environment().factory
    return sorted(name for name in factory.engines if issubclass(factory.engine(name), OneshotPlannerMixin))


def _engine_class(planner: str):
    from unified_planning.shortcuts import get_environment

    names = oneshot_planners()
    if planner not in names:
        raise PlannerUnavailableError(f"unknown planner '{planner}' (installed: {', '.join(names) or 'none'})")
    return get_environment().factory.engine(planner)


def compile_for(planner: str, problem, file: str):
    """Remove the features the engine lacks; return the problem it can solve and the map-back functions."""
    from unified_planning.engines import CompilationKind
    from unified_planning.exceptions import UPException
    from unified_planning.shortcuts import Compiler

    engine = _engine_class(planner)
    map_backs = []
    for kind_name in REMOVALS:
        if engine.supports(problem.kind):
            break
        kind = CompilationKind[kind_name]
        try:
            compiler = Compiler(problem_kind=problem.kind, compilation_kind=kind)
        except UPException:
            continue  # no compiler of this kind accepts the problem as it is now
        with compiler:
            if compiler.resulting_problem_kind(problem.kind, kind) == problem.kind:
                continue  # nothing for this compilation to remove
            result = compiler.compile(problem, kind)
        problem = result.problem
        map_backs.append(result.map_back_action_instance)
    if not engine.supports(problem.kind):
        lacking = sorted(problem.kind.features - engine.supported_kind().features)
        raise PlannerUnavailableError(
            f"planner '{planner}' cannot solve this problem: no compilation removes {', '.join(lacking)}", file
        )
    return problem, map_backs


def _search(planner: str, problem):
    """Run the engine quietly; return its status name and its plan (or None)."""
    from unified_planning.shortcuts import OneshotPlanner

    with contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with OneshotPlanner(name=planner) as engine:
            result = engine.solve(problem)
    return result.status.name, result.plan


def solve(problem, planner: str, file: str, on_search: Callable[[], None] | None = None):
    """Plan for `problem` (the original, uncompiled one) and return a validated SequentialPlan of its actions,
    or, from an engine that finds causal links (tailor-pocl), a validated CausalLinkPlan; `on_search` is called
    when the engine starts searching (the worker starts its timeout clock there)."""
    from unified_planning.plans import ActionInstance, SequentialPlan

    planner = canonical(planner)
    compiled, map_backs = compile_for(planner, problem, file)
    if on_search is not None:
        on_search()
    try:
        status, found = _search(planner, compiled)
    except (KeyboardInterrupt, PlannerError):
        raise
    except Exception as exc:
        raise PlannerError(f"planner '{planner}' failed: {type(exc).__name__}: {exc}", file) from None
    if status == "TIMEOUT":
        raise PlannerTimeoutError(f"planner '{planner}' ran out of time", file)
    if status == "UNSOLVABLE_PROVEN":
        raise NoPlanError(f"no plan exists (planner '{planner}' proved the goal unreachable)", file)
    if status == "UNSOLVABLE_INCOMPLETELY":
        raise NoPlanError(f"no plan exists (planner '{planner}' ended its search without one)", file)
    if status == "UNSUPPORTED_PROBLEM":
        raise PlannerUnavailableError(f"planner '{planner}' does not support this problem", file)
    if found is None:
        raise PlannerError(f"planner '{planner}' returned no plan (status {status})", file)
    if hasattr(found, "causal_links"):
        return _mapped_back(problem, found, map_backs, planner, file)

    actions = [(a.action.name, [p.object().name for p in a.actual_parameters]) for a in found.actions]
    objects = compiled.environment.expression_manager
    plan = []
    for name, args in actions:
        step = ActionInstance(compiled.action(name), tuple(objects.ObjectExp(compiled.object(o)) for o in args))
        for map_back in reversed(map_backs):
            step = map_back(step) if step is not None else None
        if step is not None:  # compilers may add bookkeeping actions that map back to nothing
            plan.append(step)
    sequential = SequentialPlan(plan)
    validate(problem, sequential, planner, file)
    return sequential


def _mapped_back(problem, plan, map_backs, planner: str, file: str):
    """A CausalLinkPlan of the compiled problem as one of the original actions, validated in its step order."""
    from unified_planning.plans import SequentialPlan

    def back(step):
        for map_back in reversed(map_backs):
            step = map_back(step) if step is not None else None
        return step

    if map_backs:
        plan = plan.replace_action_instances(back)
    validate(problem, SequentialPlan(list(plan.steps), problem.environment), planner, file)
    return plan


def validate(problem, plan, planner: str, file: str) -> None:
    """Check the plan with unified-planning's validator against the original problem."""
    from unified_planning.engines import ValidationResultStatus
    from unified_planning.shortcuts import PlanValidator

    with PlanValidator(problem_kind=problem.kind, plan_kind=plan.kind) as validator:
        result = validator.validate(problem, plan)
    if result.status != ValidationResultStatus.VALID:
        reason = getattr(result, "reason", None) or result.log_messages or "unknown reason"
        raise PlannerError(f"planner '{planner}' returned an invalid plan: {reason}", file)
