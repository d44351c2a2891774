"""Diagnostics of the `tailor` command through `logging`, on stderr; results stay on stdout.

The library logs to loggers under `tailor` (notes at INFO, "too small to trust" at WARNING, timings and
stages at DEBUG) and configures nothing itself; the command line shows them as `tailor CMD: note: ...`.
`-q` shows only warnings and errors (and turns the progress bars off), `-qq` only errors; `-v` adds the
debug lines.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager

LOGGER = "tailor"
LEVEL_WORDS = {logging.DEBUG: "debug", logging.INFO: "note", logging.WARNING: "warning", logging.ERROR: "error",
               logging.CRITICAL: "error"}
QUIET_FLAGS = {"-q": 1, "--quiet": 1}
VERBOSE_FLAGS = {"-v": 1, "--verbose": 1}


def level(verbosity: int) -> int:
    """-qq -> ERROR, -q -> WARNING, none -> INFO, -v -> DEBUG (verbosity = verbose count - quiet count)."""
    return {-2: logging.ERROR, -1: logging.WARNING, 0: logging.INFO}.get(max(verbosity, -2), logging.DEBUG)


def verbosity_of(argv: Sequence[str]) -> int:
    """The verbosity the command line asks for, read before argparse runs (argument types such as --jobs log
    while being parsed): -v / --verbose count up, -q / --quiet down; -qq and -vv are counted too."""
    total = 0
    for arg in argv:
        if arg == "--":
            break
        if arg.startswith("--") and len(arg) > 3:  # argparse takes unique prefixes: --qui, --verb
            total += ("--verbose".startswith(arg) and arg != "--ver") - "--quiet".startswith(arg)
        elif arg in QUIET_FLAGS or arg in VERBOSE_FLAGS:
            total += VERBOSE_FLAGS.get(arg, 0) - QUIET_FLAGS.get(arg, 0)
        elif len(arg) > 1 and arg[0] == "-" and arg[1] != "-" and set(arg[1:]) <= {"q", "v"}:
            total += arg.count("v") - arg.count("q")
    return total


class _StderrHandler(logging.Handler):
    """Writes to whatever sys.stderr is at the time (pytest's capture, a redirected stream)."""

    def __init__(self, prog: str) -> None:
        super().__init__()
        self.prog = prog

    def format(self, record: logging.LogRecord) -> str:
        return f"{self.prog}: {LEVEL_WORDS.get(record.levelno, 'note')}: {record.getMessage()}"

    def emit(self, record: logging.LogRecord) -> None:
        try:
            sys.stderr.write(self.format(record) + "\n")
            sys.stderr.flush()
        except Exception:  # noqa: BLE001 - logging must never end the program
            self.handleError(record)


def set_verbosity(verbosity: int) -> None:
    """The level of the `tailor` loggers for `verbosity` (see `level`)."""
    logging.getLogger(LOGGER).setLevel(level(verbosity))


@contextmanager
def cli_logging(verbosity: int, prog: str = "tailor") -> Iterator[_StderrHandler]:
    """Show the `tailor` loggers' messages at the level `verbosity` asks for, as `PROG: note: ...` lines on
    stderr, for the time of one command; the handler's `prog` can be renamed once the command is known."""
    logger = logging.getLogger(LOGGER)
    handler = _StderrHandler(prog)
    previous = (logger.level, logger.propagate)
    logger.addHandler(handler)
    set_verbosity(verbosity)
    logger.propagate = False  # an application's own root handler would print every line twice
    try:
        yield handler
    finally:
        logger.removeHandler(handler)
        logger.setLevel(previous[0])
        logger.propagate = previous[1]
