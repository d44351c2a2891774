"""The `tailor` command line: one subcommand per stage, looked up in a registry.

Each command module defines `HELP`, `add_arguments(parser)` and `run(args) -> int`, and keeps heavy imports
inside `run` so that `tailor plan` does not pay for the simulator or the learners.
Every project error is printed as one line on stderr and ends the process with its own exit status.
"""

from __future__ import annotations

import argparse
import importlib
import signal
import sys
import threading

from tailor import __version__
from tailor.errors import TailorError

COMMANDS = {
    "plan": "tailor.refinement.cli.plan",
    "train": "tailor.refinement.cli.train",
    "gather": "tailor.refinement.cli.gather",
    "refine": "tailor.refinement.cli.refine",
    "evaluate": "tailor.refinement.cli.evaluate",
    "coordinate": "tailor.refinement.cli.coordinate",
    "domains": "tailor.refinement.cli.domains",
}

EXIT_USAGE = 2
EXIT_INTERRUPTED = 130  # Ctrl-C (SIGINT): 128 + 2, as a shell reports it
EXIT_TERMINATED = 143  # SIGTERM: 128 + 15


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C so that every `finally` runs and joblib stops its worker processes."""


def _terminate(signum, frame) -> None:
    signal.signal(signal.SIGTERM, signal.SIG_IGN)  # a second SIGTERM must not interrupt the cleaning up
    raise Terminated


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors (`tailor CMD: error: ...`, exit 2) instead of a usage block; the usage
    stays one `--help` away. Subcommand parsers are made of the same class."""

    def error(self, message: str):
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see `{self.prog} --help`)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(prog="tailor", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"tailor {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, module_name in COMMANDS.items():
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:  # a command not built yet must not break the others
            if exc.name != module_name:
                raise
            continue
        command = sub.add_parser(name, help=module.HELP, description=module.HELP)
        module.add_arguments(command)
        command.set_defaults(run=module.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    previous = None
    if threading.current_thread() is threading.main_thread():
        previous = signal.signal(signal.SIGTERM, _terminate)
    try:
        return int(args.run(args) or 0)
    except TailorError as exc:
        print(f"tailor {args.command}: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except Terminated:
        print(f"tailor {args.command}: terminated", file=sys.stderr)
        return EXIT_TERMINATED
    except KeyboardInterrupt:
        print(f"tailor {args.command}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        return 0
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


if __name__ == "__main__":
    sys.exit(main())
