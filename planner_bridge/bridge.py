"""The planner bridge read top to bottom: PDDL files in (read once), a validated partial-order plan with causal
links out, planned in a child process (planner_bridge.worker)."""

from __future__ import annotations

from pathlib import Path

from tailor.errors import ArgumentValueError, is_finite, shown
from tailor.planner_bridge.abstract_plan import AbstractPlan
from tailor.planner_bridge.in_process import DEFAULT_PLANNER
from tailor.planner_bridge.reading import PDDLTask, read_pddl
from tailor.planner_bridge.solving import canonical
from tailor.planner_bridge.worker import MEMORY_LIMIT_GB, PlannerProcess


def plan_files(
    domain: str | Path,
    problem: str | Path,
    planner: str = DEFAULT_PLANNER,
    timeout: float | None = None,
    memory_gb: float | None = MEMORY_LIMIT_GB,
    process: PlannerProcess | None = None,
) -> AbstractPlan:
    """Read the PDDL pair once and plan it (see plan_pddl)."""
    check_limits(timeout, memory_gb)
    return plan_pddl(read_pddl(domain, problem), planner, timeout, memory_gb, process)


def plan_pddl(
    task: PDDLTask,
    planner: str = DEFAULT_PLANNER,
    timeout: float | None = None,
    memory_gb: float | None = MEMORY_LIMIT_GB,
    process: PlannerProcess | None = None,
) -> AbstractPlan:
    """Plan a pair read by read_pddl: the same files give the same plan on every run (it runs in a child
    process with a fixed hash seed, which receives the texts read here, see planner_bridge.worker); `timeout`
    limits parsing, compiling and search together, in seconds, and `memory_gb` the planner's memory (None: no
    limit). `process` is a planner child kept for many requests (worker.PlannerProcess, with its own memory
    limit); by default a new one per call.

    Raises the errors of tailor.errors: InputFileError, PDDLSyntaxError, PDDLSemanticError (from read_pddl),
    NoPlanError, PlannerTimeoutError, PlannerUnavailableError (and PlannerError itself for an engine's failure,
    or when the planner runs out of memory).
    """
    check_limits(timeout, memory_gb)
    if process is not None:
        return process.plan_pddl(task, canonical(planner), timeout)
    with PlannerProcess(memory_gb) as process:
        return process.plan_pddl(task, canonical(planner), timeout)


def check_limits(timeout: float | None, memory_gb: float | None = None) -> None:
    """An ArgumentValueError unless each limit given is a positive, finite number."""
    for name, limit in (("timeout", timeout), ("memory limit", memory_gb)):
        if limit is not None and not (limit > 0 and is_finite(limit)):
            raise ArgumentValueError(f"the {name} must be positive and finite (None for no limit), not {shown(limit)}")
