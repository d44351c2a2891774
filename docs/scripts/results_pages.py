"""docs/results/*.md from the result files committed with each bundled domain (domains/NAME/training/): the
training report `tailor train` wrote (report.json), the `--json` reports of `tailor evaluate` kept there
(evaluate*.json), the other text reports (e.g. meta_evaluation.txt, verbatim) and the pictures. Every number
on these pages comes from those files; nothing is typed by hand.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from mdtext import GENERATED, code, escape, table

ROOT = Path(__file__).resolve().parents[2]
DOMAINS = ROOT / "domains"
SKIPPED_TEXT = {"report.txt"}  # the training report as text: report.json holds the same, report.html shows it


def _num(value, digits: int = 2) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    return f"{value:.{digits}f}"


def _pct(value, digits: int = 1) -> str:
    return "-" if value is None else f"{100 * value:.{digits}f}%"


def _p(value) -> str:
    return "-" if value is None else f"{value:.2g}"


def _seconds(value) -> str:
    if value is None:
        return "-"
    minutes, seconds = divmod(round(value), 60)
    return f"{minutes} min {seconds} s" if minutes else f"{seconds} s"


def _feature_spaces(domain: str) -> dict[str, str]:
    """Each stored model's feature space, as its model file (domains/NAME/models/ACTION.json) says."""
    out = {}
    for path in sorted((DOMAINS / domain / "models").glob("*.json")):
        model = json.loads(path.read_text(encoding="utf-8"))
        if str(model.get("schema", "")).startswith("tailor.action_model/"):
            out[model["action"]] = model.get("feature_space") or model.get("feature_set") or ""
    return out


def training_dirs() -> list[Path]:
    """The bundled domains that carry committed results."""
    return sorted(d for d in DOMAINS.glob("*/training") if (d / "report.json").is_file())


def _training(domain: str, report: dict) -> list[str]:
    spaces = _feature_spaces(domain)
    out = [f"## Action models: `tailor train {domain}`\n",
           f"From `domains/{domain}/training/report.json` (schema `{report.get('schema', '?')}`): the models in "
           f"`domains/{domain}/models/`, learned by `tailor train {domain}` with seed {report['seed']} and "
           f"{report['episodes_per_scenario']} episodes per experience scenario (a model whose recipe names its own "
           f"count learns from that many); gathering took {_seconds(report.get('gather_seconds'))}, training "
           f"{_seconds(report.get('train_seconds'))} (experience already gathered is reused, not simulated again).\n"]
    if report.get("provenance"):
        out += ["Provenance recorded in the report:\n",
                table(["", ""], [[escape(str(k)), code(str(v))] for k, v in report["provenance"].items()], "ll")]
    out += ["### Duration models (Table 4.3)\n",
            "Successful episodes each model learned from, their mean duration, and the mean absolute error on the "
            "held-out quarter (first example of each episode) beside that of gradient boosting "
            "(HistGradientBoostingRegressor) on the same split:\n"]
    out.append(table(["model", "episodes", "mean t (s)", "MAE (s)", "MAE / t", "HGB MAE (s)", "MAE / HGB"],
                     [[escape(action), str(m["episodes"]), _num(m["mean_duration"]), _num(m["mae"], 3),
                       _pct(m["mae_relative"]), _num(m["mae_hgb"], 3), _num(m["mae_over_hgb"])]
                      for action, m in report["models"].items()]))
    out += [f"\nThe stored trees (`domains/{domain}/models/`): the feature space each model learns in, the examples "
            "per episode n_i and the leaf size chosen on a validation quarter, the leaves of the tree trained on all "
            "episodes, and the held-out spread refinement's `--risk` charges (uncertainty, overall):\n",
            table(["model", "features", "n_i", "leaf size", "leaves", "uncertainty (s)"],
                  [[escape(action), code(spaces[action]) if spaces.get(action) else "-", str(m["n_i"]),
                    str(m["min_samples_leaf"]), str(m["leaves"]), _num(m.get("uncertainty_overall"), 3)]
                   for action, m in report["models"].items()], align="llrrrr")]
    failed = [[escape(action), str(m["episodes_gathered"]),
               ", ".join(f"{k} {v}" for k, v in m["outcomes"].items() if k != "success") or "none"]
              for action, m in report["models"].items()]
    out += ["\nEpisodes gathered and how the unsuccessful ones ended (they are left out of the duration models):\n",
            table(["model", "gathered", "not successful"], failed, align="lrl")]
    curves = [[escape(action), str(c["episodes"]), _num(c["mae"], 3), _num(c.get("mae_hgb"), 3), str(c["leaves"])]
              for action, m in report["models"].items() for c in m.get("episodes_curve") or []]
    if curves:
        drawn = " (`mae_vs_episodes.png` below draws it)" if (DOMAINS / domain / "training" / "mae_vs_episodes.png"
                                                              ).is_file() else ""
        out += ["\n### Learning curves\n",
                f"MAE on the same held-out episodes after training on a growing number of the others{drawn}:\n",
                table(["model", "episodes", "MAE (s)", "HGB MAE (s)", "leaves"], curves)]
    for action, c in report.get("classifiers", {}).items():
        out += [f"\n### Success classifier of `{action}` (Sec. 4.2.2, Table 4.4)\n",
                f"A decision tree learned from {c['episodes']} episodes ("
                + ", ".join(f"{k} {v}" for k, v in c["outcomes"].items())
                + f"), a false success costing {_num(c['cost_false_success'], 1)} times a false failure relative to "
                f"the class balance, leaves of at least {c['min_samples_leaf']} episodes: {c['leaves']} leaves. On "
                f"{c['confusion']['episodes']} fresh episodes it was right in {_pct(c['accuracy'])}, and predicted "
                f"success for {_pct(c['false_success'])} of the failing ones. Shares of the fresh episodes:\n"]
        counts, n = c["confusion"]["counts"], c["confusion"]["episodes"]
        cell = {key: counts[key] / n for key in counts}
        out.append(table(["", "observed fail", "observed success", "total"], [
            ["predicted fail", _pct(cell["predicted_fail_observed_fail"]),
             _pct(cell["predicted_fail_observed_success"]), _pct(c["confusion"]["predicted_fail"])],
            ["predicted success", _pct(cell["predicted_success_observed_fail"]),
             _pct(cell["predicted_success_observed_success"]), _pct(1 - c["confusion"]["predicted_fail"])],
            ["total", _pct(c["confusion"]["observed_fail"]), _pct(1 - c["confusion"]["observed_fail"]),
             f"correct {_pct(c['accuracy'])}"]]))
        if c.get("note"):
            out.append("\n" + escape(c["note"]) + "\n")
    if report.get("subgoal_experience"):
        out += ["\n### Subgoal experience (Sec. 8.1)\n",
                "Episodes started at the subgoals refinement chose in random situations (greedy and refined in turn, "
                "in rounds, each with the models of the round before retrained); the duration model of the action "
                "learned from them beside its scenarios' episodes:\n",
                table(["action", "situations", "episodes", "succeeded", "rounds"],
                      [[f"{code(s['action'])} in {code(s['generator'])}", str(s["situations"]), str(s["episodes"]),
                        str(s["succeeded"]), str(s["rounds"])] for s in report["subgoal_experience"]], align="lrrrr")]
    warnings = report.get("warnings") or []
    out += ["\n### Warnings\n",
            "\n".join(f"- {escape(str(w))}" for w in warnings) + "\n" if warnings
            else "`tailor train` raised no warning about this run (too few held-out episodes, a model no better "
                 "than the median duration, a classifier at chance level).\n"]
    return out


def _evaluation(domain: str, name: str, e: dict) -> list[str]:
    horizons = (e.get("horizons") or {}).get("horizons") or []
    command = _command(e, f"tailor evaluate {domain} --situations {e['comparison']} --episodes {e['scenarios']} "
                          f"--oracle-episodes {e.get('oracle_episodes', 0)} --horizon-episodes "
                          f"{(e.get('horizons') or {}).get('scenarios', 0)} --seed {e['seed']} --json")
    out = [f"## Refined against greedy: `{name}`\n",
           f"From `domains/{domain}/training/{name}`, the report of `{command}`. {e['scenarios']} random "
           f"{code(e['comparison'])} situations (problems {', '.join(e['problems'])}), each executed greedily (h = 1) "
           "and refined (h = 2) in the simulator with the same seed; the means are over the situations where both "
           "succeeded.\n"]
    rows = [["situations where greedy and refined both succeeded",
             f"{e['episodes']} of {e['scenarios']} (failed: greedy {e['failed_greedy']}, "
             f"refined {e['failed_refined']})"],
            ["mean duration greedy (h=1) / refined (h=2)", f"{_num(e['greedy_mean'])} s / {_num(e['refined_mean'])} s"],
            ["mean improvement (Eq. 5.3)", f"{_pct(e['improvement'])} (predicted {_pct(e['predicted_improvement'])})"],
            ["paired t-test p", _p(e["p_value"])],
            ["better / equal / worse (1% band)", f"{e['better']} / {e['equal']} / {e['worse']}"]]
    if e.get("oracle_episodes"):
        rows.append([f"refined / simulated optimum ({', '.join(e.get('oracle_methods') or [])})",
                     f"{_num(e['oracle_ratio'], 3)} over {e['oracle_episodes']} situations "
                     f"(greedy / optimum {_num(e['greedy_oracle_ratio'], 3)})"])
    rows.append(["optimizer time per window (median, wall clock on the machine that ran it)",
                 f"{_num(e['window_ms_median'], 0)} ms; all windows {_pct(e['optimizer_share'])} of the execution time"])
    if e.get("optimizer_wait_share") is not None:
        rows.append(["execution waits for the optimizer (each window refined while the action before it executes)",
                     f"{_pct(e['optimizer_wait_share'], 2)} of the execution time"])
    for method, o in sorted((e.get("optimizers") or {}).items()):
        versus = o.get("vs_ga")
        rows.append([f"windows taken by `{method}`",
                     f"{o['windows']} ({_pct(o['share'])}), median {_num(o['median_ms'], 0)} ms"
                     + (f"; against the GA on the same windows: at most {_pct(versus['above_ga_max'], 3)} above it, "
                        f"below it on {versus['below_ga']}" if versus else "")])
    out.append(table(["", "measured"], rows, align="ll"))
    if e.get("per_action"):
        out += ["\nPer action (Table 5.2), mean duration in seconds:\n",
                table(["problem", "step", "action", "greedy (h=1)", "refined (h=2)"],
                      [[code(a["problem"]), str(a["step"]), code(a["action"]), _num(a["greedy_mean"]),
                        _num(a["refined_mean"])] for a in e["per_action"]], align="lrlrr")]
    if horizons:
        out += [f"\nHorizons (Table 5.3) over {e['horizons']['scenarios']} random "
                f"{code(e.get('horizon_situations', e['comparison']))} situations: mean duration, improvement over "
                "h = 1 and over the horizon before, with the p-value of the paired t-test against it:\n",
                table(["horizon", "mean (s)", "vs h=1", "vs h-1", "p (vs h-1)", "failed", "optimizer"],
                      [[f"h={h['horizon']}", _num(h["mean"]), _pct(h["improvement"]),
                        _pct(h["improvement_over_previous"]), _p(h["p_value_vs_previous"]), str(h["failed"]),
                        ", ".join(h.get("methods") or [])] for h in horizons], align="lrrrrrl")]
    return out


def _command(e: dict, fallback: str) -> str:
    """The command line that wrote a report, as its provenance records it (else `fallback`)."""
    argv = (e.get("provenance") or {}).get("argv")
    return " ".join(argv) if argv else fallback


def _closed_loop(domain: str, name: str, e: dict) -> list[str]:
    command = _command(e, f"tailor evaluate {domain} --closed-loop --situations {e['generator']} --episodes "
                          f"{e['situations']}{' --disturb ' + e['disturbance'] if e.get('disturbance') else ''} "
                          f"--seed {e['seed']} --json")
    out = [f"## Closed loop against open loop: `{name}`\n",
           f"From `domains/{domain}/training/{name}`, the report of `{command}`: each random {code(e['generator'])} "
           "situation refined once and executed open loop and closed loop (monitored, re-refined, replanned; "
           "[Executing](../executing.md)) with the same simulator seed"
           f"{', the disturbance ' + code(e['disturbance']) + ' in every run' if e.get('disturbance') else ''}. "
           f"A failed run is charged its time + {_num(e['penalty'], 0)} s.\n"]
    rows = []
    for side in ("open_loop", "closed_loop"):
        s = e[side]
        rows.append([side.replace("_", " "), f"{s['failed_runs']} of {s['runs']}", f"{_num(s['mean_penalized'])} s",
                     str(s["re_refinements"]), str(s["replans"])])
    out.append(table(["", "failed runs", "mean time (failed +penalty)", "re-refinements", "replans"], rows,
                     align="lrrrr"))
    out.append(f"\nRecovered: {_pct(e['recovered_share'])} of the runs open loop fails. Closed minus open: "
               f"{_num(e['closed_minus_open_mean'])} s on average (Wilcoxon signed-rank, one-sided p "
               f"{_p(e['p_closed_faster'])}). Overhead (monitoring, re-refinement, replanning; wall clock on the "
               f"machine that ran it): median {_pct(e['overhead_share'], 2)} of execution time.\n")
    return out


def _learning_curve(domain: str, name: str, e: dict) -> list[str]:
    command = _command(e, f"tailor evaluate {domain} --learning-curve --situations {e['generator']} --episodes "
                          f"{e['tasks']}{' --variant ' + e['variant'] if e.get('variant') else ''}"
                          f"{' --reference-episodes ' + str(e['reference']['episodes']) if e.get('reference') else ''}"
                          f" --seed {e['seed']} --json")
    out = [f"## Learning in operation: `{name}`\n",
           f"From `domains/{domain}/training/{name}`, the report of `{command}`: {e['tasks']} tasks executed closed "
           f"loop in turn{' on the changed robot ' + code(e['variant']) if e.get('variant') else ''}, the duration "
           "models and success classifiers recalibrated on the executed actions every 5 of them. The error is "
           "each action's, predicted before it ran.\n"]
    rows = [["duration MAE, first 20 tasks / last 20", f"{_num(e['mae_first'], 3)} s / {_num(e['mae_last'], 3)} s"],
            ["refined vs greedy, first 20 tasks / last 20",
             f"{_pct(e['improvement_first'])} / {_pct(e['improvement_last'])}"]]
    if e.get("reference"):
        rows.append([f"models trained from scratch on {e['reference']['episodes']} episodes of the changed robot "
                     "per scenario: MAE on the last 20 tasks' actions",
                     f"{_num(e['reference']['mae_last'], 3)} s (learning in operation "
                     f"{_num(e.get('mae_ratio_to_reference'))} x that)"])
        rows.append(["refined vs greedy with those models, last 20 tasks",
                     _pct(e["reference"].get("improvement_last"))])
        held = e["reference"].get("heldout")
        if held:
            rows.append([f"{held['tasks']} held-out tasks after the stream, every model frozen: refined vs greedy "
                         "with the models learned in operation / trained from scratch / as trained",
                         f"{_pct(held['improvement_learned'])} / {_pct(held['improvement_reference'])} / "
                         f"{_pct(held['improvement_trained'])}"])
            rows.append([f"duration MAE over the {held['executions']} actions those runs executed: learned in "
                         "operation / from scratch / as trained",
                         f"{_num(held['mae_learned'], 3)} s ({_num(held['mae_ratio'])} x scratch) / "
                         f"{_num(held['mae_reference'], 3)} s / {_num(held['mae_trained'], 3)} s"])
    out.append(table(["", "measured"], rows, align="ll"))
    return out


def _assertion(domain: str, reports: list[tuple[str, dict]]) -> list[str]:
    """Table 6.1's measures, one column per kept report (the situations each drew), side by side."""
    names = ", ".join(code(name) for name, _ in reports)
    out = [f"## Subgoal assertion (Table 6.1): {names}\n",
           f"From `domains/{domain}/training/`: random situations of each report's generator executed with the plain "
           "action and with assertion and refinement, same simulator seed"
           + ("; a subgoal asserted only where its detour pays" if all(e.get("weighs_detour") for _, e in reports)
              else "") + ". The commands:\n"]
    for name, e in reports:
        command = _command(e, f"tailor evaluate {domain} --assertion --situations {e['generator']} --episodes "
                              f"{e['episodes']} --seed {e['seed']} --json")
        out.append(f"- {code(name)}: `{command}` (risk {_num(e['risk'], 1)}, neighbourhood {_num(e['neighbourhood'])})")
    out.append("")
    rows = [["situations", *(f"{e['episodes']} {code(e['generator'])}" for _, e in reports)],
            ["plain action failed (collisions)", *(f"{_pct(1 - e['success_without'])} ({e['collisions']})"
                                                   for _, e in reports)],
            ["classifier before assertion: correct / false success (Table 6.1)",
             *(f"{_pct(_correct(e['table_before']))} / {_pct(e['table_before']['predicted_success_observed_fail'])}"
               for _, e in reports)],
            ["success without / with assertion", *(f"{_pct(e['success_without'])} / {_pct(e['success_with'])}"
                                                   for _, e in reports)],
            ["subgoal asserted", *(_pct(e["asserted"]) for _, e in reports)],
            ["asserted needlessly (plain would have succeeded)", *(_pct(e["needless_assertions"]) for _, e in reports)],
            ["slow-down where needless, mean / median",
             *(f"{_pct(e['needless_cost'])} / {_pct(e.get('needless_cost_median'))}" for _, e in reports)],
            ["left plain by the weighing (of them failed)",
             *(f"{_pct(e['weighed_out'])} ({e['weighed_out_failed']})" if "weighed_out" in e else "-"
               for _, e in reports)]]
    out.append(table(["", *(code(name) for name, _ in reports)], rows, align="l" + "r" * len(reports)))
    return out


def _correct(table: dict) -> float:
    """The share a confusion table (Table 4.4, 6.1: shares of all episodes) has right."""
    return table["predicted_fail_observed_fail"] + table["predicted_success_observed_success"]


def _classifier(domain: str, name: str, e: dict) -> list[str]:
    command = _command(e, f"tailor evaluate {domain} --classifier "
                          f"{','.join(r['scenario'] for r in e['scenarios'])} --seed {e['seed']} --json")
    out = [f"## Success classifiers on fresh episodes (Table 4.4): `{name}`\n",
           f"From `domains/{domain}/training/{name}`, the report of `{command}`: each experience scenario's "
           "action run on fresh episodes (none of them learned from), its success classifier predicting from each "
           "start. False success: predicted success but failed, a share of all episodes; always success: the share "
           "a classifier that always predicts success gets right.\n"]
    rows = [[code(r["scenario"]), code(r["classifier"]), str(r["episodes"]), _pct(r["failed"]), _pct(r["correct"]),
             _pct(r["false_success"]), _pct(r["always_success"]), _pct(r["predicted_fail"])] for r in e["scenarios"]]
    out.append(table(["scenario", "classifier", "episodes", "failed", "correct", "false success", "always success",
                      "predicted fail"], rows, align="llrrrrrr"))
    return out


def _pareto(domain: str, name: str, e: dict) -> list[str]:
    command = _command(e, f"tailor evaluate {domain} --pareto ... --episodes {e['situations']} --json")
    out = [f"## Time against energy (Ch. 8.1): `{name}`\n",
           f"From `domains/{domain}/training/{name}`, the report of `{command}`: {e['situations']} random "
           f"{code(e['comparison'])} situations refined for {code(e['objective'])} with each weight W and executed; "
           f"means over the {e['episodes']} where no run failed ({e['test']} of energy against W = 0).\n"]
    rows = [["greedy", str(e["greedy"]["failed"]), f"{_num(e['greedy']['duration'])} s", _num(e["greedy"]["energy"]),
             "", "", ""]]
    for p in e["pareto"]:
        rows.append([f"W = {p['weight']:g}", str(p["failed"]), f"{_num(p['duration'])} s", _num(p["energy"]),
                     _pct(p["duration_change"]), _pct(p["energy_change"]), _p(p["p_energy"])])
    out.append(table(["", "failed", "mean time", "mean energy (J)", "time vs W = 0", "energy vs W = 0",
                      "p energy"], rows, align="lrrrrrr"))
    return out


def domain_page(training: Path) -> str:
    domain = training.parent.name
    report = json.loads((training / "report.json").read_text(encoding="utf-8"))
    out = [GENERATED.format(source=f"the files in domains/{domain}/training/"),
           f"# Results: {domain}\n",
           f"What the committed result files of the `{domain}` domain say (simulator `{report['simulator']}`). "
           "They are rewritten by the commands named with each section; this page is generated from them.\n"]
    out += _training(domain, report)
    assertions, at = [], 0  # (one section where the first report is: their situations side by side)
    for path in sorted(training.glob("evaluate*.json")):
        evaluation = json.loads(path.read_text(encoding="utf-8"))
        if str(evaluation.get("schema", "")).startswith("tailor.evaluate_classifier/"):
            out += ["\n"] + _classifier(domain, path.name, evaluation)
        elif "greedy_mean" in evaluation:
            out += ["\n"] + _evaluation(domain, path.name, evaluation)
        elif "recovered_share" in evaluation:
            out += ["\n"] + _closed_loop(domain, path.name, evaluation)
        elif "mae_last" in evaluation:
            out += ["\n"] + _learning_curve(domain, path.name, evaluation)
        elif "pareto" in evaluation:
            out += ["\n"] + _pareto(domain, path.name, evaluation)
        elif "needless_assertions" in evaluation:
            at = at if assertions else len(out)
            assertions.append((path.name, evaluation))
    if assertions:
        out[at:at] = ["\n"] + _assertion(domain, assertions)
    for path in sorted(training.glob("*.txt")):
        if path.name in SKIPPED_TEXT:
            continue
        out += [f"\n## `{path.name}`\n", f"`domains/{domain}/training/{path.name}`, as the command wrote it:\n",
                "```text\n" + path.read_text(encoding="utf-8").rstrip("\n") + "\n```\n"]
    pictures = sorted(training.glob("*.png"))
    if pictures:
        out.append("\n## Pictures\n")
        for png in pictures:
            out += [f"`{png.name}`\n", f"![{png.stem}](../../domains/{domain}/training/{png.name})\n"]
    also = {"report.txt": "the tables and every model's rules as text",
            "report.html": "the same in one page with the pictures"}
    present = [f"`{name}` ({what})" for name, what in also.items() if (training / name).is_file()]
    if present:
        out.append(f"\nAlso in the folder, as `tailor train` wrote them: {' and '.join(present)}.\n")
    return "\n".join(out)


def index_page(dirs: list[Path]) -> str:
    rows = []
    for training in dirs:
        report = json.loads((training / "report.json").read_text(encoding="utf-8"))
        domain = training.parent.name
        models = ", ".join(f"{a} {_num(m['mae'], 3)} s ({_pct(m['mae_relative'])})" for a, m in report["models"].items())
        kept = []
        for path in sorted(training.glob("evaluate*.json")):
            e = json.loads(path.read_text(encoding="utf-8"))
            if "improvement" in e:
                kept.append(f"{code(path.name)}: refined {_pct(e['improvement'])} faster than greedy")
            elif "recovered_share" in e:
                kept.append(f"{code(path.name)}: closed loop failed {e['closed_loop']['failed_runs']} of "
                            f"{e['closed_loop']['runs']} runs, open loop {e['open_loop']['failed_runs']}")
            elif "mae_last" in e:
                kept.append(f"{code(path.name)}: learning in operation, MAE {_num(e['mae_first'], 3)} -> "
                            f"{_num(e['mae_last'], 3)} s")
            elif "needless_assertions" in e:
                kept.append(f"{code(path.name)}: {e['generator']} success {_pct(e['success_without'])} -> "
                            f"{_pct(e['success_with'])} with assertion")
            elif str(e.get("schema", "")).startswith("tailor.evaluate_classifier/"):
                kept.append(f"{code(path.name)}: classifier correct " + ", ".join(
                    f"{_pct(r['correct'])} on {r['scenario']} (always success {_pct(r['always_success'])})"
                    for r in e["scenarios"]))
        kept += [code(path.name) for path in sorted(training.glob("*.txt")) if path.name not in SKIPPED_TEXT]
        rows.append([f"[{domain}]({domain}.md)", escape(models), "; ".join(kept) or "-"])
    return "\n".join([
        GENERATED.format(source="the files in domains/*/training/"),
        "# Results\n",
        "One page per bundled domain, generated from the result files committed beside its models "
        "(`domains/NAME/training/`): the training report of `tailor train`, the reports of `tailor evaluate` kept "
        "there, and their pictures. When a command writes those files again, `python docs/scripts/generate.py` "
        "writes these pages again; a test fails while they differ.\n",
        table(["domain", "duration models: MAE (share of the mean duration)", "evaluations kept"],
              rows, align="lll")])


def pages() -> dict[str, str]:
    dirs = training_dirs()
    out = {"results/index.md": index_page(dirs)}
    for training in dirs:
        out[f"results/{training.parent.name}.md"] = domain_page(training)
    return out
