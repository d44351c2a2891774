"""Read a PDDL domain/problem pair once (read_pddl: the texts, checked by planner_bridge.lint) and parse it into a
unified-planning Problem (parse_task), turning every failure into a one-line error that names the file, and the
line and column where they are known."""

from __future__ import annotations

import os
import re
import stat
from dataclasses import dataclass
from pathlib import Path

from tailor.errors import InputFileError, PDDLSemanticError, PDDLSyntaxError, PlannerError, TailorError
from tailor.planner_bridge.lint import DomainSignature, check_domain, check_problem
from tailor.planner_bridge.sexpr import read_sexpr

# unified-planning's reader reports places as "line: 16, col 38" or "line: 15, col: 18"; pyparsing as "line:19, col:3".
_UP_PLACE = re.compile(r"line:\s*(\d+),\s*col:?\s*(\d+)")
# The largest PDDL file read: the biggest IPC problems are a few MB; a bound, so that a mistaken path (a disk
# image, a log) ends in one line instead of filling the memory.
MAX_PDDL_BYTES = 64 * 2**20


def read_input(path: Path, limit: int, error: type[TailorError] = InputFileError,
               missing: str = "no such file") -> bytes:
    """The bytes of the regular file `path`, at most `limit` of them; any other file is an `error` naming it
    (`missing` says that it does not exist). A named pipe, a device or a socket is refused before it is
    opened, and again on what was opened (opened without waiting for a writer): reading one could block
    forever (a FIFO) or never end (/dev/zero). The PDDL files and the TOML files (binding, belief) are read
    here."""
    path = Path(path)
    try:
        _check_regular(os.stat(path), path, error)
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise error(missing, str(path)) from None
    except OSError as exc:
        raise error(f"cannot read: {exc.strerror or exc}", str(path)) from None
    try:
        info = os.fstat(fd)
        _check_regular(info, path, error)  # (the name may have been swapped for something else meanwhile)
        if info.st_size > limit:
            raise error(_too_large(info.st_size, limit), str(path))
        chunks, total = [], 0
        while total <= limit:
            chunk = os.read(fd, min(1 << 20, limit + 1 - total))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
    except OSError as exc:
        raise error(f"cannot read: {exc.strerror or exc}", str(path)) from None
    finally:
        os.close(fd)
    if total > limit:  # (it grew while we read)
        raise error(_too_large(total, limit), str(path))
    return b"".join(chunks)


def _check_regular(info: os.stat_result, path: Path, error: type[TailorError]) -> None:
    if stat.S_ISDIR(info.st_mode):
        raise error("not a file (a folder)", str(path))
    if not stat.S_ISREG(info.st_mode):
        kind = ("a named pipe" if stat.S_ISFIFO(info.st_mode) else "a socket" if stat.S_ISSOCK(info.st_mode)
                else "a device")
        raise error(f"not a regular file ({kind}): inputs are read from regular files only", str(path))


def _too_large(size: int, limit: int) -> str:
    return f"too large to read ({size} bytes; at most {limit})"


def read_text(path: Path, limit: int = MAX_PDDL_BYTES) -> str:
    """The file's text (without a UTF-8 byte-order mark); a missing, unreadable, non-text or too large file,
    or one that is not a regular file, is an InputFileError."""
    data = read_input(path, limit)
    try:
        # "utf-8-sig" drops a leading byte-order mark, as Windows editors write one: the BOM is accepted.
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputFileError(f"not a UTF-8 text file (byte {exc.start})", str(path)) from None


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
