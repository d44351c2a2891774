"""Solve a unified-planning Problem with any installed OneshotPlanner and return a validated sequential plan.

When the engine cannot handle a feature of the problem (negative conditions, conditional effects, equality,
quantifiers, ...) the problem goes through the shortest chain of unified-planning's compilers that makes it
supported (found by search, see compile_for), and the plan is mapped back to the original actions.
Timeouts are enforced by planner_bridge.worker, which runs all of this in a child process.
"""

from __future__ import annotations

import contextlib
import io
import warnings
from collections.abc import Callable
from dataclasses import dataclass

from tailor.errors import NoPlanError, PlannerError, PlannerTimeoutError, PlannerUnavailableError

# Other names accepted for an engine: `--planner pocl` is our POCL engine (planner_bridge.pocl_engine).
ALIASES = {"pocl": "tailor-pocl"}

# The compilations a chain is built from, in the order they are tried at each length; grounding last, as it
# is the costliest and the others keep the actions' parameters. Chains are at most MAX_CHAIN long.
COMPILATIONS = (
    "QUANTIFIERS_REMOVING",
    "CONDITIONAL_EFFECTS_REMOVING",
    "DISJUNCTIVE_CONDITIONS_REMOVING",
    "NEGATIVE_CONDITIONS_REMOVING",
    "USERTYPE_FLUENTS_REMOVING",
    "BOUNDED_TYPES_REMOVING",
    "STATE_INVARIANTS_REMOVING",
    "GROUNDING",
)
MAX_CHAIN = 4
# Engines whose search ends without a plan only when it has exhausted every reachable state, so that ending
# is a proof, though they report UNSOLVABLE_INCOMPLETELY: up-pyperplan 1.1 compares its search function with
# search names and so never says UNSOLVABLE_PROVEN (tailor runs it with its default, complete weighted A*;
# pyperplan-opt runs A*). Any other engine's UNSOLVABLE_INCOMPLETELY is an engine that gave up, not a proof.
EXHAUSTIVE = frozenset({"pyperplan", "pyperplan-opt"})


@dataclass(frozen=True)
class Compiled:
    """A problem the engine supports, the compilations that made it (in order; empty when none was needed)
    and the functions that map its action instances back, one per compilation."""

    problem: object
    chain: tuple[str, ...] = ()
    map_backs: tuple[Callable, ...] = ()


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


def _compile(problem, kind_name: str):
    """The CompilerResult of one compilation, or None when no installed compiler accepts or handles the problem."""
    from unified_planning.engines import CompilationKind
    from unified_planning.exceptions import UPException
    from unified_planning.shortcuts import Compiler

    kind = CompilationKind[kind_name]
    try:
        compiler = Compiler(problem_kind=problem.kind, compilation_kind=kind)
    except UPException:
        return None  # no compiler of this kind accepts the problem as it is now
    with compiler, contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return compiler.compile(problem, kind)
        except MemoryError:
            raise
        except Exception:  # a compiler failing on its own input (unified-planning 1.3's quantifier remover
            return None  # asks for a ProblemKind method that does not exist): one chain less to try


def compile_for(planner: str, problem, file: str) -> Compiled:
    """Find the shortest chain of compilations after which the engine supports the problem (breadth first,
    each step judged by the kind of the problem it really produced, not by what the compiler promises)."""
    engine = _engine_class(planner)
    if engine.supports(problem.kind):
        return Compiled(problem)
    frontier = [Compiled(problem)]
    seen = {frozenset(problem.kind.features)}
    for _ in range(MAX_CHAIN):
        longer = []
        for current in frontier:
            for kind_name in COMPILATIONS:
                result = _compile(current.problem, kind_name)
                if result is None or frozenset(result.problem.kind.features) in seen:
                    continue  # it failed, removed nothing, or reached a kind already tried
                seen.add(frozenset(result.problem.kind.features))
                step = Compiled(
                    result.problem,
                    current.chain + (kind_name,),
                    current.map_backs + (result.map_back_action_instance,),
                )
                if engine.supports(step.problem.kind):
                    return step
                longer.append(step)
        frontier = longer
    lacking = sorted(problem.kind.features - engine.supported_kind().features)
    raise PlannerUnavailableError(
        f"planner '{planner}' cannot solve this problem: no compilation removes {', '.join(lacking)} "
        f"(chains of up to {MAX_CHAIN} tried)",
        file,
    )


def _search(planner: str, problem):
    """Run the engine quietly; return its status name and its plan (or None)."""
    from unified_planning.shortcuts import OneshotPlanner

    with contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with OneshotPlanner(name=planner) as engine:
            result = engine.solve(problem)
    return result.status.name, result.plan


def _contradictory_goal(problem) -> bool:
    """Whether the problem's goals together simplify to false (e.g. a fact and its negation)."""
    if not problem.goals:
        return False
    env = problem.environment
    return env.simplifier.simplify(env.expression_manager.And(problem.goals)).is_false()


def solve(problem, planner: str, file: str, on_search: Callable[[], None] | None = None):
    """Plan for `problem` (the original, uncompiled one); return a validated SequentialPlan of its actions,
    or, from an engine that finds causal links (tailor-pocl), a validated CausalLinkPlan, and the chain of
    compilations used (empty when the engine supports the problem as it is); `on_search` is called when the
    engine starts searching."""
    from unified_planning.plans import ActionInstance, SequentialPlan

    planner = canonical(planner)
    if _contradictory_goal(problem):  # some engines refuse a goal of `false` instead of finding no plan
        raise NoPlanError("no plan exists (the goal is contradictory: it simplifies to false)", file)
    found_chain = compile_for(planner, problem, file)
    compiled, map_backs, chain = found_chain.problem, found_chain.map_backs, found_chain.chain
    if on_search is not None:
        on_search()
    try:
        status, found = _search(planner, compiled)
    except (KeyboardInterrupt, MemoryError, PlannerError):
        raise
    except Exception as exc:
        said = " ".join(str(exc).split())  # one line, whatever the engine's message looks like
        raise PlannerError(f"planner '{planner}' failed: {type(exc).__name__}: {said}", file) from None
    if status == "TIMEOUT":
        raise PlannerTimeoutError(f"planner '{planner}' ran out of time", file)
    if status == "UNSOLVABLE_PROVEN":
        raise NoPlanError(f"no plan exists (planner '{planner}' proved the goal unreachable)", file)
    if status == "UNSOLVABLE_INCOMPLETELY" and planner in EXHAUSTIVE:
        raise NoPlanError(f"no plan exists (planner '{planner}' ended its search without one)", file)
    if status == "UNSOLVABLE_INCOMPLETELY":  # a search limit or an incomplete search: "no plan" is not proved
        raise PlannerError(f"planner '{planner}' gave up without a plan (it did not prove the goal unreachable)",
                           file)
    if status == "UNSUPPORTED_PROBLEM":
        raise PlannerUnavailableError(f"planner '{planner}' does not support this problem", file)
    if found is None:
        raise PlannerError(f"planner '{planner}' returned no plan (status {status})", file)
    if hasattr(found, "causal_links"):
        if "GROUNDING" not in chain:  # a ground problem's links name ground fluents: deorder its steps instead
            return _mapped_back(problem, found, map_backs, planner, file), chain
        found = SequentialPlan(list(found.steps), compiled.environment)

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
    return sequential, chain


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
