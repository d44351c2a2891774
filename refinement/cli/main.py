"""The `tailor` command line: one subcommand per stage, looked up in a registry.

Each command module defines `HELP`, `add_arguments(parser)` and `run(args) -> int`, and keeps heavy imports
inside `run` so that `tailor plan` does not pay for the simulator or the learners.
Every project error is printed as one line on stderr and ends the process with its own exit status.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from tailor import __version__
from tailor.errors import TailorError

COMMANDS = {
    "plan": "tailor.refinement.cli.plan",
    "train": "tailor.refinement.cli.train",
    "refine": "tailor.refinement.cli.refine",
    "evaluate": "tailor.refinement.cli.evaluate",
    "domains": "tailor.refinement.cli.domains",
}

EXIT_INTERRUPTED = 130


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="tailor", description=__doc__.splitlines()[0])
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
    try:
        return int(args.run(args) or 0)
    except TailorError as exc:
        print(f"tailor {args.command}: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print(f"tailor {args.command}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        return 0


if __name__ == "__main__":
    sys.exit(main())
