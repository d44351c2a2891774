"""Find a domain/problem pair from file paths or from the names of a bundled domain and one of its problems."""

from __future__ import annotations

import logging
from pathlib import Path

from tailor.errors import InputFileError

DOMAINS_DIR = Path(__file__).resolve().parent.parent / "domains"  # packaged beside planner_bridge
DOMAIN_FILE = "domain.pddl"
PROBLEMS_DIR = "problems"


def bundled_domains() -> list[str]:
    """Names of the bundled domains (folders of `domains/` holding a domain.pddl)."""
    if not DOMAINS_DIR.is_dir():
        return []
    return sorted(d.name for d in DOMAINS_DIR.iterdir() if (d / DOMAIN_FILE).is_file())


def bundled_problems(domain: str) -> list[str]:
    """Names of a bundled domain's problems (the stems of its problems/*.pddl)."""
    return sorted(p.stem for p in (DOMAINS_DIR / domain / PROBLEMS_DIR).glob("*.pddl"))


def resolve_domain_dir(domain_arg: str | Path) -> Path:
    """The folder of a domain given as a bundled name, a folder holding domain.pddl, or a domain.pddl file."""
    arg = str(domain_arg)
    path = Path(arg)
    _warn_if_shadowing(arg)
    if path.is_dir():
        if not (path / DOMAIN_FILE).is_file():
            raise InputFileError(f"a domain folder needs a {DOMAIN_FILE}", arg)
        return path
    if path.is_file():
        if path.name != DOMAIN_FILE:  # another file beside a domain.pddl would silently stand for that one
            raise InputFileError(f"not a domain folder's {DOMAIN_FILE} (give the folder, or its {DOMAIN_FILE})", arg)
        return path.parent
    if not _looks_like_path(arg) and arg in bundled_domains():
        return DOMAINS_DIR / arg
    raise InputFileError(
        f"no such domain folder, domain file or bundled domain (bundled: {', '.join(bundled_domains()) or 'none'})",
        arg)


_WARNED: set[str] = set()


def _warn_if_shadowing(arg: str) -> None:
    """A bare name that is both a file or folder here and a bundled domain means the one here (an existing path
    wins): say so, once per command, since the bundled domain may have been meant."""
    if not _looks_like_path(arg) and Path(arg).exists() and arg in bundled_domains() and arg not in _WARNED:
        _WARNED.add(arg)
        logging.getLogger(__name__).warning(
            "%s: the %s here, not the bundled domain of that name (write ./%s to say so; run elsewhere for the "
            "bundled one)", arg, "folder" if Path(arg).is_dir() else "file", arg)


def _looks_like_path(arg: str) -> bool:
    return "/" in arg or "\\" in arg or arg.endswith(".pddl")


def resolve_problem(domain_arg: str | Path, problem_arg: str | Path) -> tuple[Path, Path]:
    """(domain file, problem file) for a bundled domain and problem name, for two file paths, or for a domain file
    (or the folder holding it) and the name of a problem in the `problems/` folder beside it. An existing file
    wins over a bundled name; InputFileError names the argument that matches neither."""
    domain_arg, problem_arg = str(domain_arg), str(problem_arg)
    domain = Path(domain_arg)
    if domain.is_dir():
        domain = resolve_domain_dir(domain_arg) / DOMAIN_FILE
    elif domain.is_file():
        _warn_if_shadowing(domain_arg)
    elif not _looks_like_path(domain_arg):
        if domain_arg not in bundled_domains():
            raise InputFileError(
                f"no such file or bundled domain (bundled: {', '.join(bundled_domains()) or 'none'})", domain_arg
            )
        domain = DOMAINS_DIR / domain_arg / DOMAIN_FILE
    problem = Path(problem_arg)
    if not problem.is_file() and not _looks_like_path(problem_arg):
        candidate = domain.parent / PROBLEMS_DIR / f"{problem_arg}.pddl"
        if not candidate.is_file():
            known = sorted(p.stem for p in (domain.parent / PROBLEMS_DIR).glob("*.pddl"))
            raise InputFileError(
                f"no such file, nor a problem of {domain} (known: {', '.join(known) or 'none'})", problem_arg
            )
        problem = candidate
    for path in (domain, problem):
        if not path.is_file():
            raise InputFileError("no such file" if not path.exists() else "not a file", str(path))
    return domain, problem
