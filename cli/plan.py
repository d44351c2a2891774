"""`tailor plan DOMAIN PROBLEM`: plan a PDDL pair into a partial-order plan with causal links (Sec. 5.2), printed
as VHPOP-like text, as JSON, or as a sequential IPC plan file (`--format ipc`, as Fast Downward's `sas_plan`)."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable

from tailor.cli.arguments import positive_seconds
from tailor.outputs import Provenance, provenance, versioned
from tailor.planner_bridge import AbstractPlan, format_ipc, plan_files, render_text, resolve_problem


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("domain", metavar="DOMAIN", help="domain.pddl file, the folder holding it, or the name of a bundled domain (see `tailor domains`)")
    parser.add_argument("problem", metavar="PROBLEM", help="problem .pddl file, or the name of one of its problems")
    parser.add_argument(
        "--planner", default="pyperplan", metavar="NAME",
        help="any installed unified-planning engine (fast-downward with `pip install 'tailor[planners]'`), or pocl "
             "(our POCL planner; default: pyperplan)",
    )
    parser.add_argument(
        "--timeout", type=positive_seconds, default=None, metavar="S", help="seconds the planner may search (default: no limit)"
    )
    output = parser.add_mutually_exclusive_group()
    output.add_argument(
        "--format", choices=sorted(FORMATS), default="text",
        help="text: the partial-order plan with its causal links, VHPOP-like (default); json: the same as JSON; "
             "ipc: a sequential IPC plan file, one (action arg ...) a line in a valid order, as Fast Downward "
             "writes sas_plan",
    )
    output.add_argument("--json", action="store_const", const="json", dest="format", help="the same as --format json")


def format_json(data: dict) -> str:
    """JSON with one step, link or ordering per line: valid JSON that diffs well in golden files."""
    lines = []
    for key, value in data.items():
        if isinstance(value, list) and value:
            items = ",\n".join(f"    {json.dumps(item)}" for item in value)
            lines.append(f"  {json.dumps(key)}: [\n{items}\n  ]")
        else:
            lines.append(f"  {json.dumps(key)}: {json.dumps(value)}")
    return "{\n" + ",\n".join(lines) + "\n}\n"


# Each output format and what writes it from the plan and its provenance (which the JSON carries); `--format`
# takes its choices from here.
FORMATS: dict[str, Callable[[AbstractPlan, Provenance], str]] = {
    "text": lambda plan, origin: render_text(plan),
    "json": lambda plan, origin: format_json(versioned("plan", plan.to_json(), origin)),
    "ipc": lambda plan, origin: format_ipc(plan),
}


def run(args: argparse.Namespace) -> int:
    domain, problem = resolve_problem(args.domain, args.problem)
    plan = plan_files(domain, problem, planner=args.planner, timeout=args.timeout)
    sys.stdout.write(FORMATS[args.format](plan, provenance(getattr(args, "argv", None))))
    return 0
