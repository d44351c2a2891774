"""The planner bridge in this process: parse, solve (compiling away what the engine lacks), validate, link.

planner_bridge.bridge runs it in a child process (planner_bridge.child), for a fixed hash seed and its limits;
the benchmark and the unified-planning interface (planner_bridge.up_interop) call it here.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

from tailor.planner_bridge.abstract_plan import AbstractPlan, CausalLink, Step
from tailor.planner_bridge.causal import partial_order, sorted_links
from tailor.planner_bridge.reading import PDDLTask, parse_task, read_pddl
from tailor.planner_bridge.solving import canonical, solve

DEFAULT_PLANNER = "pyperplan"


def plan_here(
    domain: str | Path, problem: str | Path, planner: str = DEFAULT_PLANNER, on_search: Callable[[], None] | None = None
) -> AbstractPlan:
    """Plan the PDDL pair in this process (see plan_pddl_here); the files are read once.

    Without a fixed PYTHONHASHSEED, the engine may pick a different one of several valid plans on each run.
    """
    return plan_pddl_here(read_pddl(domain, problem), planner, on_search)


def plan_pddl_here(
    task: PDDLTask, planner: str = DEFAULT_PLANNER, on_search: Callable[[], None] | None = None
) -> AbstractPlan:
    """The pipeline in this process for a pair read by read_pddl: parse, solve, validate, link (the causal links
    come from the planner when it finds them, as tailor-pocl does, else from deordering)."""
    return plan_parsed(parse_task(task), task.domain_name, planner, str(task.problem), on_search)


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
