"""Read a PDDL domain/problem pair into a unified-planning Problem, turning every failure into a one-line error
that names the file, and the line and column where they are known."""

from __future__ import annotations

import re
from pathlib import Path

from tailor.errors import InputFileError, PDDLSemanticError, PDDLSyntaxError, PlannerError
from tailor.planner_bridge.lint import check_domain, check_problem
from tailor.planner_bridge.sexpr import read_sexpr

# unified-planning's reader reports places as "line: 16, col 38" or "line: 15, col: 18"; pyparsing as "line:19, col:3".
_UP_PLACE = re.compile(r"line:\s*(\d+),\s*col:?\s*(\d+)")


def read_text(path: Path) -> str:
    """The file's text (without a UTF-8 byte-order mark); a missing, unreadable or non-text file is an
    InputFileError."""
    if not path.exists():
        raise InputFileError("no such file", str(path))
    if not path.is_file():
        raise InputFileError("not a file", str(path))
    try:
        # "utf-8-sig" drops a leading byte-order mark, as Windows editors write one: the BOM is accepted.
        return path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputFileError(f"not a UTF-8 text file (byte {exc.start})", str(path)) from None
    except OSError as exc:
        raise InputFileError(f"cannot read: {exc.strerror}", str(path)) from None


def _reader_error(exc: Exception, file: str) -> PlannerError:
    """Translate an exception of unified-planning's PDDL reader (pyparsing or its own) into ours."""
    line = getattr(exc, "lineno", None)
    if line is not None and hasattr(exc, "msg"):  # pyparsing's ParseException and friends
        return PDDLSyntaxError(f"syntax error: {exc.msg}", file, line, getattr(exc, "col", None))
    text = " ".join(str(exc).split())
    place = _UP_PLACE.search(text)
    message = _UP_PLACE.split(text)[0] if place else text
    message = re.sub(r"\s*(Error from|[Ff]ound at|From)\s*$", "", message.strip()).rstrip(".,: ")
    return PDDLSemanticError(
        message or type(exc).__name__,
        file,
        int(place.group(1)) if place else None,
        int(place.group(2)) if place else None,
    )


def check_files(domain: Path, problem: Path) -> tuple[str, str, str]:
    """Read and check the pair without unified-planning (fast); return both texts and the domain's PDDL name."""
    domain_text, problem_text = read_text(domain), read_text(problem)
    signature = check_domain(read_sexpr(domain_text, str(domain)), str(domain))
    check_problem(read_sexpr(problem_text, str(problem)), signature, str(problem))
    return domain_text, problem_text, signature.name


def read_problem(domain: Path, problem: Path):
    """Check and parse the pair; return the unified-planning Problem (its `name` is the PDDL problem name) and
    the domain's PDDL name."""
    domain_text, problem_text, domain_name = check_files(domain, problem)
    from unified_planning.io import PDDLReader

    # Parse the domain alone first, so that an error the reader finds is attributed to the right file.
    try:
        PDDLReader().parse_problem_string(domain_text)
    except MemoryError:
        raise
    except Exception as exc:  # the reader raises pyparsing errors, SyntaxError, KeyError, ...
        raise _reader_error(exc, str(domain)) from None
    try:
        parsed = PDDLReader().parse_problem_string(domain_text, problem_text)
    except MemoryError:
        raise
    except Exception as exc:
        raise _reader_error(exc, str(problem)) from None
    return parsed, domain_name
