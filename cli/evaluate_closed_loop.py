"""`tailor evaluate DOMAIN --closed-loop` and `--learning-curve`: closed-loop execution measured (issue 30, Ch. 8.1).

--closed-loop: random situations of the binding's comparison generator (or --situations), each refined once and
executed open and closed loop with the same simulator seed (and --disturb); failed runs, mean time with a failed
run charged its time + 30 s, the share of open-loop failures closed loop completes, the overhead.
--learning-curve: a stream of --episodes tasks executed closed loop on the robot --variant while the models
learn in operation; the models' error on the tasks met so far and refined vs greedy time, per task (--plot).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from tailor.errors import UsageError

CURVE_WINDOW = 20  # tasks per point of the learning curve's moving mean
CURVE_HORIZON = 2  # the refined runs of the stream refine this many actions ahead


def _check(args, binding) -> None:
    wrong = binding.entry.unknown_option(args.disturb, args.variant)
    if wrong is not None:
        raise UsageError(wrong)


def _write_json(kind: str, report: dict, rows: list[dict], args, models_dir) -> int:
    """The report and its rows as JSON, with the provenance of the command that made them."""
    from tailor.outputs import json_text, model_files, provenance, versioned

    origin = provenance(getattr(args, "argv", None), {"seed": args.seed}, model_files(models_dir))
    sys.stdout.write(json_text(versioned(kind, {**report, "rows": rows}, origin)) + "\n")
    return 0


def run_closed_loop(args: argparse.Namespace, domain_dir, binding, plan, models_dir, items) -> int:
    from tailor.refinement.evaluation.closed_loop import closed_loop_episode, summarize_closed_loop
    from tailor.sims.parallel import run_in_workers

    _check(args, binding)
    if args.variant is not None:
        raise UsageError("--variant belongs to --learning-curve (a changed robot the models learn to follow)")
    rows = run_in_workers(closed_loop_episode, [(job, i, objects, args.disturb) for job, i, objects in items],
                          args.jobs, "open vs closed loop", unit="situation")
    report = {"domain": binding.domain or domain_dir.name, "simulator": binding.simulator, "seed": args.seed,
              "generator": plan.comparison, "disturbance": args.disturb, "situations": len(rows)}
    report.update(summarize_closed_loop(rows))
    if args.json:
        return _write_json("evaluate_closed_loop", report, rows, args, models_dir)
    out = sys.stdout.write
    out(f"Domain {report['domain']}: {len(rows)} random '{plan.comparison}' situations (seed {args.seed}), each "
        f"refined once and executed open and closed loop with the same simulator seed"
        f"{', disturbance ' + args.disturb if args.disturb else ''}\n")
    for side in ("open_loop", "closed_loop"):
        s = report[side]
        mean = "-" if s["mean_penalized"] is None else f"{s['mean_penalized']:.2f} s"
        out(f"  {side.replace('_', ' '):<12} failed {s['failed_runs']:>4} of {s['runs']}, mean time {mean} (a failed "
            f"run charged +{report['penalty']:.0f} s), {s['re_refinements']} re-refinements, {s['replans']} replans\n")
    rec = report["recovered_share"]
    out(f"  recovered    {'-' if rec is None else f'{100 * rec:.1f}%'} of the runs open loop fails\n")
    p, share = report["p_closed_faster"], report["overhead_share"]
    out(f"  closed - open mean {report['closed_minus_open_mean']:+.2f} s (Wilcoxon one-sided p "
        f"{'-' if p is None else f'{p:.2g}'}); overhead median "
        f"{'-' if share is None else f'{100 * share:.2f}%'} of execution time\n")
    return 0


def run_learning_curve(args: argparse.Namespace, domain_dir, binding, plan, models_dir, items, fresh=None) -> int:
    """The stream of --episodes tasks learning in operation; with --reference-episodes, models trained from scratch
    on the variant compared on the stream's last CURVE_WINDOW tasks and, where `fresh(n)` draws n tasks after the
    stream, on --heldout-tasks of them with every model frozen (the stream's last models, the scratch ones and
    those as trained): the same tasks and seeds for all, none of them learned from."""
    from tailor.outputs import check_output_file
    from tailor.refinement.evaluation.closed_loop import learning_stream

    _check(args, binding)
    if args.plot:
        check_output_file(args.plot, ".png")
    rows, learner = learning_stream(items, args.variant, horizon=CURVE_HORIZON)
    reference = None
    if args.reference_episodes:
        from tailor.refinement.evaluation.closed_loop import (episodes_error, fixed_models, frozen, frozen_runs,
                                                              reference_error, reference_improvement,
                                                              reference_models)
        from tailor.refinement.situations import job_models, situation_sequence

        job, _, objects = items[0]
        models = job_models(job, situation_sequence(job, objects))
        trained = reference_models(domain_dir, binding, dict(models), args.variant, args.reference_episodes, args.seed,
                                   args.jobs)
        reference = {"episodes": args.reference_episodes, "mae_last": reference_error(rows[-CURVE_WINDOW:], trained),
                     "improvement_last": reference_improvement(items[-CURVE_WINDOW:], args.variant, trained)}
        if fresh is not None and args.heldout_tasks and learner is not None:
            tasks = fresh(args.heldout_tasks)
            learned = frozen(learner)  # (its success classifiers too, as the stream left them)
            sets = {"learned": learned.adapted(dict(models)), "reference": trained, "trained": dict(models)}
            runs = {name: frozen_runs(tasks, args.variant, learned if name == "learned" else fixed_models(chosen),
                                      CURVE_HORIZON) for name, chosen in sets.items()}
            pooled = [e for _, executed in runs.values() for e in executed]  # every held-out run's actions
            held = {"tasks": len(tasks), "executions": sum(e.succeeded for e in pooled)}
            for name, chosen in sets.items():
                held[f"improvement_{name}"] = runs[name][0]
                held[f"mae_{name}"] = episodes_error(pooled, chosen)
            held["mae_ratio"] = (held["mae_learned"] / held["mae_reference"]
                                 if held["mae_learned"] is not None and held["mae_reference"] else None)
            reference["heldout"] = held
    errors = [np.mean(r["relative_errors"]) if r["relative_errors"] else np.nan for r in rows]
    first = rows[:CURVE_WINDOW]
    last = rows[-CURVE_WINDOW:]

    def mean_error(chunk):
        values = [e for r in chunk for e in r["abs_errors"]]
        return float(np.mean(values)) if values else None

    def gain(chunk):
        g = np.mean([r["greedy"] for r in chunk])
        return float((g - np.mean([r["refined"] for r in chunk])) / g) if chunk else None

    report = {"domain": binding.domain or domain_dir.name, "simulator": binding.simulator, "seed": args.seed,
              "generator": plan.comparison, "variant": args.variant, "tasks": len(rows), "horizon": CURVE_HORIZON,
              "mae_first": mean_error(first), "mae_last": mean_error(last),
              "improvement_first": gain(first), "improvement_last": gain(last)}
    if reference is not None:
        report["reference"] = reference
        report["mae_ratio_to_reference"] = (report["mae_last"] / reference["mae_last"]
                                            if reference["mae_last"] and report["mae_last"] is not None else None)
    if args.plot:
        from tailor.refinement.evaluation.closed_loop_plots import draw_learning_curve

        draw_learning_curve(args.plot, rows, errors, report, CURVE_WINDOW)
        report["plot"] = str(args.plot)
    if args.json:
        return _write_json("evaluate_learning_curve", report, rows, args, models_dir)
    out = sys.stdout.write
    out(f"Domain {report['domain']}: {len(rows)} tasks executed closed loop, learning in operation"
        f"{' on variant ' + args.variant if args.variant else ''} (seed {args.seed})\n")
    fmt = lambda v, unit="": "-" if v is None else f"{v:.3f}{unit}"  # noqa: E731
    out(f"  duration MAE  first {CURVE_WINDOW} tasks {fmt(report['mae_first'], ' s')}, last {CURVE_WINDOW} "
        f"{fmt(report['mae_last'], ' s')}\n")
    pct = lambda v: "-" if v is None else f"{100 * v:.1f}%"  # noqa: E731
    out(f"  refined vs greedy  first {pct(report['improvement_first'])}, last {pct(report['improvement_last'])}\n")
    if reference is not None:
        out(f"  models trained from scratch on {reference['episodes']} episodes of the variant per scenario: MAE "
            f"{fmt(reference['mae_last'], ' s')} on the last {CURVE_WINDOW} tasks' actions (learning in operation "
            f"{fmt(report['mae_ratio_to_reference'])} x that); refined vs greedy with them on the last "
            f"{CURVE_WINDOW} tasks {pct(reference['improvement_last'])}\n")
        held = reference.get("heldout")
        if held:
            out(f"  on {held['tasks']} held-out tasks after the stream, every model frozen: refined vs greedy "
                f"{pct(held['improvement_learned'])} with the models learned in operation, "
                f"{pct(held['improvement_reference'])} with those trained from scratch, "
                f"{pct(held['improvement_trained'])} with those as trained; duration MAE on their "
                f"{held['executions']} executed actions {fmt(held['mae_learned'], ' s')} learned in operation "
                f"({fmt(held['mae_ratio'])} x scratch {fmt(held['mae_reference'], ' s')}; as trained "
                f"{fmt(held['mae_trained'], ' s')})\n")
    if args.plot:
        out(f"Wrote {args.plot}\n")
    return 0
