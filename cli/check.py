"""`tailor check DOMAIN [PROBLEM]`: what the binding and the belief make of each problem, before anything moves.

Per problem: its plan's free parameters with their ranges, every belief value and whether it is read, and the
warnings `tailor refine` also prints (a belief value never read; an object's quantity left free although the
belief gives it; a `read` on a fact that is not true initially). Exit 0 with warnings, unless --strict.
"""

from __future__ import annotations

import argparse
import sys

from tailor.cli.arguments import positive_seconds
from tailor.errors import BindingError
from tailor.outputs import json_text, provenance, versioned
from tailor.planner_bridge import bundled_problems, plan_pddl, resolve_domain_dir
from tailor.refinement import pipeline

DESCRIPTION = (
    "say what the binding and each problem's belief file make of the problem: the free parameters with their "
    "ranges, every belief value and whether anything reads it, and warnings where the pair looks wrong (a "
    "value never read, an object's position left free for refinement to choose, a `read` on a fact that is "
    "not true initially). `tailor refine` prints the same warnings; --strict makes them errors (exit 11).")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("domain", metavar="DOMAIN", help="domain.pddl file, the folder holding it, or the name of a "
                        "bundled domain")
    parser.add_argument("problem", metavar="PROBLEM", nargs="?",
                        help="problem .pddl file or name (default: every problem in the domain's problems/)")
    parser.add_argument("--belief", metavar="FILE", help="belief state file (with PROBLEM; default: its .toml)")
    parser.add_argument("--planner", default="pyperplan", metavar="NAME", help="unified-planning engine, or pocl")
    parser.add_argument("--timeout", type=positive_seconds, default=None, metavar="S", help="planner time limit")
    parser.add_argument("--strict", action="store_true", help="a warning is an error (exit 11)")
    parser.add_argument("--json", action="store_true", help="print the report as JSON")


def run(args: argparse.Namespace) -> int:
    problems = [args.problem] if args.problem else bundled_problems(resolve_domain_dir(args.domain))
    reports = []
    for problem in problems:
        task = pipeline.resolve_task(args.domain, problem, args.belief if args.problem else None)
        inputs = pipeline.read_task(task)
        plan = plan_pddl(inputs.pddl, planner=args.planner, timeout=args.timeout)
        checked = pipeline.check(inputs, plan)
        reports.append((task, plan, checked))
    if args.json:
        sys.stdout.write(json_text(versioned("check", {"problems": [
            {"problem": plan.problem, "file": str(task.problem), "belief_file": str(task.belief), **checked.to_json()}
            for task, plan, checked in reports]}, provenance(getattr(args, "argv", None)))) + "\n")
    else:
        for task, plan, checked in reports:
            _print_text(task, plan, checked)
    warnings = [w for _, _, checked in reports for w in checked.warnings]
    if args.strict and warnings:
        raise BindingError(f"{len(warnings)} warning(s), the first: {warnings[0]} (--strict)")
    return 0


def _print_text(task, plan, checked) -> None:
    out = sys.stdout.write
    out(f"{plan.domain}/{plan.problem} ({task.problem}, belief {task.belief}):\n")
    free = checked.sequence.free_parameters()
    out(f"  free parameters: {len(free)}\n")
    for p in free:
        out(f"    {p.id:<20} [{p.low:g}, {p.high:g}]\n")
    out(f"  belief values: {len(checked.belief)}\n")
    for use in checked.belief:
        out(f"    {use.object + '.' + use.quantity:<20} {use.value:<10g} {'read' if use.read else 'NOT READ'}\n")
    for warning in checked.warnings:
        out(f"  warning: {warning}\n")
    if not checked.warnings:
        out("  no warnings\n")
