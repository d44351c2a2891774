"""The `tailor` command line: one subcommand per stage, looked up in a registry.

Each command module defines `add_arguments(parser)` and `run(args) -> int`; only the module of the command
given is imported, so that `tailor plan` does not pay for the optimizers, the simulators or the learners.
Every project error is printed as one line on stderr and ends the process with its own exit status; other
diagnostics go through `logging` (tailor.cli.logs), results to stdout.
"""

from __future__ import annotations

import argparse
import errno
import importlib
import io
import os
import signal
import sys
import threading

from tailor import __version__
from tailor.errors import OutputFileError, TailorError, printable
from tailor.cli.logs import cli_logging, set_verbosity, verbosity_of

COMMANDS = {  # name: (module, one line of help); a module defines add_arguments(parser) and run(args) -> int
    "plan": ("tailor.cli.plan",
              "plan a PDDL domain/problem pair into a validated partial-order plan with causal links"),
    "train": ("tailor.cli.train",
              "gather experience in the simulator and learn the action models (durations, success classifiers)"),
    "gather": ("tailor.cli.gather",
              "simulate episodes A..B-1 of the domain's experience scenarios and keep them as shards for `tailor train`"),
    "check": ("tailor.cli.check",
              "say what the binding and belief make of a problem: free parameters, belief values read, warnings"),
    "refine": ("tailor.cli.refine",
              "refine the free parameters of a plan for the fastest predicted execution, optionally simulate it"),
    "execute": ("tailor.cli.execute",
              "execute a refined plan one action at a time, closed loop: monitor, re-refine, replan, learn (Ch. 8.1)"),
    "evaluate": ("tailor.cli.evaluate",
              "measure refined vs greedy execution in the simulator over random situations"),
    "coordinate": ("tailor.cli.coordinate",
              "measure implicit coordination of a robot team with learned action models (Ch. 7)"),
    "new": ("tailor.cli.new",
              "make a plug-in package for a robot of your own, ready to install, train, refine and evaluate"),
    "domains": ("tailor.cli.domains",
              "list installed simulators and bundled domains, and what each can do (plan, train, refine, evaluate)"),
}

EXIT_USAGE = 2
EXIT_INTERRUPTED = 130  # Ctrl-C (SIGINT): 128 + 2, as a shell reports it
EXIT_TERMINATED = 143  # SIGTERM: 128 + 15
EXIT_NOT_COMPLETED = 19  # `tailor execute`: the task was not completed (docs/exit-statuses.md)


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C so that every `finally` runs and joblib stops its worker processes."""


def _terminate(signum, frame) -> None:
    signal.signal(signal.SIGTERM, signal.SIG_IGN)  # a second SIGTERM must not interrupt the cleaning up
    raise Terminated


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors (`tailor CMD: error: ...`, exit 2) instead of a usage block; the usage
    stays one `--help` away. Subcommand parsers are made of the same class."""

    def error(self, message: str):
        self.exit(EXIT_USAGE, f"{self.prog}: error: {printable(message)} (see `{self.prog} --help`)\n")


DESCRIPTION = """\
tailor makes a robot execute a symbolic plan fast and smoothly. A PDDL planner decides what to do; action
models learned from simulated experience predict how long each action takes and whether it succeeds;
subgoal refinement chooses the values the plan leaves free (where and how fast the robot arrives at each
subgoal) so that the whole sequence is predicted fastest; a simulator executes and measures the result."""

READ_MORE = """\
Each command has its own help: tailor COMMAND --help. Read more in the README (README.md in the source
tree; the home page `pip show tailor` names): the pipeline, the exit statuses, how to add your own robot."""


def _examples() -> str:
    """Examples with a bundled domain that can be refined (its name and a problem read from the data)."""
    domain = problem = None
    try:
        from tailor.planner_bridge.bundled import DOMAINS_DIR, bundled_domains, bundled_problems

        ready = [d for d in bundled_domains() if any((DOMAINS_DIR / d / "models").glob("*.json"))]
        if ready and bundled_problems(ready[-1]):
            domain, problem = ready[-1], bundled_problems(ready[-1])[0]
    except (OSError, TailorError):
        pass
    domain, problem = domain or "DOMAIN", problem or "PROBLEM"
    examples = [
        ("tailor domains", "what is installed, and what each domain can do"),
        (f"tailor plan {domain} {problem}", "the partial-order plan with its causal links"),
        (f"tailor refine {domain} {problem} --simulate --plot run.png",
         "choose the free parameters, simulate greedy and refined execution, draw both"),
        (f"tailor train {domain} --out DIR", "learn the action models again, into DIR"),
        (f"tailor -q evaluate {domain} --json > results.json",
         "measure refined against greedy; only warnings on stderr"),
    ]
    return "examples:\n" + "\n".join(f"  {command}\n      {what}" for command, what in examples)


def _verbosity_options(parser: argparse.ArgumentParser, default) -> None:
    parser.add_argument("-q", "--quiet", action="count", default=default,
                        help="less on stderr: -q only warnings and errors, no progress bars; -qq only errors")
    parser.add_argument("-v", "--verbose", action="count", default=default,
                        help="more on stderr: stages and timings (debug lines)")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser of every command's one line of help; of `command` in full (its module imported): a command
    pays for no other command's imports (`tailor plan` loads neither the optimizers nor the simulators)."""
    parser = Parser(prog="tailor", description=DESCRIPTION, epilog=f"{_examples()}\n\n{READ_MORE}",
                    formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"tailor {__version__}")
    _verbosity_options(parser, 0)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND", title="commands")
    for name, (module_name, summary) in COMMANDS.items():
        if name != command:
            sub.add_parser(name, help=summary)
            continue
        module = importlib.import_module(module_name)
        parsed = sub.add_parser(name, help=summary, description=getattr(module, "DESCRIPTION", summary))
        module.add_arguments(parsed)
        _verbosity_options(parsed, argparse.SUPPRESS)  # also after the command: tailor train DOMAIN -q
        parsed.set_defaults(run=module.run, parser=parsed)
    return parser


def command_of(argv: list[str]) -> str | None:
    """The command `argv` names: its first word that is not an option (tailor's own options take no value)."""
    return next((word for word in argv if not word.startswith("-")), None)


def main(argv: list[str] | None = None) -> int:
    """Run the command `argv` (default: this process's command line, as the `tailor` program) and return its
    exit status. As the program, the status stands once the command is done: a SIGTERM or Ctrl-C while the
    interpreter shuts down no longer kills the process by the signal with no word (see _keep_status)."""
    program = argv is None
    argv = sys.argv[1:] if argv is None else list(argv)
    with cli_logging(verbosity_of(argv)) as log:  # before parsing: argument types may log (--jobs capped)
        args, extras = build_parser(command_of(argv)).parse_known_args(argv)
        if extras:  # said by the command's parser (`tailor plan: error: ...`), not the top one
            args.parser.error(f"unrecognized arguments: {' '.join(extras)}")
        log.prog = f"tailor {args.command}"
        set_verbosity(args.verbose - args.quiet)  # as argparse read it (also --qui, --verb)
        args.progress = args.quiet == 0  # progress bars (on a terminal only) unless -q
        args.argv = argv  # the command line, for the outputs' provenance (tailor.outputs.provenance)
        return _run(args, program)


class _ClosedOutput(io.TextIOBase):
    """Standard output when the process started with it closed: writing to it is an error, as for `ls >&-`."""

    def write(self, text: str) -> int:
        raise OSError(errno.EBADF, "standard output is closed")


# errors of writing a stream (no file name: the results on standard output, as every command writes them)
WRITE_ERRORS = {errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO, errno.EBADF}  # (EPIPE: BrokenPipeError)


def _stdout_failed(exc: OSError | None = None) -> bool:
    """Whether standard output cannot be written (closed, a full disk, an I/O error); if so, later writes and the
    interpreter's last flush go to the null device, so the one-line error stays the only message."""
    if isinstance(sys.stdout, _ClosedOutput):
        return True
    failed = exc is not None and exc.filename is None and exc.errno in WRITE_ERRORS
    try:
        sys.stdout.flush()
    except (OSError, ValueError):
        failed = True
    if failed:
        try:
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, sys.stdout.fileno())
            os.close(null)
        except (OSError, ValueError):
            sys.stdout = _ClosedOutput()
    return failed


def _run(args: argparse.Namespace, program: bool = False) -> int:
    """Run the parsed command; its exit status. `program`: this process is the `tailor` program, which ends
    once the status is known (see _keep_status); else the signal handlers are as they were before."""
    previous = None
    code = None
    if threading.current_thread() is threading.main_thread():
        previous = signal.signal(signal.SIGTERM, _terminate)
    if sys.stdout is None:  # started with standard output closed
        sys.stdout = _ClosedOutput()
    try:
        code = _status(args, keep=program and previous is not None)
        return code
    finally:
        if previous is not None:
            if program and code is not None:
                _keep_status(code)
            else:
                signal.signal(signal.SIGTERM, previous)


def _keep_status(code: int) -> None:
    """From now on SIGTERM and Ctrl-C are ignored: the command is done (`tailor train`'s files are in place) and
    the process ends with `code` once the interpreter has shut down (most of a second after `tailor train`,
    with scikit-learn and matplotlib loaded). Ignored, not handled: the interpreter puts back the default
    action of every signal it handles before it tears its modules down, and a signal then would kill the
    process with no word; an ignored one stays ignored. (SIGKILL still ends a shutdown that hangs.)"""
    for signum in (signal.SIGTERM, signal.SIGINT):
        signal.signal(signum, signal.SIG_IGN)


def _status(args: argparse.Namespace, keep: bool = False) -> int:
    """Run the command; the status it ends with, each error said in one line on stderr. Once the command has
    returned, its status stands: with `keep` (the program) signals are ignored from then on (_keep_status),
    and one that arrives before (or, without `keep`, while standard output is flushed) changes nothing."""
    returned = None
    try:
        returned = args.run(args) or 0  # (nothing between the return and this store lets a signal handler run)
        if keep:
            _keep_status(returned)
        sys.stdout.flush()  # a full disk shows here, not in the interpreter's last flush
        return int(returned)
    except TailorError as exc:
        print(f"tailor {args.command}: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM (Terminated)
        if returned is not None:  # the command was done: a signal before _keep_status took hold
            if keep:
                _keep_status(returned)
            return int(returned)
        terminated = isinstance(exc, Terminated)
        print(f"tailor {args.command}: {'terminated' if terminated else 'interrupted'}", file=sys.stderr)
        return EXIT_TERMINATED if terminated else EXIT_INTERRUPTED
    except BrokenPipeError:
        _stdout_failed()
        return 0
    except OSError as exc:  # not a project error: writing the results failed, or an unforeseen system error
        if _stdout_failed(exc):
            print(f"tailor {args.command}: error: cannot write to standard output: "
                  f"{printable(str(exc.strerror or exc))}", file=sys.stderr)
            return OutputFileError.exit_code
        print(f"tailor {args.command}: error: {printable(str(exc))}", file=sys.stderr)
        return TailorError.exit_code


if __name__ == "__main__":
    sys.exit(main())
