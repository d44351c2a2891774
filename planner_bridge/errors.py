"""Errors of the planner bridge: each names the file (and line, where the parser gives it) and has its own exit status."""

from __future__ import annotations


class PlannerError(Exception):
    """Base of every planner-bridge error; the CLI prints it as one line and exits with `exit_code`."""

    exit_code = 1

    def __init__(self, message: str, file: str | None = None, line: int | None = None, col: int | None = None):
        super().__init__(message)
        self.message = message
        self.file = file
        self.line = line
        self.col = col

    def __str__(self) -> str:
        where = ""
        if self.file:
            where = str(self.file)
            if self.line is not None:
                where += f":{self.line}"
                if self.col is not None:
                    where += f":{self.col}"
            where += ": "
        return where + self.message


class InputFileError(PlannerError):
    """A domain or problem file is missing or unreadable."""

    exit_code = 3


class PDDLSyntaxError(PlannerError):
    """The PDDL text does not parse."""

    exit_code = 4


class PDDLSemanticError(PlannerError):
    """The PDDL parses but is inconsistent: undefined predicate or type, wrong arity, another domain's problem."""

    exit_code = 5


class NoPlanError(PlannerError):
    """The planner proved that no plan exists."""

    exit_code = 6


class PlannerTimeoutError(PlannerError):
    """The planner ran out of time before finding a plan."""

    exit_code = 7


class PlannerUnavailableError(PlannerError):
    """The planner name is unknown, or no compilation makes the problem solvable by it."""

    exit_code = 8
