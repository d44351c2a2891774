"""The one exception base of tailor and its exit statuses (the README's table).

Every error a user can cause is a `TailorError`: the command line prints it as one line naming the file (and
line:column where known) and exits with the class's `exit_code`. Planner, refinement and simulator errors are
subclasses, so an API user catches them all with one `except tailor.TailorError`.
"""

from __future__ import annotations

import math
import re
from typing import Any

# Characters a message shows escaped, as Python writes them in a string ("\\n", "\\x1b", "\\u202e"): control
# characters (a newline would make two lines of one error; an ESC byte in a file name would reach the terminal
# as an escape sequence), line and paragraph separators, and the marks that reorder text (bidi controls).
_UNPRINTABLE = re.compile("[\x00-\x1f\x7f-\x9f\u061c\u200e\u200f\u2028\u2029\u202a-\u202e\u2066-\u2069]")


def printable(text: str) -> str:
    """`text` with every control character escaped: what a one-line message shows of a name or path."""
    return _UNPRINTABLE.sub(lambda m: m.group().encode("unicode_escape").decode("ascii"), text)



MAX_SHOWN = 60  # characters of a value an error message repeats


def is_finite(value: float) -> bool:
    """Whether a number is finite as a float: an integer beyond any float (10**400) is not."""
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def shown(value: Any) -> str:
    """`value` for a one-line message: repr, but an integer too long to print whole by its size (Python will
    not even print one of more than 4,300 digits), anything else cut to MAX_SHOWN characters."""
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 64:
        return f"an integer of {value.bit_length()} bits"
    text = repr(value)
    return text if len(text) <= MAX_SHOWN else text[:MAX_SHOWN - 3] + "..."


class TailorError(Exception):
    """Base of every tailor error; `str()` is one line: `file:line:col: message`, control characters escaped
    (`message` and `file` keep them as given)."""

    exit_code = 9  # an error with no more specific status: "other refinement error"

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
        return printable(where + str(self.message))


# --- planning (planner_bridge) ---------------------------------------------------------------------------
class PlannerError(TailorError):
    """The planner failed or returned a plan the validator rejects."""

    exit_code = 1


class InputFileError(PlannerError):
    """A domain or problem file is missing or unreadable (or an unknown bundled name)."""

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


# --- refinement -----------------------------------------------------------------------------------------
class UsageError(TailorError):
    """A command-line value only the domain can refute (e.g. a situation generator its simulator lacks)."""

    exit_code = 2


class BeliefError(TailorError):
    """A belief-state file is missing or invalid."""

    exit_code = 10


class BindingError(TailorError):
    """An action library binding is missing or invalid, or a plan uses an action it does not bind."""

    exit_code = 11


class ModelFileError(TailorError):
    """An action model file is missing, of the wrong schema, or inconsistent."""

    exit_code = 12


class EmptyRangeError(TailorError):
    """The ranges the predicates imply for a parameter do not intersect (or a bound value lies outside them)."""

    exit_code = 13


class DataError(TailorError):
    """Experience data or training arguments are missing or malformed."""

    exit_code = 14


# --- outputs (any command) ------------------------------------------------------------------------------
class OutputFileError(TailorError):
    """An output file or folder cannot be written: not writable, a directory where a file is meant, a wrong suffix."""

    exit_code = 16


# --- parallel work (any command with --backend) ---------------------------------------------------------
class BackendError(TailorError):
    """A parallel backend cannot be used: its optional packages are missing, or its cluster cannot be reached."""

    exit_code = 17


# --- simulators -----------------------------------------------------------------------------------------
class SimError(TailorError):
    """Invalid simulator input: an unknown action or simulator, a state or parameter outside the world."""

    exit_code = 15


# --- closed-loop execution ------------------------------------------------------------------------------
class ExecutionError(TailorError):
    """An executor (a robot adapter, or a simulator run one action at a time) raised or reported something
    impossible for a step: a duration that is not a finite number >= 0, an unknown outcome, a state that is not
    finite numbers. The message names the step; the experience kept so far is intact."""

    exit_code = 18


# --- the Python API -------------------------------------------------------------------------------------
class ArgumentTypeError(TailorError, TypeError):
    """An API call got an argument of the wrong type (the message names the argument); also a TypeError."""

    exit_code = 2


class ArgumentValueError(TailorError, ValueError):
    """An API call got an argument of the right type but an impossible value (named); also a ValueError."""

    exit_code = 2


def check_path_argument(value, name: str) -> None:
    """An ArgumentTypeError unless `value` is a path (a str or an os.PathLike), naming the argument."""
    import os

    if not isinstance(value, (str, os.PathLike)):
        raise ArgumentTypeError(f"{name} must be a path (str or os.PathLike), not {type(value).__name__}")
