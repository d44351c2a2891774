"""`tailor execute DOMAIN PROBLEM`: plan, refine and execute one action at a time, closed loop (Ch. 8.1).

Each action is monitored against its prediction; a deviation re-refines the next window from the measured
state, a failure replans from the facts that hold (up to --replans times). --learn recalibrates the duration
models on the executed actions (every --learn-every of them; with --log, also on the executions logged before).
--objective and --max are refine's (Ch. 8.1): every refinement of the run, re-refinements and replans too,
minimizes that objective within those limits.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from tailor.cli.arguments import add_models_argument, add_objective_arguments, positive_seconds, seed, whole_number
from tailor.cli.main import EXIT_NOT_COMPLETED
from tailor.outputs import check_output_file, json_text
from tailor.progress import showing_progress
from tailor.errors import UsageError
from tailor.refinement.objective_grammar import ObjectiveSyntaxError, bounds_of
from tailor.refinement.optimizers import DEFAULT_OPTIMIZER, OPTIMIZERS



def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("domain", metavar="DOMAIN", help="domain.pddl file, the folder holding it, or the name of a "
                        "bundled domain (see `tailor domains`)")
    parser.add_argument("problem", metavar="PROBLEM", help="problem .pddl file, or the name of one of its problems")
    parser.add_argument("--open-loop", action="store_true", help="execute the refined plan without monitoring, "
                        "re-refinement or replanning (the first failure ends the run)")
    parser.add_argument("--replans", type=whole_number(0), default=2, metavar="N",
                        help="plan again after a failure at most N times (default 2)")
    parser.add_argument("--learn", action="store_true", help="recalibrate the duration models and success "
                        "classifiers on the executed actions as they come (with --log: on the executions logged "
                        "before, too)")
    parser.add_argument("--learn-every", type=whole_number(1), default=5, metavar="K",
                        help="with --learn: recalibrate after every K executed actions (default 5)")
    parser.add_argument("--log", metavar="DIR", help="keep every executed action in DIR/<action>.csv (the "
                        "recorded-executions log `tailor train --log` reads, source 'execution'), added to what "
                        "is there")
    parser.add_argument("--disturb", metavar="NAME", help="a seeded disturbance of the simulated world (see "
                        "`tailor domains`), never known to refinement")
    parser.add_argument("--variant", metavar="NAME", help="a changed robot the simulator offers (see `tailor domains`)")
    parser.add_argument("--horizon", type=whole_number(1), default=2, metavar="H",
                        help="actions optimized together (default 2; 1 is greedy)")
    parser.add_argument("--optimizer", choices=sorted(OPTIMIZERS), default=DEFAULT_OPTIMIZER,
                        help=f"as for `tailor refine` (default: {DEFAULT_OPTIMIZER})")
    add_objective_arguments(parser)  # every refinement of the run minimizes it: re-refinements and replans too
    parser.add_argument("--seed", type=seed, default=0, metavar="S",
                        help="seed of the optimizer and of the simulator's noise and disturbance (default 0)")
    parser.add_argument("--belief", metavar="FILE", help="belief state file (default: PROBLEM's stem + .toml)")
    add_models_argument(parser)
    parser.add_argument("--planner", default="pyperplan", metavar="NAME", help="unified-planning engine, or pocl")
    parser.add_argument("--timeout", type=positive_seconds, default=None, metavar="S", help="planner time limit")
    parser.add_argument("--json", action="store_true", help="print the events and the run's summary as JSON")
    parser.add_argument("--plot", metavar="FILE.png", help="draw the executed trajectory with its re-refinements "
                        "and replans")


def run(args: argparse.Namespace) -> int:
    from tailor.outputs import provenance, versioned
    from tailor.refinement.execution import run as prepare_run
    from tailor.refinement.execution import summarize

    if args.plot:
        check_output_file(args.plot, ".png")
    try:
        limits = bounds_of(args.limits)
    except ObjectiveSyntaxError as exc:
        raise UsageError(f"--max: {exc}") from None
    loop = prepare_run(args.domain, args.problem, args.belief, horizon=args.horizon, optimizer=args.optimizer,
                     seed=args.seed, models=args.models, closed_loop=not args.open_loop, replans=args.replans,
                     learn=args.learn, learn_every=args.learn_every, disturbance=args.disturb, variant=args.variant,
                     log=args.log, planner=args.planner, timeout=args.timeout, objective=args.objective,
                     limits=limits)
    collected = []
    with showing_progress(False):
        for event in loop.events():
            collected.append(event)
            if not args.json:
                print(_line(event), flush=True)
    summary = summarize(collected)
    if args.plot:
        from tailor.cli.execute_plot import draw_run

        written = draw_run(collected, args.domain, Path(args.plot))
        print(f"wrote {written}", file=sys.stderr)
    if args.json:
        origin = provenance(getattr(args, "argv", None), {"seed": args.seed}, loop.model_files())
        data = {"events": [e.to_json() for e in collected], "summary": summary.to_json()}
        sys.stdout.write(json_text(versioned("execute", data, origin)) + "\n")
    else:
        print(f"{'completed' if summary.completed else 'NOT completed'}: {summary.actions} action(s) executed in "
              f"{summary.duration:.2f} s, {summary.re_refinements} re-refinement(s), {summary.replans} replan(s), "
              f"overhead {summary.overhead * 1000:.0f} ms")
    return 0 if summary.completed else EXIT_NOT_COMPLETED


def _line(event) -> str:
    if event.kind == "executed":
        return (f"{event.pddl} {event.action}: predicted {event.predicted:.2f} s, measured {event.measured:.2f} s, "
                f"{event.outcome}")
    if event.kind == "re-refined":
        return f"  re-refined {event.pddl} from the measured state: {event.reason}"
    if event.kind == "replanned":
        return f"  replanned ({event.reason}): {' '.join(event.plan) or 'nothing left to do'}"
    return f"finished: {event.outcome} ({event.reason})"


__all__ = ["add_arguments", "run"]
