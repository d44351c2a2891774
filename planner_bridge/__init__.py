"""PDDL in, a validated partial-order plan with causal links out (Sec. 5.2 of the dissertation).

    task = read_pddl(domain, problem)      # each file read once and checked (PDDLTask: texts, signature, names)
    plan = plan_pddl(task)                 # planned in a child process (plan_files(domain, problem): both steps)
    problem = parse_task(task)             # the unified-planning Problem, in this process, from the same texts
    plan = plan_from_ipc(task, "sas_plan") # a plan file another planner wrote, validated and linked
    text = format_ipc(plan)                # the plan as a sequential IPC plan file
"""

from tailor.planner_bridge.abstract_plan import GOAL, INITIAL, AbstractPlan, CausalLink, Step, render_text
from tailor.planner_bridge.bridge import plan_files, plan_pddl
from tailor.planner_bridge.bundled import bundled_domains, bundled_problems, resolve_domain_dir, resolve_problem
from tailor.errors import (
    InputFileError,
    NoPlanError,
    PDDLSemanticError,
    PDDLSyntaxError,
    PlannerError,
    PlannerTimeoutError,
    PlannerUnavailableError,
)
from tailor.planner_bridge.in_process import DEFAULT_PLANNER, plan_here, plan_pddl_here
from tailor.planner_bridge.ipc import format_ipc, plan_from_ipc, read_ipc_plan
from tailor.planner_bridge.reading import PDDLTask, parse_task, read_pddl

__all__ = [
    "GOAL",
    "INITIAL",
    "DEFAULT_PLANNER",
    "AbstractPlan",
    "CausalLink",
    "Step",
    "PDDLTask",
    "read_pddl",
    "parse_task",
    "plan_pddl",
    "plan_files",
    "plan_here",
    "plan_pddl_here",
    "render_text",
    "format_ipc",
    "read_ipc_plan",
    "plan_from_ipc",
    "resolve_problem",
    "resolve_domain_dir",
    "bundled_domains",
    "bundled_problems",
    "PlannerError",
    "InputFileError",
    "PDDLSyntaxError",
    "PDDLSemanticError",
    "NoPlanError",
    "PlannerTimeoutError",
    "PlannerUnavailableError",
]
