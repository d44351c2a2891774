"""docs/commands.md from the command line's own parsers: `tailor.cli.main.COMMANDS` names the commands and
`build_parser(command)` builds each one in full, so the page says what `tailor COMMAND --help` says.

argparse has no public way to list a parser's arguments; its `_actions` (and the sub-parsers action's `choices`)
are what every argparse documentation tool reads, and they have not changed in Python 3.
"""

from __future__ import annotations

import argparse
import os

from mdtext import GENERATED, code, escape, table

USAGE_WIDTH = 80  # argparse wraps the usage to the terminal's width: a fixed one keeps the page the same


def _subparser(parser: argparse.ArgumentParser, command: str) -> argparse.ArgumentParser:
    actions = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return actions[0].choices[command]


def _help(action: argparse.Action, prog: str) -> str:
    """The help text as argparse prints it: `%(default)s` and the like expanded."""
    text = action.help or ""
    if "%" in text:
        params = {k: v for k, v in vars(action).items() if v is not argparse.SUPPRESS}
        params["prog"] = prog
        if params.get("choices") is not None:
            params["choices"] = ", ".join(map(str, params["choices"]))
        text = text % params
    return text


def _invocation(action: argparse.Action) -> str:
    """`--out DIR`, `--backend {loky,dask,ray}`, `-q, --quiet`, `DOMAIN`: how the argument is written."""
    if not action.option_strings:
        return action.metavar or action.dest.upper() if action.choices is None else "{" + ",".join(action.choices) + "}"
    if action.nargs == 0:
        return ", ".join(action.option_strings)
    value = action.metavar or ("{" + ",".join(map(str, action.choices)) + "}" if action.choices
                               else action.dest.upper())
    return ", ".join(f"{option} {value}" for option in action.option_strings)


def _arguments(parser: argparse.ArgumentParser) -> str:
    rows = []
    for action in parser._actions:
        if action.help is argparse.SUPPRESS or isinstance(action, (argparse._HelpAction, argparse._SubParsersAction)):
            continue
        rows.append([code(_invocation(action)), escape(_help(action, parser.prog))])
    return table(["argument", "what it does"], rows, align="ll")


def _usage(parser: argparse.ArgumentParser) -> str:
    formatter = argparse.HelpFormatter(parser.prog, width=USAGE_WIDTH)
    formatter.add_usage(parser.usage, parser._actions, parser._mutually_exclusive_groups)
    return formatter.format_help().strip()


def page() -> str:
    """The whole page: tailor's own options and command list, then one section per command."""
    os.environ["COLUMNS"] = str(USAGE_WIDTH)  # argparse's other formatters read it
    from tailor.cli.main import COMMANDS, build_parser

    top = build_parser()
    out = [GENERATED.format(source="the argparse parsers of tailor.cli (tailor.cli.main.build_parser)"),
           "# Command reference\n",
           "Every command, option and argument of `tailor`, as its parsers define them (the same text as "
           "`tailor --help` and `tailor COMMAND --help`). What a command's output means is in the guides; what its "
           "exit status means is in [Exit statuses](exit-statuses.md).\n",
           "```text\n" + _usage(top) + "\n```\n",
           escape(top.description.replace("\n", " ")) + "\n",
           table(["command", "what it does"],
                 [[f"[{code('tailor ' + name)}](#tailor-{name})", escape(summary)]
                  for name, (_, summary) in COMMANDS.items()], align="ll"),
           "\nOptions of `tailor` itself (`-q` and `-v` are also accepted after the command):\n",
           _arguments(top)]
    for name in COMMANDS:
        parser = _subparser(build_parser(name), name)
        out += [f"\n## tailor {name}\n",
                escape((parser.description or "").replace("\n", " ")) + "\n",
                "```text\n" + _usage(parser) + "\n```\n",
                _arguments(parser)]
    return "\n".join(out)
