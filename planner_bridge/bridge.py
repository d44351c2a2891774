"""The planner bridge read top to bottom: PDDL files in, a validated partial-order plan with causal links out."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Callable

from tailor.planner_bridge.abstract_plan import AbstractPlan, CausalLink, Step
from tailor.planner_bridge.causal import partial_order, sorted_links
from tailor.planner_bridge.reading import check_files, read_problem
from tailor.planner_bridge.solving import canonical, solve

DEFAULT_PLANNER = "pyperplan"
# The planner process's address space (RLIMIT_AS, see planner_bridge.worker): a bound, so a huge problem ends
# in one line instead of swapping the machine; its imports alone take about 0.4 GB.
MEMORY_LIMIT_GB = 8.0


def plan_files(
    domain: str | Path,
    problem: str | Path,
    planner: str = DEFAULT_PLANNER,
    timeout: float | None = None,
    memory_gb: float | None = MEMORY_LIMIT_GB,
    process=None,
) -> AbstractPlan:
    """Plan the PDDL pair: the same files give the same plan on every run (it runs in a child process with a
    fixed hash seed, see planner_bridge.worker); `timeout` limits parsing, compiling and search together, in
    seconds, and `memory_gb` the planner's address space (None: no limit). `process` is a planner child kept
    for many requests (worker.PlannerProcess, with its own memory limit); by default a new one per call.

    Raises the errors of tailor.errors: InputFileError, PDDLSyntaxError, PDDLSemanticError, NoPlanError,
    PlannerTimeoutError, PlannerUnavailableError (and PlannerError itself for an engine's failure, or when the
    planner runs out of memory).
    """
    from tailor.planner_bridge.worker import plan_in_worker

    for name, limit in (("timeout", timeout), ("memory limit", memory_gb)):
        if limit is not None and not (limit > 0 and math.isfinite(limit)):
            raise ValueError(f"the {name} must be positive and finite (None for no limit), not {limit}")
    domain, problem = Path(domain), Path(problem)
    check_files(domain, problem)  # bad files fail here, fast, before a child process is started
    if process is not None:
        return process.plan(domain, problem, canonical(planner), timeout)
    return plan_in_worker(domain, problem, canonical(planner), timeout, memory_gb)


def plan_here(
    domain: str | Path, problem: str | Path, planner: str = DEFAULT_PLANNER, on_search: Callable[[], None] | None = None
) -> AbstractPlan:
    """The pipeline in this process: parse, solve (compiling away what the engine lacks), validate, link
    (the causal links come from the planner when it finds them, as tailor-pocl does, else from deordering).

    Without a fixed PYTHONHASHSEED, the engine may pick a different one of several valid plans on each run.
    """
    domain, problem = Path(domain), Path(problem)
    parsed, domain_name = read_problem(domain, problem)
    return plan_parsed(parsed, domain_name, planner, str(problem), on_search)


def plan_parsed(parsed, domain_name: str, planner: str = DEFAULT_PLANNER, file: str | None = None,
                on_search: Callable[[], None] | None = None) -> AbstractPlan:
    """Solve, validate and link a unified-planning Problem in this process (`file` names it in errors)."""
    parsed.environment.credits_stream = None  # no engine credits on stdout: `--json` output must be pure JSON
    planner = canonical(planner)
    found, chain = solve(parsed, planner, file, on_search)
    if hasattr(found, "causal_links"):
        steps, links, orderings = _from_causal_link_plan(parsed, found)
    else:
        steps, links, orderings = partial_order(parsed, found)
    objects, initial = problem_facts(parsed)
    return AbstractPlan(domain_name, parsed.name, planner, steps, links, orderings, objects, initial, chain)


def _from_causal_link_plan(parsed, plan) -> tuple[tuple[Step, ...], tuple[CausalLink, ...], tuple]:
    """Steps, causal links and orderings as the planner found them; links on fluents a compiler added (not in
    the PDDL) are left out."""
    steps = tuple(
        Step(k, s.action.name, tuple(p.object().name for p in s.actual_parameters)) for k, s in enumerate(plan.steps, 1)
    )
    links = [link for link in plan.causal_links if parsed.has_fluent(link.fact[0])]
    return steps, sorted_links(links), tuple(plan.orderings)


def problem_facts(parsed) -> tuple[tuple[tuple[str, tuple[str, ...]], ...], tuple[tuple[str, ...], ...]]:
    """(objects with their type chains, initial facts that hold) of a parsed unified-planning problem."""
    objects = []
    for o in parsed.all_objects:
        chain, t = [], o.type
        while t is not None:
            chain.append(getattr(t, "name", str(t)))
            t = getattr(t, "father", None)
        objects.append((o.name, tuple(chain)))
    initial = tuple((fact.fluent().name, *(str(a) for a in fact.args))
                    for fact, value in parsed.explicit_initial_values.items() if value.is_true())
    return tuple(objects), initial
