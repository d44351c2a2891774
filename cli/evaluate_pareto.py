"""`tailor evaluate DOMAIN --pareto W1,W2,...`: the time-energy front (Ch. 8.1, issue 31).

The random situations of the binding's comparison generator (or --situations), each refined for `duration + W *
energy` for every weight W (0, the duration alone, always among them) and greedily, all executed with the same
simulator seed: measured mean time, energy and error per weight, the changes against W = 0 and the Wilcoxon p of
energy; with `--max MEASURE=BOUND` also duration-only refinement keeping that bound, and the share of runs that
end within it with and without (tailor.refinement.evaluation.pareto).
"""

from __future__ import annotations

import argparse
import math
import sys

from tailor.cli.arguments import announce_models, number
from tailor.errors import UsageError

WEIGHT_LIMIT = 1e6  # a larger energy weight is no trade-off anyone sweeps (and its sums lose the duration)


def energy_weights(text: str) -> tuple[float, ...]:
    """An argparse type: comma-separated energy weights, each a finite number from 0 to WEIGHT_LIMIT; returned
    sorted, without repeats, with 0 (the duration alone, the reference) added where missing."""
    parts = [part.strip() for part in text.split(",")]
    if not any(parts) or not all(parts):  # (an empty item is a typing mistake, as in --risk-sweep)
        raise argparse.ArgumentTypeError(f"expected comma-separated energy weights, e.g. 0,0.1,0.3,1, not {text!r}")
    weights = []
    for part in parts:
        value = number(part)
        if not (math.isfinite(value) and 0.0 <= value <= WEIGHT_LIMIT):
            raise argparse.ArgumentTypeError(f"an energy weight is a number from 0 to {WEIGHT_LIMIT:g}, not {part!r}")
        weights.append(value + 0.0)  # (-0.0 is 0)
    return tuple(sorted({0.0, *weights}))


def _check(args: argparse.Namespace) -> None:
    for flag, given in (("--assertion", args.assertion), ("--meta", args.meta), ("--closed-loop", args.closed_loop),
                        ("--learning-curve", args.learning_curve), ("--risk-sweep", bool(args.risk_sweep)),
                        ("--filter", bool(args.filter))):
        if given:
            raise UsageError(f"--pareto and {flag} are two experiments: give one")
    if args.disturb is not None or args.variant is not None:
        raise UsageError("--disturb belongs to --closed-loop, --variant to --learning-curve")


def run_pareto(args: argparse.Namespace, domain_dir, binding, plan, source, items) -> int:
    """Run the sweep on `items` (job, index, belief values) and print the report (text, or JSON with --json)."""
    from tailor.outputs import check_output_file
    from tailor.refinement import pipeline
    from tailor.refinement.evaluation.pareto import energy_objective, pareto_episode, summarize_pareto
    from tailor.refinement.objective_grammar import ObjectiveSyntaxError, bounds_of
    from tailor.refinement.refine import check_measures, resolve_risk
    from tailor.refinement.situations import job_models, situation_sequence
    from tailor.sims.parallel import run_in_workers

    _check(args)
    weights = args.pareto
    try:
        limits = bounds_of(args.limits)
    except ObjectiveSyntaxError as exc:
        raise UsageError(f"--max: {exc}") from None
    for option, objective, bounds in (("--pareto", energy_objective(max(weights)), ()), ("--max", None, limits)):
        wrong = pipeline.unknown_measure(binding, objective, bounds)
        if wrong is not None:
            raise UsageError(f"{option}: {wrong}")
    if args.plot:
        check_output_file(args.plot, ".png")
    risk = 0.0 if args.risk is None else args.risk
    if items:  # the models loaded once here: a missing model of a measure fails before any work
        job, _, objects = items[0]
        sequence = situation_sequence(job, objects)
        models = job_models(job, sequence)
        check_measures(sequence.actions, models, energy_objective(max(weights)), limits)
        risk = resolve_risk(args.risk, models.values())
    announce_models("evaluate", source)
    neighbourhood = binding.refinement.neighbourhood if args.neighbourhood is None else args.neighbourhood
    rows = run_in_workers(pareto_episode, [(job, i, objects, weights, limits, args.optimizer, risk, neighbourhood)
                                           for job, i, objects in items], args.jobs, "energy weights",
                          getattr(args, "progress", True), unit="situation")
    units = {name: (binding.entry.units[name].unit if name in binding.entry.units else "s")
             for name in ("duration", "energy", "error")}
    report = {"domain": binding.domain or domain_dir.name, "simulator": binding.simulator, "seed": args.seed,
              "models": str(source.path), "comparison": plan.comparison, "optimizer": args.optimizer, "risk": risk,
              "neighbourhood": neighbourhood, "horizon": 2, "objective": "duration + W*energy",
              "weights": list(weights), "measure_units": units,
              "measured": "per run: duration and energy summed over its actions, error the largest end error of "
                          "its actions"}
    report.update(summarize_pareto(rows, weights, limits))
    if args.plot:
        from tailor.refinement.evaluation.pareto_plots import draw_pareto

        draw_pareto(args.plot, report, units)
        report["plot"] = str(args.plot)
    if args.json:
        from tailor.outputs import json_text, model_files, provenance, versioned

        origin = provenance(getattr(args, "argv", None), {"seed": args.seed}, model_files(source.path))
        sys.stdout.write(json_text(versioned("evaluate_pareto", {**report, "rows": rows}, origin)) + "\n")
    else:
        _print_text(report)
    return 0


def _fmt(value, pattern: str = "{:.2f}") -> str:
    return "-" if value is None else pattern.format(value)


def _pct(value) -> str:
    return "-" if value is None else f"{100 * value:+.1f}%"


def _share(value) -> str:
    return "-" if value is None else f"{100 * value:.1f}%"


def _print_text(report: dict) -> None:
    out = sys.stdout.write
    u = report["measure_units"]
    out(f"Domain {report['domain']}: {report['situations']} random '{report['comparison']}' situations (seed "
        f"{report['seed']}), refined (h=2, {report['optimizer']}, risk {report['risk']:g}, neighbourhood "
        f"{report['neighbourhood']:g}) for duration + W*energy and executed with the "
        f"same simulator seed; means over the {report['episodes']} situations where greedy and every weight "
        "succeeded (a situation with a failed run is left out of every mean)\n")
    out(f"  {'run':<13} {'failed':>6}  {'time (' + u['duration'] + ')':>9}  {'energy (' + u['energy'] + ')':>11}  "
        f"{'error (' + u['error'] + ')':>10}  {'time vs W=0':>11}  {'energy vs W=0':>13}  {'p energy':>9}  front\n")
    g = report["greedy"]
    out(f"  {'greedy (h=1)':<13} {g['failed']:>6}  {_fmt(g['duration']):>9}  {_fmt(g['energy']):>11}  "
        f"{_fmt(g['error'], '{:.4f}'):>10}  {'':>11}  {'':>13}  {'':>9}  {'*' if g['front'] else ''}\n")
    for e in report["pareto"]:
        out(f"  {'W=' + format(e['weight'], 'g'):<13} {e['failed']:>6}  {_fmt(e['duration']):>9}  "
            f"{_fmt(e['energy']):>11}  {_fmt(e['error'], '{:.4f}'):>10}  {_pct(e['duration_change']):>11}  "
            f"{_pct(e['energy_change']):>13}  {_fmt(e['p_energy'], '{:.2g}'):>9}  {'*' if e['front'] else ''}\n")
    out(f"  (* on the time-energy front; p: {report['test']}; error: the largest end error of a run's actions)\n")
    limit = report.get("limit")
    if limit:
        bounds = ", ".join(f"{m} <= {b:g} {u.get(m, '')}".rstrip() for m, b in limit["bounds"].items())
        out(f"\nWith --max ({bounds} for every action), duration-only refinement (W=0) with and without it:\n")
        out(f"  the bound binds (W=0's choice breaks it, as predicted) in {limit['binds']} of {limit['situations']} "
            f"situations ({_share(limit['binds_share'])}); no choice keeps it in {limit['unattainable']}\n")
        out(f"  runs ending within it    without {_share(limit['within_duration_only'])}, with "
            f"{_share(limit['within_limited'])} (where it binds: {_share(limit['within_duration_only_where_binding'])}"
            f", {_share(limit['within_limited_where_binding'])}; a failed run is not within)\n")
        shares = limit["actions_within"]
        out("  actions ending within it " + ", ".join(
            f"{action} {_share(shares['duration_only'].get(action))} / {_share(share)}"
            for action, share in shares["limited"].items()) + " (without / with)\n")
        out(f"  failed runs              without {limit['failed_duration_only']}, with {limit['failed_limited']}\n")
        out(f"  with against without     time {_pct(limit['duration_change'])}, energy {_pct(limit['energy_change'])}"
            f", error {_pct(limit['error_change'])} (means over the {limit['episodes']} situations where both "
            "succeeded)\n")
    if report.get("plot"):
        out(f"Wrote {report['plot']}\n")
