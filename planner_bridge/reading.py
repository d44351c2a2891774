"""Read a PDDL domain/problem pair once (read_pddl: the texts, checked by planner_bridge.lint) and parse it into a
unified-planning Problem (parse_task), turning every failure into a one-line error that names the file, and the
line and column where they are known."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from tailor.errors import InputFileError, PDDLSemanticError, PDDLSyntaxError, PlannerError
from tailor.planner_bridge.lint import DomainSignature, check_domain, check_problem
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


@dataclass(frozen=True)
class PDDLTask:
    """A domain/problem pair as read once for a whole command: the files, their texts, what the domain declares
    (checked: the problem uses only that) and both PDDL names (lower-cased, as unified-planning names them).
    Everything after the read (the planner child, the binding's check, a given plan's check) takes it."""

    domain: Path
    problem: Path
    domain_text: str
    problem_text: str
    signature: DomainSignature
    domain_name: str
    problem_name: str

    def to_json(self) -> dict:
        """The task as JSON (what the parent sends its planner child)."""
        return {"domain": str(self.domain), "problem": str(self.problem), "domain_text": self.domain_text,
                "problem_text": self.problem_text, "signature": self.signature.to_json(),
                "domain_name": self.domain_name, "problem_name": self.problem_name}

    @classmethod
    def from_json(cls, data: dict) -> "PDDLTask":
        return cls(Path(data["domain"]), Path(data["problem"]), data["domain_text"], data["problem_text"],
                   DomainSignature.from_json(data["signature"]), data["domain_name"], data["problem_name"])


def read_pddl(domain: str | Path, problem: str | Path) -> PDDLTask:
    """Read each file once and check the pair without unified-planning (fast): bad files fail here, naming the
    file, line and column, before any planner starts."""
    domain, problem = Path(domain), Path(problem)
    domain_text, problem_text = read_text(domain), read_text(problem)
    signature = check_domain(read_sexpr(domain_text, str(domain)), str(domain))
    problem_name = check_problem(read_sexpr(problem_text, str(problem)), signature, str(problem))
    return PDDLTask(domain, problem, domain_text, problem_text, signature, signature.name, problem_name)


def check_files(domain: Path, problem: Path) -> tuple[str, str, str]:
    """Read and check the pair (see read_pddl); return both texts and the domain's PDDL name."""
    task = read_pddl(domain, problem)
    return task.domain_text, task.problem_text, task.domain_name


def parse_task(task: PDDLTask):
    """The unified-planning Problem of a pair read by read_pddl (its `name` is the PDDL problem name). The pair
    is parsed once; only when that fails is the domain parsed alone, to name the file the error is in."""
    from unified_planning.io import PDDLReader

    try:
        return PDDLReader().parse_problem_string(task.domain_text, task.problem_text)
    except MemoryError:
        raise
    except Exception as exc:  # the reader raises pyparsing errors, SyntaxError, KeyError, ...
        failure = exc
    try:
        PDDLReader().parse_problem_string(task.domain_text)
    except MemoryError:
        raise
    except Exception as exc:
        raise _reader_error(exc, str(task.domain)) from None
    raise _reader_error(failure, str(task.problem)) from None


def read_problem(domain: str | Path, problem: str | Path):
    """Read, check and parse the pair; return the unified-planning Problem (its `name` is the PDDL problem name)
    and the domain's PDDL name."""
    task = read_pddl(domain, problem)
    return parse_task(task), task.domain_name
