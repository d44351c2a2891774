"""Errors of the planner bridge (defined with the project's one base in `tailor.errors`)."""

from tailor.errors import (  # noqa: F401
    InputFileError,
    NoPlanError,
    PDDLSemanticError,
    PDDLSyntaxError,
    PlannerError,
    PlannerTimeoutError,
    PlannerUnavailableError,
)
