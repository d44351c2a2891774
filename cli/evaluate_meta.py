"""`tailor evaluate DOMAIN --meta`: learn the meta action model from evaluated episodes and measure the filter
it gives on fresh ones (Sec. 5.5.4, Tables 5.4-5.6, Fig. 5.16)."""

from __future__ import annotations

import argparse
import filecmp
import logging
import shutil
import sys
from pathlib import Path

from tailor.errors import OutputFileError

META_HORIZON = 2  # the refinement the meta model judges against greedy (h = 1), as in Table 5.4


def _pct(value) -> str:
    return "-" if value is None else f"{100 * value:.1f}%"


def _table(out, title: str, unfiltered: dict, filtered: dict) -> None:
    out(f"\n{title}\n")
    out(f"  {'':<34}{'unfiltered (Table 5.4)':>24}{'filtered (Table 5.6)':>24}\n")
    rows = [("situations refined", lambda t: f"{t['refined']} of {t['scenarios']}"),
            ("episodes (both succeeded)", lambda t: str(t["episodes"])),
            ("mean duration (greedy " + (f"{unfiltered['greedy_mean']:.2f} s)" if unfiltered["greedy_mean"] else "-)"),
             lambda t: "-" if t["mean"] is None else f"{t['mean']:.2f} s"),
            ("mean improvement (Eq. 5.3)", lambda t: _pct(t["improvement"])),
            ("paired t-test p vs greedy", lambda t: "-" if t["p_value"] is None else f"{t['p_value']:.2g}")]
    for c in ("better", "equal", "worse"):
        rows.append((f"{c}: episodes (share)", lambda t, c=c: f"{t[c]} ({_pct(t[c + '_share'])})"))
        rows.append((f"{c}: mean improvement", lambda t, c=c: _pct(t["improvement_" + c])))
    rows.append(("failed executions", lambda t: str(t["failed"])))
    for label, cell in rows:
        out(f"  {label:<34}{cell(unfiltered):>24}{cell(filtered):>24}\n")


def _confusion(out, title: str, c: dict) -> None:
    out(f"\n{title} ({c['episodes']} episodes; shares of all, rows actual, columns predicted)\n")
    out(f"  {'actual / predicted':<20}" + "".join(f"{k:>10}" for k in c["classes"]) + f"{'total':>10}\n")
    for k, row in zip(c["classes"], c["shares"]):
        out(f"  {k:<20}" + "".join(f"{_pct(v):>10}" for v in row)
            + f"{_pct(c['actual_totals'][c['classes'].index(k)]):>10}\n")
    out(f"  {'total':<20}" + "".join(f"{_pct(v):>10}" for v in c["predicted_totals"])
        + f"{_pct(c['correct']):>10} correct\n")


def _print_text(report: dict) -> None:
    out = sys.stdout.write
    t, f = report["training"], report["fresh"]
    out(f"Domain {report['domain']}: meta action model of refinement (h={report['horizon']}) vs greedy over random "
        f"'{report['generator']}' situations (seed {report['seed']}): learned from situations "
        f"{t['situations'][0]}-{t['situations'][1] - 1}, measured on fresh situations "
        f"{f['situations'][0]}-{f['situations'][1] - 1}\n")
    out(f"  labels: better / equal / worse beyond +-{100 * report['equal_band']:.0f}% of the greedy time; training "
        f"episodes {t['labels']['better']} / {t['labels']['equal']} / {t['labels']['worse']}\n")
    out(f"  tree: {t['leaves']} {'leaf' if t['leaves'] == 1 else 'leaves'}, cost of a worse episode {t['cost']:g}, at least {t['min_samples_leaf']} "
        f"episodes a leaf (chosen by {t['cv_folds']}-fold cross-validation)\n")
    out("  cross-validated on the training situations (filtered: refine where \"better\" is predicted):\n")
    out(f"    {'cost':>5} {'leaf':>5} {'improvement':>12} {'worse':>7} {'refined':>8} {'accuracy':>9}"
        f"   (unfiltered: improvement {_pct(t['unfiltered_improvement'])})\n")
    for c in t["candidates"]:
        mark = "  <- chosen" if (c["cost"], c["min_samples_leaf"]) == (t["cost"], t["min_samples_leaf"]) else ""
        out(f"    {c['cost']:>5g} {c['min_samples_leaf']:>5} {_pct(c['improvement']):>12} {_pct(c['worse_share']):>7}"
            f" {_pct(c['refined_share']):>8} {_pct(c['accuracy']):>9}{mark}\n")
    _table(out, f"Fresh situations, {f['episodes']} ({f['not_judged']} not judged: another first window):",
           f["unfiltered"], f["filtered"])
    floor = f["floor"]
    out(f"\n  worse share {_pct(f['unfiltered']['worse_share'])} -> {_pct(f['filtered']['worse_share'])} "
        f"(drop {_pct(floor['worse_share_drop'])}; floor two thirds: {'met' if floor['worse_drop_met'] else 'MISSED'}); "
        f"mean improvement {'kept' if floor['improvement_kept'] else 'DROPPED'}\n")
    _confusion(out, "Table 5.5, fresh situations", f["confusion"])
    _confusion(out, "Table 5.5, training situations", t["confusion"])
    out("\nRules (leaf: class (training episodes better/equal/worse)):\n")
    out("".join(f"  {line}\n" for line in report["rules"]))
    for path in report["files"]:
        out(f"Wrote {path}\n")


def _out_folder(args: argparse.Namespace, domain_dir: Path, source) -> Path:
    """The models folder the meta model is written to: `--out DIR`'s models/, else the folder of the action
    models it judges (unless those are the bundled ones: then the user's data folder)."""
    from tailor.refinement.model_store import MODELS, default_training_out

    if args.out is not None:
        return Path(args.out).expanduser() / MODELS
    if source.origin != "domain folder":
        return source.path
    return default_training_out(domain_dir) / MODELS


def _check_companions(target: Path, source: Path) -> list[Path]:
    """The model files to copy beside the meta model (it judges those models); an error if the folder holds
    other models of the same names, which the meta model would then be wrongly used with."""
    from tailor.refinement.models.action_models import META_FILE

    if target.resolve() == source.resolve():
        return []
    copies = []
    for path in sorted(source.glob("*.json")):
        if path.name == META_FILE:
            continue
        there = target / path.name
        if there.exists() and not filecmp.cmp(path, there, shallow=False):
            raise OutputFileError(f"holds another {path.name} than the models evaluated ({source}): the meta model "
                                  "must sit beside the models it judges (give --out elsewhere, or --models this "
                                  "folder)", file=str(target))
        if not there.exists():
            copies.append(path)
    return copies


def run_meta(args: argparse.Namespace, domain_dir: Path, binding, plan, source) -> int:
    from tailor.refinement.evaluation.experiments import situation_seed
    from tailor.refinement.evaluation.meta_episodes import meta_episode
    from tailor.refinement.evaluation.meta_experiment import fresh_report
    from tailor.refinement.learning.meta_learning import CV_FOLDS, learn_meta_model
    from tailor.refinement.models.action_models import write_json_atomic
    from tailor.refinement.models.meta_model import meta_model_path
    from tailor.outputs import check_output_dir, check_output_file, write_atomically
    from tailor.sims.parallel import run_in_workers
    from tailor.refinement.situations import draw_situations, job_models, situation_sequence

    from tailor.cli.arguments import announce_models

    target = _out_folder(args, domain_dir, source)
    check_output_dir(target)  # before any work: an output that cannot be written must not cost the evaluation
    if args.plot:
        check_output_file(args.plot, ".png")
    copies = _check_companions(target, source.path) if target.exists() else [
        p for p in sorted(source.path.glob("*.json")) if p.name != "meta.json"]
    train_n, fresh_n = args.episodes, args.fresh_episodes if args.fresh_episodes is not None else args.episodes
    planned: dict = {}

    def situations(start: int, count: int) -> list:
        seeds = [(index, situation_seed(args.seed, index)) for index in range(start, start + count)]
        return draw_situations(domain_dir, binding, plan.comparison, seeds, args.seed, planned, source.path)

    train_items, fresh_items = situations(0, train_n), situations(train_n, fresh_n)
    risk = 0.0 if args.risk is None else args.risk
    if train_items:  # the models, loaded up front (a bad model file fails before any work), give the risk lambda
        from tailor.refinement.refine import resolve_risk  # of the refinement judged: the one evaluate and refine run

        job, _, objects = train_items[0]
        risk = resolve_risk(args.risk, job_models(job, situation_sequence(job, objects)).values())
    neighbourhood = binding.refinement.neighbourhood if args.neighbourhood is None else args.neighbourhood
    announce_models("evaluate", source)
    progress = getattr(args, "progress", True)
    train_rows = run_in_workers(meta_episode, [(j, i, o, META_HORIZON, risk, neighbourhood)
                                               for j, i, o in train_items], args.jobs, "meta: training episodes",
                                progress)
    fresh_rows = run_in_workers(meta_episode, [(j, i, o, META_HORIZON, risk, neighbourhood)
                                               for j, i, o in fresh_items], args.jobs, "meta: fresh episodes",
                                progress)
    training = learn_meta_model(train_rows, META_HORIZON, seed=args.seed, cost=args.worse_cost)
    fresh = fresh_report(training.model, fresh_rows)
    model = training.model
    report_in_model = {k: v for k, v in training.report.items() if k != "candidates"}
    report_in_model.update(trained_on={"generator": plan.comparison, "seed": args.seed, "situations": [0, train_n]},
                           fresh=fresh)
    from dataclasses import replace

    model = replace(model, report=report_in_model)
    files = []
    path = meta_model_path(target)
    for companion in copies:  # atomically, each: never half a model file
        write_atomically(target / companion.name, lambda tmp, companion=companion: shutil.copyfile(companion, tmp))
    write_json_atomic(path, model.to_json())
    files.append(str(path))
    if copies:
        logging.getLogger(__name__).info("copied the action models it judges beside it: %s",
                                         ", ".join(p.name for p in copies))
    if args.plot:
        from tailor.refinement.evaluation.meta_plots import draw_meta_model

        files.append(str(draw_meta_model(Path(args.plot), training, fresh_rows)))
    report = {"domain": binding.domain or domain_dir.name, "simulator": binding.simulator, "seed": args.seed,
              "models": str(source.path), "generator": plan.comparison, "horizon": META_HORIZON,
              "risk": risk, "neighbourhood": neighbourhood,
              "equal_band": model.equal_band, "features": list(model.feature_names),
              "window": [{"action": a, "feature_set": s} for a, s in model.window],
              "training": {**training.report, "situations": [0, train_n], "cv_folds": CV_FOLDS,
                           "confusion": training.report["training_confusion"]},
              "fresh": {**fresh, "situations": [train_n, train_n + fresh_n]},
              "rules": model.rules_text().splitlines(), "files": files,
              "episodes": {"training": _rows_json(train_rows), "fresh": _rows_json(fresh_rows)}}
    del report["training"]["training_confusion"]
    if args.json:
        from tailor.outputs import json_text, model_files, provenance, versioned
        from tailor.refinement.models.action_models import META_FILE

        read = [p for p in model_files(source.path) if p.name != META_FILE]  # (the meta model: written, not read)
        origin = provenance(getattr(args, "argv", None), {"seed": args.seed}, read)
        sys.stdout.write(json_text(versioned("evaluate_meta", report, origin)) + "\n")
        logging.getLogger(__name__).info("wrote %s", ", ".join(files))
    else:
        _print_text(report)
    return 0


def _rows_json(rows: list[dict]) -> list[dict]:
    """Per episode what a re-analysis needs: the situation, both executions, the features."""
    return [{"index": r["index"], "seed": r["seed"], "problem": r["problem"], "situation": r["situation"],
             "greedy": {"predicted": r["predicted_greedy"], "simulated": r["greedy"], "outcome": r["greedy_outcome"]},
             "refined": {"predicted": r["predicted_refined"], "simulated": r["refined"],
                         "outcome": r["refined_outcome"]},
             "features": r["features"]} for r in rows]
