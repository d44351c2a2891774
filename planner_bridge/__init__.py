"""PDDL in, a validated partial-order plan with causal links out (Sec. 5.2 of the dissertation)."""

from tailor.planner_bridge.abstract_plan import GOAL, INITIAL, AbstractPlan, CausalLink, Step
from tailor.planner_bridge.bridge import DEFAULT_PLANNER, plan_files, plan_here
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
from tailor.planner_bridge.text import render_text

__all__ = [
    "GOAL",
    "INITIAL",
    "DEFAULT_PLANNER",
    "AbstractPlan",
    "CausalLink",
    "Step",
    "plan_files",
    "plan_here",
    "render_text",
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
