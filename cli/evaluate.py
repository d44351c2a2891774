"""`tailor evaluate DOMAIN`: greedy vs refined execution measured in the simulator (Sec. 5.5, Tables 5.1-5.4)."""

from __future__ import annotations

import argparse
import sys

from tailor.refinement.optimizers import DEFAULT_OPTIMIZER, OPTIMIZERS
from tailor.cli.arguments import (
    add_backend_arguments,
    add_filter_arguments,
    add_models_argument,
    add_neighbourhood_argument,
    add_limit_argument,
    number,
    add_risk_argument,
    announce_models,
    backend_session,
    MAX_EPISODES,
    risk_lambda,
    seed,
    whole_number,
    worker_count,
)
from tailor.cli.evaluate_pareto import energy_weights


HORIZONS = (1, 2, 3, 4)  # run on every horizon situation; reported where one differs from a shorter horizon
HORIZON_EPISODES = 100  # situations of the horizons experiment (Table 5.3) without --horizon-episodes


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("domain", metavar="DOMAIN", help="bundled domain name, a domain folder, or its domain.pddl")
    parser.add_argument("--episodes", type=whole_number(0, MAX_EPISODES), default=1000, metavar="N",
                        help="random situations refined greedily and with h=2 (default 1000)")
    parser.add_argument("--oracle-episodes", type=whole_number(0, MAX_EPISODES), default=100, metavar="N",
                        help="of these, how many are also searched in the simulator (default 100)")
    parser.add_argument("--horizon-episodes", type=whole_number(0, MAX_EPISODES), default=None, metavar="N",
                        help=f"situations run with horizons 1-4 (Table 5.3; default {HORIZON_EPISODES}, or --episodes "
                             "if fewer); a horizon longer than a sequence acts as its length, and one longer than "
                             "every sequence is not listed")
    parser.add_argument("--situations", metavar="NAME", default=None,
                        help="a situation generator of the domain's simulator to evaluate on (greedy vs refined and "
                             "the horizons, or --assertion) instead of the binding's [evaluation] ones, e.g. "
                             "another scenario")
    parser.add_argument("--seed", type=seed, default=0, metavar="S", help="seed of situations and simulator")
    parser.add_argument("--jobs", type=worker_count, default=1, metavar="J",
                        help="worker processes (default 1; at most the number of CPUs)")
    add_models_argument(parser)
    parser.add_argument("--json", action="store_true", help="print the report as JSON")
    add_backend_arguments(parser)
    parser.add_argument("--assertion", action="store_true",
                        help="measure subgoal assertion instead (Table 6.1): random situations of the binding's "
                             "[evaluation] assertion generator, plain vs with assertion + refinement")
    parser.add_argument("--classifier", type=_names, default=(), metavar="SCENARIO[,SCENARIO...]",
                        help="measure the success classifiers instead (Table 4.4): the classifier of each experience "
                             "scenario's action (comma-separated scenarios, as `tailor domains` lists them) on "
                             "--episodes fresh episodes of it: correct, false success (predicted success but failed, "
                             "of all episodes) and the share an 'always success' prediction gets right")
    parser.add_argument("--plot", metavar="FILE.png",
                        help="with --assertion: draw three instances with their asserted subgoals (Fig. 6.6), and "
                             "as FILE_search_space.png the search space of one asserted subgoal (Fig. 6.5); "
                             "with --meta: the meta model's tree and regions (Fig. 5.16); with --pareto: measured "
                             "mean time against mean energy per weight, the front marked")
    parser.add_argument("--closed-loop", action="store_true",
                        help="execute each situation's refined plan open and closed loop (monitored, re-refined, "
                             "replanned; Ch. 8.1) with the same simulator seed: failed runs, time, recovered share, "
                             "overhead")
    parser.add_argument("--learning-curve", action="store_true",
                        help="execute --episodes tasks in turn, closed loop, the models learning in operation "
                             "(optionally on --variant); the models' error and refined vs greedy time per task")
    parser.add_argument("--reference-episodes", type=whole_number(0, MAX_EPISODES), default=0, metavar="N",
                        help="with --learning-curve: also train models from scratch on N episodes of the variant "
                             "per experience scenario and compare their error (default 0: not)")
    parser.add_argument("--heldout-tasks", type=whole_number(0, MAX_EPISODES), default=50, metavar="N",
                        help="with --reference-episodes: also compare refined vs greedy on N fresh tasks after the "
                             "stream, every model frozen (default 50; 0: not)")
    parser.add_argument("--disturb", metavar="NAME", default=None,
                        help="with --closed-loop: a seeded disturbance of the simulated world in every run "
                             "(see `tailor domains`)")
    parser.add_argument("--variant", metavar="NAME", default=None,
                        help="with --learning-curve: the changed robot the tasks run on (see `tailor domains`)")
    parser.add_argument("--meta", action="store_true",
                        help="learn the meta action model (Sec. 5.5.4) from --episodes situations and measure "
                             "refinement unfiltered vs filtered by it on --fresh-episodes others (Tables 5.4-5.6)")
    parser.add_argument("--fresh-episodes", type=whole_number(1, MAX_EPISODES), default=None, metavar="M",
                        help="with --meta: fresh situations it is measured on (default: as many as --episodes)")
    parser.add_argument("--worse-cost", type=positive_number, default=None, metavar="C",
                        help="with --meta: weight of a worse episode in the tree (its cost matrix; default: chosen "
                             "by cross-validation among 1, 2, 3, 5)")
    parser.add_argument("--out", metavar="DIR", default=None,
                        help="with --meta: write DIR/models/meta.json (default: beside --models / $TAILOR_MODELS, "
                             "or the user data folder with copies of the bundled models)")
    add_filter_arguments(parser)
    add_risk_argument(parser)
    add_neighbourhood_argument(parser)
    parser.add_argument("--optimizer", choices=sorted(OPTIMIZERS), default=DEFAULT_OPTIMIZER,
                        help="the optimizer of the refined runs (the GA also runs on the same windows where it did "
                             f"not, for comparison; default: {DEFAULT_OPTIMIZER}, as `tailor refine`)")
    parser.add_argument("--risk-sweep", type=_lambdas, default=(), metavar="LIST",
                        help="also refine every situation with each of these risk lambdas (comma-separated, e.g. "
                             "0,0.5,1,2) and report them side by side on the same situations, greedy runs and oracle")
    parser.add_argument("--pareto", type=energy_weights, default=None, metavar="W1,W2,...",
                        help="the time-energy front instead (Ch. 8.1): refine every situation for duration + W*energy "
                             "with each energy weight W (comma-separated, e.g. 0,0.1,0.3,1; 0, the duration alone, is "
                             "always run), execute each and report measured mean time, energy and error per weight "
                             "against greedy and W=0 (Wilcoxon p of energy); --plot FILE.png draws time against "
                             "energy with the front marked")
    add_limit_argument(parser, "with --pareto: also refine for the duration keeping every action's predicted MEASURE "
                             "at most BOUND (e.g. error=0.05), and report the share of runs ending within it with "
                             "and without (repeatable, one bound per measure)")


def _lambdas(text: str) -> tuple[float, ...]:
    parts = [part.strip() for part in text.split(",")]
    if not any(parts) or not all(parts):  # (an empty item is a typing mistake, as in --n-i)
        raise argparse.ArgumentTypeError(f"expected comma-separated risk lambdas, e.g. 0,0.5,1, not {text!r}")
    return tuple(dict.fromkeys(risk_lambda(part) for part in parts))


def _names(text: str) -> tuple[str, ...]:
    """Comma-separated names (argparse type of --classifier), each once, in order."""
    parts = [part.strip() for part in text.split(",")]
    if not all(parts):
        raise argparse.ArgumentTypeError(f"expected comma-separated scenario names, not {text!r}")
    return tuple(dict.fromkeys(parts))


def positive_number(text: str) -> float:
    """A finite number above 0 (argparse type)."""
    import math

    value = number(text)
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"must be a positive number, not {text}")
    return value


def _fmt(value, pattern="{:.2f}") -> str:
    return "-" if value is None else pattern.format(value)


def _pct(value) -> str:
    """A share as a percentage, "12.3%"; "-" where there is none (no "-%")."""
    return "-" if value is None else _fmt(100 * value, "{:.1f}") + "%"


def _print_text(report: dict) -> None:
    out = sys.stdout.write
    s = report
    out(f"Domain {report['domain']}: greedy vs refined over {s['scenarios']} random '{report['comparison']}' "
        f"situations (seed {report['seed']}; problems {', '.join(s['problems'])}); {s['episodes']} where greedy "
        f"and refined both succeeded (failed: greedy {s['failed_greedy']}, refined {s['failed_refined']})\n")
    if s.get("filter_decisions"):
        f = s["filter_decisions"]
        out(f"  meta filter (Sec. 5.5.4)     refined {f['refined']}, greedy kept {f['kept_greedy']} "
            f"(not judged, refined: {f['not_judged']})\n")
    out(f"  failure rate greedy / refined {_pct(s['failure_rate_greedy'])} / {_pct(s['failure_rate_refined'])}\n")
    out(f"  penalized mean, all scenarios {_fmt(s['penalized_greedy_mean'])} s / {_fmt(s['penalized_refined_mean'])} s "
        f"(a failure counts its time + {s['failure_penalty_s']:.0f} s; improvement {_pct(s['penalized_improvement'])})\n")
    out(f"  mean duration greedy (h=1)   {_fmt(s['greedy_mean'])} s\n")
    risk = f", risk {report['risk']:g}" if report.get("risk") else ""
    out(f"  mean duration refined (h=2{risk})  {_fmt(s['refined_mean'])} s\n")
    out(f"  mean improvement (Eq. 5.3)   {_pct(s['improvement'])}   (predicted {_pct(s['predicted_improvement'])})\n")
    out(f"  paired t-test p-value        {_fmt(s['p_value'], '{:.2g}')}\n")
    out(f"  better / equal / worse       {s['better']} / {s['equal']} / {s['worse']}   "
        f"(mean improvement {_pct(s['improvement_better'])} / {_pct(s['improvement_equal'])} / "
        f"{_pct(s['improvement_worse'])})\n")
    if "zero_mean" in s:
        out(f"  free parameters all zero     {_fmt(s['zero_mean'])} s over {s['zero_episodes']} (failed "
            f"{s['failed_zero']}); refined is {_pct(s['improvement_over_zero'])} faster, "
            f"p {_fmt(s['p_value_zero'], '{:.2g}')}\n")
    out(f"  refined / simulated optimum  {_fmt(s['oracle_ratio'], '{:.3f}')} over {s['oracle_episodes']} episodes "
        f"(greedy / optimum {_fmt(s['greedy_oracle_ratio'], '{:.3f}')}; {', '.join(s['oracle_methods']) or '-'})\n")
    if s.get("stronger_baseline") == "zero":
        out(f"  over the stronger baseline   zero ({_fmt(s['stronger_baseline_mean'])} s, faster than greedy): refined "
            f"is {_pct(s['improvement_over_stronger_baseline'])} faster over the "
            f"{s['stronger_baseline_episodes']} situations where all three succeeded\n")
    optimizer = report.get("optimizer", "auto")
    out(f"  optimizer per sequence       {optimizer} {_fmt(s['analytic_ms_median'])} ms, ga alone "
        f"{_fmt(s['ga_ms_median'])} ms (medians); their predicted totals agree within 1% in "
        f"{_pct(s['analytic_ga_agree'])}\n")
    for method, row in (s.get("optimizers") or {}).items():
        gaps = (f"; certified gap median {100 * row['gap_share_median']:.3f}%, max {100 * row['gap_share_max']:.3f}% "
                f"over {row['certified_windows']} windows" if row["certified_windows"] else "")
        out(f"  windows by {method:<17} {_pct(row['share'])} ({row['windows']}), median {_fmt(row['median_ms'])} ms"
            f"{gaps}\n")
        if "vs_ga" in row:
            v = row["vs_ga"]
            out(f"    against the GA, same windows: predicted {_fmt(v['cost_mean'], '{:.4f}')} s vs "
                f"{_fmt(v['ga_cost_mean'], '{:.4f}')} s on average; above the GA's by at most "
                f"{_fmt(100 * v['above_ga_max'], '{:.3f}')}% ({v['above_ga_by_more_than_0.1%']} windows by more than "
                f"0.1%), below it on {v['below_ga']}; the GA's median {_fmt(v['ga_median_ms'])} ms\n")
    if s.get("window_ms_median") is not None:
        out(f"  optimizer per window (h=2)   median {_fmt(s['window_ms_median'])} ms; all windows of a sequence take "
            f"{_pct(s['optimizer_share'])} of its execution time on average, execution waits for "
            f"{_pct(s.get('optimizer_wait_share'))} (each window refined while the action before it executes)\n")
    if s.get("per_action"):
        out("\nPer action (Table 5.2), mean duration (s) over the situations where both succeeded (how many):\n")
        _print_per_action(out, s["per_action"])
    sweep = report.get("risk_sweep")
    if sweep:
        out(f"\nRisk-aware refinement (h=2, {report.get('optimizer', 'auto')}) on the same situations: objective = "
            "predicted duration + "
            "lambda * uncertainty\n")
        out("  lambda  failed greedy/refined  improvement  penalized  better/equal/worse  worse  refined/optimum\n")
        for row in sweep:
            out(f"  {row['risk']:<6g}  {_pct(row['failure_rate_greedy']):>6} / {_pct(row['failure_rate_refined']):>5}"
                f"  {_pct(row['improvement']):>10}  {_pct(row['penalized_improvement']):>8}"
                f"  {row['better']:>6}/{row['equal']}/{row['worse']:<5}  {_pct(row['worse_share']):>5}"
                f"  {_fmt(row['oracle_ratio'], '{:.3f}'):>8} ({row['oracle_episodes']})\n")
    w = report.get("horizons")
    if w:
        out(f"\nHorizons (Table 5.3) over random '{report['horizon_situations']}' situations, {w['episodes']} "
            "where every horizon succeeded:\n")
        out("  horizon  mean (s)  improvement vs h=1  vs h-1   p (vs h-1)  optimizer\n")
        for row in w["horizons"]:
            out(f"  h={row['horizon']:<6} {_fmt(row['mean']):>8}  {_pct(row['improvement']):>17}"
                f"  {_pct(row['improvement_over_previous']):>6}  {_fmt(row['p_value_vs_previous'], '{:.2g}'):>10}"
                f"  {','.join(row['methods'])}"
                + (f"  ({row['shorter']} of {w['scenarios']} situations have fewer actions: h={row['horizon']} acts "
                   "as their length there)" if row.get("shorter") else "") + "\n")
        if w.get("per_action"):
            out(f"\nPer action of the horizon sequence (Table 5.2(b)), mean duration (s) over the {w['episodes']} "
                "situations above (how many had each sequence):\n")
            _print_per_action(out, w["per_action"])


def _print_per_action(out, rows: list[dict]) -> None:
    """Table 5.2: one line per action of each executed sequence, greedy (h=1) and refined (h=2) means."""
    out("  problem          step  action              greedy (h=1)  refined (h=2)\n")
    for row in rows:
        label = f"{row['problem']} ({row['situations']})"
        out(f"  {label:<16} {row['step']:>4}  {row['action']:<18} {_fmt(row['greedy_mean']):>13}"
            f"  {_fmt(row['refined_mean']):>13}\n")


def run(args: argparse.Namespace) -> int:
    with backend_session(args):  # the workers of --backend run every episode below
        return _evaluate(args)


def _evaluate(args: argparse.Namespace) -> int:
    from tailor.planner_bridge import resolve_domain_dir
    from tailor.refinement.binding import load_domain_binding
    from tailor.refinement.evaluation.experiments import (
        comparison_episode,
        distinct_horizons,
        horizon_episode,
        horizon_rows,
        situation_rows,
        situation_seed,
        summarize_comparison,
        summarize_horizons,
        summarize_risk_sweep,
    )
    from tailor.refinement.model_store import resolve_models
    from tailor.sims.parallel import run_in_workers
    from tailor.refinement.situations import draw_situations, job_models, situation_sequence

    domain_dir = resolve_domain_dir(args.domain)
    binding = load_domain_binding(domain_dir)
    source = resolve_models(domain_dir, args.models)
    from tailor.errors import UsageError

    if args.pareto is None and args.limits:
        raise UsageError("--max belongs to --pareto")
    if args.classifier:  # (draws no situations: needs no [evaluation])
        others = [flag for flag, given in (("--assertion", args.assertion), ("--meta", args.meta),
                                           ("--pareto", args.pareto is not None), ("--closed-loop", args.closed_loop),
                                           ("--learning-curve", args.learning_curve)) if given]
        if others:
            raise UsageError(f"--classifier and {others[0]} are two experiments: give one")
        if args.plot or args.situations is not None:
            raise UsageError(f"{'--plot' if args.plot else '--situations'} does not apply to --classifier (it "
                             "gathers episodes of experience scenarios, it draws no situations)")
        from tailor.cli.evaluate_assertion import run_classifier

        return run_classifier(args, domain_dir, binding, source.path)
    plan = binding.require_evaluation()
    if args.situations is not None:  # (checked before any experiment: a bad name is one line, whichever runs)
        known = binding.entry.situations
        if args.situations not in known:
            raise UsageError(f"--situations {args.situations!r} is not a situation generator of simulator "
                             f"{binding.simulator!r} (known: {', '.join(known) or 'none'})")
    if args.pareto is not None and (args.meta or args.assertion):
        raise UsageError(f"--pareto and {'--meta' if args.meta else '--assertion'} are two experiments: give one")
    if args.meta:
        if args.assertion:
            raise UsageError("--meta and --assertion are two experiments: give one")
        if args.episodes < 20:
            raise UsageError(f"--meta needs at least 20 --episodes to learn from, not {args.episodes}")
        from tailor.cli.evaluate_meta import run_meta

        return run_meta(args, domain_dir, binding, plan, source)
    if args.fresh_episodes is not None or args.out is not None or args.worse_cost is not None:
        raise UsageError("--fresh-episodes, --worse-cost and --out belong to --meta")
    if args.assertion or (args.plot and not args.learning_curve and args.pareto is None):
        from tailor.cli.evaluate_assertion import run_assertion

        if args.situations is not None:
            from dataclasses import replace

            plan = replace(plan, assertion=args.situations)
        return run_assertion(args, domain_dir, binding, plan, source.path)
    if args.situations is not None:
        from dataclasses import replace

        plan = replace(plan, comparison=args.situations, horizons=args.situations)
    planned: dict = {}  # each problem the situations need, planned once

    def situations(generator: str, count: int, start: int = 0) -> list:
        seeds = [(index, situation_seed(args.seed, index)) for index in range(start, start + count)]
        return draw_situations(domain_dir, binding, generator, seeds, args.seed, planned, source.path)

    items = situations(plan.comparison, args.episodes)
    if args.pareto is not None:
        from tailor.cli.evaluate_pareto import run_pareto

        return run_pareto(args, domain_dir, binding, plan, source, items)
    if args.closed_loop or args.learning_curve:
        from tailor.cli.evaluate_closed_loop import run_closed_loop, run_learning_curve

        if args.closed_loop and args.learning_curve:
            raise UsageError("--closed-loop and --learning-curve are two experiments: give one")
        if args.closed_loop:
            return run_closed_loop(args, domain_dir, binding, plan, source.path, items)
        return run_learning_curve(args, domain_dir, binding, plan, source.path, items,
                                  fresh=lambda count: situations(plan.comparison, count, args.episodes))
    if args.disturb is not None or args.variant is not None:
        raise UsageError("--disturb belongs to --closed-loop, --variant to --learning-curve")
    use_filter = binding.refinement.filter if args.filter is None else args.filter
    if use_filter:  # a missing or bad meta model fails before any work
        from tailor.refinement.models.meta_model import load_meta_model

        load_meta_model(source.path)
    models = None
    if items:  # the models are loaded here once, so a missing or bad model file fails before any work
        job, _, objects = items[0]
        models = job_models(job, situation_sequence(job, objects)).values()
    announce_models("evaluate", source)
    risk = 0.0 if args.risk is None else args.risk
    if models is not None:  # the risk lambda (the default only where every model stores its uncertainty)
        from tailor.refinement.refine import resolve_risk

        risk = resolve_risk(args.risk, models)
        if any(args.risk_sweep):
            resolve_risk(max(args.risk_sweep), models)
    neighbourhood = binding.refinement.neighbourhood if args.neighbourhood is None else args.neighbourhood
    rows = run_in_workers(comparison_episode, [(job, i, objects, i < args.oracle_episodes, binding.refinement.zero_baseline,
                                                use_filter, risk, args.risk_sweep, neighbourhood, args.optimizer)
                                               for job, i, objects in items], args.jobs, "greedy vs refined",
                          getattr(args, "progress", True))
    report = {"domain": binding.domain or domain_dir.name, "simulator": binding.simulator, "seed": args.seed,
              "models": str(source.path), "comparison": plan.comparison, "filter": use_filter, "risk": risk,
              "neighbourhood": neighbourhood, "optimizer": args.optimizer}
    report.update(summarize_comparison(rows))
    if args.risk_sweep:
        report["risk_sweep"] = summarize_risk_sweep(rows)
    report["situations"] = situation_rows(rows, {i: objects for _, i, objects in items})
    horizon_episodes = (min(HORIZON_EPISODES, args.episodes) if args.horizon_episodes is None
                        else args.horizon_episodes)
    if plan.horizons and horizon_episodes:
        items = situations(plan.horizons, horizon_episodes)
        hrows = run_in_workers(horizon_episode, [(job, i, objects, HORIZONS) for job, i, objects in items],
                              args.jobs, "horizons 1..4", getattr(args, "progress", True))
        shown = distinct_horizons(hrows, HORIZONS)  # h=3, 4 of two-action sequences are h=2: not listed
        report["horizon_situations"] = plan.horizons
        report["horizons"] = summarize_horizons(hrows, shown)
        report["horizons"]["situations"] = horizon_rows(hrows, {i: objects for _, i, objects in items}, shown)
    if args.json:
        from tailor.outputs import json_text, model_files, provenance, versioned

        origin = provenance(getattr(args, "argv", None), {"seed": args.seed}, model_files(source.path))
        sys.stdout.write(json_text(versioned("evaluate", report, origin)) + "\n")
    else:
        _print_text(report)
    return 0
