"""`tailor evaluate DOMAIN --assertion`: subgoal assertion measured in the simulator (Sec. 6.3, Table 6.1); and
`--classifier SCENARIO,...`: the success classifier on fresh episodes of experience scenarios (Table 4.4)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from tailor.errors import ArgumentValueError, BindingError

PLOT_INSTANCES = 3


def _pct(value) -> str:
    return "-" if value is None else f"{100 * value:.1f}%"


def _print_text(report: dict) -> None:
    out = sys.stdout.write
    s = report
    out(f"Domain {s['domain']}: subgoal assertion over {s['episodes']} random '{s['generator']}' situations "
        f"(seed {s['seed']}), each executed plain and with assertion + refinement (h=2"
        + (f", risk {s['risk']:g}, neighbourhood {s['neighbourhood']:g}" if "risk" in s else "")
        + "), same simulator seed\n")
    out(f"  success without assertion     {_pct(s['success_without'])}   (failures: "
        f"{', '.join(f'{k} {v}' for k, v in s['failures_without'].items()) or 'none'})\n")
    out(f"  success with assertion        {_pct(s['success_with'])}   (failures: "
        f"{', '.join(f'{k} {v}' for k, v in s['failures_with'].items()) or 'none'})\n")
    counted = "collisions" if s.get("collision_outcome", "collision") == "collision" else "failures"
    out(f"  {counted + ' avoided':<30}{_pct(s['collisions_avoided'])} of {s['collisions']} "
        f"({_pct(s['collisions_avoided_and_succeeded'])} avoided and succeeded)\n")
    out(f"  subgoal asserted              {_pct(s['asserted'])} of the situations\n")
    if s.get("failure_probability_sources"):
        out(f"  failure predicted             {_pct(s['predicted_fail'])} of the situations; left plain in "
            f"{_pct(s['weighed_out'])} of the situations, the detour predicted to cost more than failing (failure "
            f"probability x a second attempt through the subgoal); plain failed there {s['weighed_out_failed']} "
            "times\n")
        ms = s.get("assertion_ms_median")
        out(f"    failure probability from {'; '.join(s['failure_probability_sources'])}; predicted detour median "
            f"{'-' if s['detour_predicted_median'] is None else format(s['detour_predicted_median'], '+.2f')} s; "
            f"weighing {'-' if ms is None else f'{ms:.0f}'} ms per situation (median)\n")
    out(f"  needless assertions           {_pct(s['needless_assertions'])} of the situations "
        f"(plain would have succeeded), slower there by {_pct(s['needless_cost'])} on average "
        f"(median {_pct(s['needless_cost_median'])})\n")
    legs = ", ".join(f"{k} {v}" for k, v in s["failed_legs_with"].items()) or "none"
    out(f"  failures with assertion where plain succeeded: {s['new_failures']} (failed action: {legs})\n")
    ms = s["optimizer_ms_median"]
    out(f"  optimizer                     {', '.join(s['optimizers']) or '-'}; median "
        f"{'-' if ms is None else f'{ms:.0f}'} ms per asserted situation\n")
    for key, title in (("table_before", "before assertion (plain)"), ("table_after", "after assertion")):
        _print_matrix(f"Table 6.1, {title}: predicted x observed (share of all situations)", s[key])
    if s.get("plot"):
        out(f"\nWrote {s['plot']}\n")
    if s.get("plot_search_space"):
        out(f"Wrote {s['plot_search_space']} (Fig. 6.5, situation {s['plot_search_space_situation']})\n")


def _print_matrix(title: str, t: dict) -> None:
    """Table 4.4 or 6.1: shares by predicted (rows) and observed (columns) outcome, with totals."""
    out = sys.stdout.write
    out(f"\n  {title}\n")
    out("                       observed fail   observed success   total\n")
    for p in ("fail", "success"):
        f, ok = t[f"predicted_{p}_observed_fail"], t[f"predicted_{p}_observed_success"]
        out(f"    predicted {p:<8} {_pct(f):>14} {_pct(ok):>18} {_pct(f + ok):>7}\n")
    f = t["predicted_fail_observed_fail"] + t["predicted_success_observed_fail"]
    out(f"    total              {_pct(f):>14} {_pct(1 - f):>18}\n")


def _print_classifier(report: dict) -> None:
    out = sys.stdout.write
    out(f"Domain {report['domain']}: success classifiers on fresh episodes of experience scenarios (Table 4.4; "
        f"seed {report['seed']}); false success: predicted success but failed, a share of all episodes\n")
    out("  scenario              classifier                 episodes  failed  correct  false success  "
        "always success\n")
    rows = report["scenarios"]
    for r in rows:
        out(f"  {r['scenario']:<21} {r['classifier']:<26} {r['episodes']:>8}  {_pct(r['failed']):>6}  "
            f"{_pct(r['correct']):>7}  {_pct(r['false_success']):>13}  {_pct(r['always_success']):>14}\n")
    for r in rows:
        _print_matrix(f"Table 4.4, {r['scenario']} ({r['classifier']}; correct {_pct(r['correct'])}): predicted x "
                      "observed (share of all episodes)", r["table"])


def run_classifier(args: argparse.Namespace, domain_dir, binding, models_dir) -> int:
    """Table 4.4 per scenario of --classifier: the success classifier of the scenario's action (its file
    ACTION.collision.json in the model folder) on --episodes fresh episodes, gathered with the seed stream
    classifier_seed(--seed)."""
    from tailor.refinement.evaluation.assertion_experiment import classifier_seed, classifier_table
    from tailor.refinement.models.action_models import COLLISION_SUFFIX, load_success_models
    from tailor.sims.experience import gather, scenario

    if args.episodes < 1:
        raise ArgumentValueError("--classifier needs at least 1 --episodes")
    actions = {name: scenario(binding.simulator, name).action for name in args.classifier}  # unknown: one line
    models = load_success_models(models_dir, set(actions.values()))  # a missing classifier fails before any work
    seed = classifier_seed(args.seed)
    rows = []
    for name, action in actions.items():
        episodes = gather(binding.simulator, name, args.episodes, seed=seed, jobs=args.jobs,
                          progress=getattr(args, "progress", True))
        rows.append({"scenario": name, "action": action, "classifier": f"{action}{COLLISION_SUFFIX}",
                     **classifier_table(models[action], episodes)})
    report = {"domain": binding.domain or domain_dir.name, "simulator": binding.simulator, "seed": args.seed,
              "episode_seed": seed, "scenarios": rows}
    if args.json:
        from tailor.outputs import json_text, provenance, versioned

        files = [Path(models_dir) / f"{action}{COLLISION_SUFFIX}" for action in sorted(models)]
        origin = provenance(getattr(args, "argv", None), {"seed": args.seed}, files)
        sys.stdout.write(json_text(versioned("evaluate_classifier", report, origin)) + "\n")
    else:
        _print_classifier(report)
    return 0


def _draw_search_space(plot, kept: list[dict], entry) -> dict:
    """Fig. 6.5 beside Fig. 6.6 (FILE_search_space.png) for the first drawn situation with an asserted subgoal:
    the report's keys naming the file and the situation (none where no drawn situation has one)."""
    from tailor.refinement.evaluation.assertion_plots import draw_search_space, search_space, search_space_name

    for row in kept:
        space = row["inserted"] and search_space(row["asserted_sequence"], row["sequence"], row["models"],
                                                 row["success_models"], entry)
        if space:
            path = draw_search_space(search_space_name(plot), space,
                                     f"Search space of subgoal refinement in subgoal assertion (situation "
                                     f"{row['index']}; {', '.join(space.axes)} varied, the other free parameters "
                                     "at their refined values)", entry)
            return {"plot_search_space": str(path), "plot_search_space_situation": row["index"]}
    return {}


def run_assertion(args: argparse.Namespace, domain_dir, binding, plan, models_dir) -> int:
    from tailor.refinement.evaluation.assertion_experiment import (
        AssertionSetup,
        assertion_episode,
        assertion_seed,
        pick_instances,
        summarize_assertion,
    )
    from tailor.refinement.models.action_models import load_success_models
    from tailor.sims.parallel import run_in_workers
    from tailor.refinement.situations import draw_situations, job_models, situation_sequence

    if args.plot:
        from tailor.outputs import check_output_file

        if not args.assertion:
            raise ArgumentValueError("--plot draws the instances of --assertion (Fig. 6.6) or the meta model of "
                                     "--meta (Fig. 5.16): give one of them")
        check_output_file(args.plot, ".png")
        from tailor.refinement.evaluation.assertion_plots import search_space_name

        check_output_file(search_space_name(args.plot), ".png")
    if plan.assertion is None:
        raise BindingError("[evaluation] names no assertion situations (add assertion = \"<situation generator>\")",
                           file=binding.file)
    names = {a.success_model for a in binding.actions.values() if a.success_model}
    if not names:
        raise BindingError("--assertion: no action of the binding names a success_model to assert subgoals with",
                           file=binding.file)
    setup = AssertionSetup(load_success_models(models_dir, names), risk=getattr(args, "risk", None),
                           neighbourhood=getattr(args, "neighbourhood", None))
    seeds = [(index, assertion_seed(args.seed, index)) for index in range(args.episodes)]
    items = draw_situations(domain_dir, binding, plan.assertion, seeds, args.seed, {}, models_dir)
    refining = {}
    if items:  # models loaded once up front: a missing or bad model file fails before any work
        from tailor.refinement.pipeline import Options, resolve_options

        job, _, objects = items[0]
        resolved = resolve_options(Options(risk=setup.risk, neighbourhood=setup.neighbourhood), binding,
                                   job_models(job, situation_sequence(job, objects)))
        refining = {"risk": resolved.risk, "neighbourhood": resolved.neighbourhood}
    rows = run_in_workers(assertion_episode, [(job, i, objects, setup) for job, i, objects in items], args.jobs,
                          "plain vs asserted")
    report = {"domain": binding.domain or domain_dir.name, "simulator": binding.simulator, "seed": args.seed,
              "generator": plan.assertion, **refining, "weighs_detour": setup.weigh}
    report.update(summarize_assertion(rows))
    if args.plot:
        from tailor.refinement.evaluation.assertion_plots import draw_instances

        chosen = pick_instances(rows, PLOT_INSTANCES)
        by_index = {i: (job, objects) for job, i, objects in items}
        kept = [assertion_episode(by_index[r["index"]][0], r["index"], by_index[r["index"]][1], setup, keep=True)
                for r in chosen]
        draw_instances(args.plot, kept, binding.entry.views)
        report["plot"] = str(args.plot)
        report["plot_situations"] = [r["index"] for r in chosen]
        report.update(_draw_search_space(args.plot, kept, binding.entry))
    if args.json:
        from tailor.outputs import json_text, model_files, provenance, versioned

        origin = provenance(getattr(args, "argv", None), {"seed": args.seed}, model_files(models_dir))
        sys.stdout.write(json_text(versioned("evaluate_assertion", report, origin)) + "\n")
    else:
        _print_text(report)
    return 0
