"""`tailor evaluate soccer`: greedy vs refined execution measured in the simulator (Sec. 5.5, Tables 5.1-5.4)."""

from __future__ import annotations

import argparse
import json
import sys

from tailor.refinement.cli.arguments import whole_number

HELP = "measure refined vs greedy execution in the simulator over random scenarios"

HORIZONS = (1, 2, 3, 4)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("domain", metavar="DOMAIN", help="bundled domain (soccer) or its domain.pddl")
    parser.add_argument("--episodes", type=whole_number(0), default=1000, metavar="N",
                        help="approachBall -> dribbleBall scenarios (default 1000)")
    parser.add_argument("--oracle-episodes", type=whole_number(0), default=100, metavar="N",
                        help="of these, how many are also searched exhaustively in the simulator (default 100)")
    parser.add_argument("--waypoint-episodes", type=whole_number(0), default=100, metavar="N",
                        help="four-way-point navigations run with horizons 1-4 (default 100)")
    parser.add_argument("--seed", type=int, default=0, metavar="S", help="seed of scenarios and simulator")
    parser.add_argument("--jobs", type=whole_number(1), default=1, metavar="J", help="worker processes (default 1)")
    parser.add_argument("--json", action="store_true", help="print the report as JSON")


def _run_parallel(function, items, jobs: int, desc: str) -> list:
    from joblib import Parallel, delayed
    from tqdm import tqdm

    items = list(items)
    results = []
    with tqdm(total=len(items), desc=desc, unit="ep", file=sys.stderr, disable=not items) as bar:
        if jobs <= 1:
            for item in items:
                results.append(function(*item))
                bar.update()
        else:
            for result in Parallel(n_jobs=jobs, return_as="generator")(delayed(function)(*i) for i in items):
                results.append(result)
                bar.update()
    return results


def _fmt(value, pattern="{:.2f}") -> str:
    return "-" if value is None else pattern.format(value)


def _print_text(report: dict) -> None:
    out = sys.stdout.write
    s = report
    out(f"Soccer approachBall -> dribbleBall, {s['scenarios']} scenarios (seed {report['seed']}); "
        f"{s['episodes']} where greedy and refined both succeeded "
        f"(failed: greedy {s['failed_greedy']}, refined {s['failed_refined']})\n")
    out(f"  mean duration greedy (h=1)   {_fmt(s['greedy_mean'])} s\n")
    out(f"  mean duration refined (h=2)  {_fmt(s['refined_mean'])} s\n")
    out(f"  mean improvement (Eq. 5.3)   {_fmt(s['improvement'] and 100 * s['improvement'], '{:.1f}')}%"
        f"   (predicted {_fmt(s['predicted_improvement'] and 100 * s['predicted_improvement'], '{:.1f}')}%)\n")
    out(f"  paired t-test p-value        {_fmt(s['p_value'], '{:.2g}')}\n")
    out(f"  better / equal / worse       {s['better']} / {s['equal']} / {s['worse']}   "
        f"(mean improvement {_fmt(s['improvement_better'] and 100 * s['improvement_better'], '{:.1f}')}% / "
        f"{_fmt(s['improvement_equal'] and 100 * s['improvement_equal'], '{:.1f}')}% / "
        f"{_fmt(s['improvement_worse'] and 100 * s['improvement_worse'], '{:.1f}')}%)\n")
    out(f"  refined / simulated optimum  {_fmt(s['oracle_ratio'], '{:.3f}')} over {s['oracle_episodes']} episodes "
        f"(greedy / optimum {_fmt(s['greedy_oracle_ratio'], '{:.3f}')})\n")
    out(f"  optimizer median time        analytic {_fmt(s['analytic_ms_median'])} ms, ga {_fmt(s['ga_ms_median'])} ms; "
        f"agree within 1% in {_fmt(s['analytic_ga_agree'] and 100 * s['analytic_ga_agree'], '{:.1f}')}% "
        f"(analytic fell back to ga {s['analytic_fallbacks']} times)\n")
    w = report.get("waypoints")
    if w:
        out(f"\nFour way-points with goToPose (Table 5.3), {w['episodes']} episodes where every horizon succeeded:\n")
        out("  horizon  mean (s)  improvement vs h=1  vs h-1   p (vs h-1)  optimizer\n")
        for row in w["horizons"]:
            out(f"  h={row['horizon']:<6} {_fmt(row['mean']):>8}  {_fmt(100 * row['improvement'], '{:.1f}'):>17}%"
                f"  {_fmt(100 * row['improvement_over_previous'], '{:.1f}'):>6}%  {_fmt(row['p_value_vs_previous'], '{:.2g}'):>10}"
                f"  {','.join(row['methods'])}\n")


def run(args: argparse.Namespace) -> int:
    from tailor.refinement.evaluation.experiments import (
        prepared_job,
        score_episode,
        summarize_score,
        summarize_waypoints,
        waypoint_episode,
    )
    from tailor.refinement.pipeline import prepare, resolve_task

    from tailor.planner_bridge import resolve_problem
    from tailor.planner_bridge.errors import InputFileError
    from tailor.refinement.errors import TailorError

    for problem in ("score", "waypoints"):
        try:
            resolve_problem(args.domain, problem)
        except InputFileError as exc:
            if exc.file != problem:  # the domain itself is unknown: that error says so
                raise
            raise TailorError(f"the evaluation needs the soccer problems 'score' and 'waypoints' beside the domain, "
                              f"and {problem!r} is not there", file=args.domain) from None
    score = prepare(resolve_task(args.domain, "score"))
    job = prepared_job(score, args.seed)
    rows = _run_parallel(score_episode, [(job, i, i < args.oracle_episodes) for i in range(args.episodes)],
                         args.jobs, "greedy vs refined")
    report = {"domain": score.plan.domain, "seed": args.seed}
    report.update(summarize_score(rows))
    if args.waypoint_episodes:
        waypoints = prepare(resolve_task(args.domain, "waypoints"))
        wjob = prepared_job(waypoints, args.seed)
        wrows = _run_parallel(waypoint_episode, [(wjob, i, HORIZONS) for i in range(args.waypoint_episodes)],
                              args.jobs, "way-points h=1..4")
        report["waypoints"] = summarize_waypoints(wrows, HORIZONS)
    if args.json:
        sys.stdout.write(json.dumps(report, indent=1) + "\n")
    else:
        _print_text(report)
    return 0
