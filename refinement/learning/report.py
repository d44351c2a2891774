"""The readable training report: a Table 4.3-like row per duration model and per further measure's model
(energy, end error: Ch. 8.1), the classifier's confusion matrix (Table 4.4), and the learned rules (the full
text file); and the short summary `tailor train` prints."""

from __future__ import annotations

from tailor.refinement.learning.trust import classifier_reports


def hours_minutes(hours: float) -> str:
    minutes = round(hours * 60.0)
    return f"{minutes // 60}:{minutes % 60:02d}"


def percent(share: float) -> str:
    return f"{100.0 * share:.1f}%"


def false_success_text(c: dict, failing: str = "failing episodes") -> str:
    """How many of the fresh failures a classifier predicted to succeed; saying so where there was none (its
    share is then 0 by convention, which would read as a result)."""
    if not c["confusion"]["observed_fail"]:
        return f"no {failing} among the fresh episodes to predict"
    return f"{percent(c['false_success'])} of the {failing} were predicted to succeed"


SPACE_LABELS = ("raw", "generic", "expert", "auto")


def space_mae(comparison: dict) -> dict[str, float]:
    """Fig. 4.3's row of one action: space label -> held-out MAE (s)."""
    return {row["space"]: row["mae"] for row in comparison.get("rows", ())}


def space_table(reports: dict[str, dict]) -> list[str]:
    """Fig. 4.3 as a table: per action the held-out MAE on each feature space and of gradient boosting on the
    raw parameters, and the auto space's ratios to both."""
    rows = {action: r["space_comparison"] for action, r in reports.items() if r.get("space_comparison")}
    if not rows:
        return []
    header = (f"{'action':<14}" + "".join(f"{label:>9}" for label in SPACE_LABELS)
              + f"{'HGB raw':>9}{'auto/HGB':>9}{'auto/expert':>12}")
    lines = [header, "-" * len(header)]
    for action, comparison in rows.items():
        mae = space_mae(comparison)
        cells = "".join(f"{mae[label]:>9.3f}" if label in mae else f"{'-':>9}" for label in SPACE_LABELS)
        hgb = comparison["mae_hgb_raw"]
        auto = mae.get("auto")
        over_hgb = "-" if auto is None or not hgb else f"{auto / hgb:.2f}"
        over_expert = "-" if auto is None or not mae.get("expert") else f"{auto / mae['expert']:.2f}"
        lines.append(f"{action:<14}{cells}{hgb:>9.3f}{over_hgb:>9}{over_expert:>12}")
    return lines


def feature_lines(action: str, report: dict) -> list[str]:
    """The features a model uses, each as a formula with its unit (generated ones), or its space's name."""
    features = report.get("features")
    if not features:
        return []
    lines = [f"  {action} features (generated, Sec. 4.1.1):"]
    for f in features:
        unit = f" [{f['unit']}]" if f.get("unit") else ""
        lines.append(f"    {f['name']} = {f['formula']}{unit}")
    return lines


def duration_table(reports: dict[str, dict]) -> list[str]:
    header = (f"{'action':<14}{'episodes':>9}{'mean t (s)':>11}{'sim. h:mm':>10}{'n_i':>5}{'leaf':>5}{'MAE (s)':>9}"
              f"{'MAE/t':>7}{'HGB MAE (s)':>12}{'MAE/HGB':>8}{'leaves':>7}")
    lines = [header, "-" * len(header)]
    for action, r in reports.items():
        lines.append(
            f"{action:<14}{r['episodes']:>9d}{r['mean_duration']:>11.2f}{hours_minutes(r['simulated_hours']):>10}"
            f"{r['n_i']:>5d}{r['min_samples_leaf']:>5d}{r['mae']:>9.3f}{percent(r['mae_relative']):>7}"
            f"{r['mae_hgb']:>12.3f}"
            f"{'-' if r['mae_over_hgb'] is None else format(r['mae_over_hgb'], '.2f'):>8}{r['leaves']:>7}"
        )
    return lines


def measure_table(measures: dict[str, dict[str, dict]]) -> list[str]:
    """Per action and further measure: successful episodes, the measure's mean, the leaf size, the held-out MAE
    (absolute, relative to the mean, against gradient boosting) and the stored tree's leaves."""
    rows = [(action, name, r) for action, by_measure in measures.items() for name, r in by_measure.items()]
    if not rows:
        return []
    header = (f"{'action':<14}{'measure':<14}{'unit':>5}{'episodes':>9}{'mean':>10}{'leaf':>5}{'MAE':>10}"
              f"{'MAE/mean':>9}{'HGB MAE':>10}{'MAE/HGB':>8}{'leaves':>7}")
    lines = [header, "-" * len(header)]
    for action, name, r in rows:
        over = r.get("mae_over_hgb")
        lines.append(f"{action:<14}{name:<14}{r.get('unit', ''):>5}{r['episodes']:>9d}{r['mean']:>10.4g}"
                     f"{r['min_samples_leaf']:>5d}{r['mae']:>10.4g}{percent(r['mae_relative']):>9}"
                     f"{r['mae_hgb']:>10.4g}{'-' if over is None else format(over, '.2f'):>8}{r['leaves']:>7}")
    return lines


def measure_mae_lines(report: dict) -> list[str]:
    """One line per action with further measures' models: each one's held-out MAE, relative to its mean and to
    gradient boosting."""
    lines = []
    for action, by_measure in report.get("measures", {}).items():
        parts = []
        for name, r in by_measure.items():
            unit = f" {r['unit']}" if r.get("unit") else ""
            over = "" if r.get("mae_over_hgb") is None else f", {r['mae_over_hgb']:.2f}x HGB"
            parts.append(f"{name} MAE {r['mae']:.4g}{unit} ({percent(r['mae_relative'])} of its mean{over})")
        if parts:
            lines.append(f"  {action} measures: " + "; ".join(parts))
    return lines


def confusion_table(evaluation: dict) -> list[str]:
    c, n = evaluation["counts"], max(evaluation["episodes"], 1)
    share = lambda key: percent(c[key] / n)  # noqa: E731
    fail_row = c["predicted_fail_observed_fail"] + c["predicted_fail_observed_success"]
    success_row = c["predicted_success_observed_fail"] + c["predicted_success_observed_success"]
    fail_col = c["predicted_fail_observed_fail"] + c["predicted_success_observed_fail"]
    success_col = c["predicted_fail_observed_success"] + c["predicted_success_observed_success"]
    return [
        f"{'':<20}{'observed Fail':>14}{'observed Success':>18}{'total':>8}",
        f"{'predicted Fail':<20}{share('predicted_fail_observed_fail'):>14}"
        f"{share('predicted_fail_observed_success'):>18}{percent(fail_row / n):>8}",
        f"{'predicted Success':<20}{share('predicted_success_observed_fail'):>14}"
        f"{share('predicted_success_observed_success'):>18}{percent(success_row / n):>8}",
        f"{'total':<20}{percent(fail_col / n):>14}{percent(success_col / n):>18}"
        f"   correct {percent(evaluation['accuracy'])}",
    ]


def _subgoal_lines(chains: list[dict] | None) -> list[str]:
    lines = []
    for chain in chains or ():
        generator = chain.get("generator", chain.get("problem"))  # schema 2 named it the problem
        lines += ["", f"{chain['action']} also learned from {chain['episodes']} episodes started at the subgoals "
                      f"refinement chose in {chain['situations']} random '{generator}' situations",
                  f"(greedy and horizon 2 in turn, in {chain['rounds']} round(s), each with the models the one "
                  "before retrained; Sec. 8.1); its row covers both."]
    return lines


def _classifier_lines(c: dict) -> list[str]:
    return [
        "",
        f"Success classifier of {c['action']} (Sec. 4.2.2): decision tree trained on "
        f"{c['episodes']} episodes ({c['outcomes']}), cost of a false success {c['cost_false_success']:g} "
        f"relative to the class balance (class weight of failures {c['class_weight_fail']:.3g}), "
        f"min_samples_leaf {c['min_samples_leaf']}, {c['leaves']} leaves.",
        f"Confusion matrix on {c['fresh_episodes']} fresh episodes (Table 4.4):",
        "",
        *confusion_table(c["confusion"]),
        "",
        f"false success: {false_success_text(c)}",
    ]


def rules_sections(models: dict, classifiers: dict) -> dict[str, str]:
    """Section title -> the learned rules (WEKA-like text, App. C.3.1) of each model and classifier."""
    sections = {}
    for action, model in models.items():
        sections[f"Rules of {action} (n_i = {model.n_i})"] = model.rules_text()
        for name, measure in getattr(model, "measures", {}).items():
            unit = f"{measure.unit}, " if measure.unit else ""
            sections[f"Rules of {action} {name} ({unit}n_i = {measure.n_i})"] = measure.rules_text(model.feature_names)
    sections.update({f"Rules of the success classifier of {action}": classifier.rules_text()
                     for action, classifier in classifiers.items()})
    return sections


def header_line(report: dict) -> str:
    return (f"Action models of domain {report['domain']} (simulator {report.get('simulator', '?')}, seed "
            f"{report['seed']}, {report['episodes_per_scenario']} episodes per scenario; "
            f"gathering {report['gather_seconds']:.0f} s, training {report['train_seconds']:.0f} s)")


def warning_lines(warnings: list[str]) -> list[str]:
    return ["", "WARNING: this run is too small to trust:", *(f"  - {w}" for w in warnings)] if warnings else []


def format_report(report: dict, models: dict, classifiers: dict, warnings: list[str] = ()) -> str:
    """The whole report as text; `models` and `classifiers` (by action) give the rules."""
    lines = [
        header_line(report),
        *warning_lines(list(warnings)),
        "",
        "Duration models (Table 4.3): successful episodes, their mean duration, simulated time of all gathered",
        "episodes, chosen n_i and leaf size (min_samples_leaf), MAE on the held-out quarter (first example of each",
        "episode), and the MAE of HistGradientBoostingRegressor trained on the same examples; leaves of the",
        "stored model (trained on all episodes).",
        "",
        *duration_table(report["models"]),
        *_subgoal_lines(report.get("subgoal_experience")),
    ]
    measures = measure_table(report.get("measures", {}))
    if measures:
        lines += ["", "Models of further measures (Ch. 8.1): each a model tree in its action's features, by the same",
                  "protocol from the first example of each episode (n_i = 1); mean and MAE in the measure's unit, MAE",
                  "on the held-out quarter beside gradient boosting (HGB) on the same examples.", "", *measures]
    table = space_table(report["models"])
    if table:
        lines += ["", "Feature spaces (Fig. 4.3): held-out MAE (s) of the model tree on the raw parameters, Table",
                  "4.1's generic row where the action's quantities match one, the simulator's expert space where it",
                  "brings one and the generated space (auto), each with its leaf size chosen on validation at the",
                  "model's n_i, beside gradient boosting (HGB) on the raw parameters; the same test episodes for every",
                  "space.", "", *table]
    for action, r in report["models"].items():
        chosen = feature_lines(action, r)
        if chosen:
            lines += ["", *chosen]
    for c in classifier_reports(report).values():
        lines += _classifier_lines(c)
    lines.append("")
    for title, text in rules_sections(models, classifiers).items():
        lines += [f"{title}:", text, ""]
    return "\n".join(lines)


def summary_lines(report: dict) -> list[str]:
    """What `tailor train` prints: per duration model its examples, MAE, MAE relative to the mean duration and
    to gradient boosting; per classifier its accuracy on fresh episodes (the details are in the report files)."""
    header = f"  {'action':<16}{'episodes':>9}{'examples':>10}{'MAE (s)':>9}{'MAE/mean':>10}{'vs HGB':>8}"
    lines = [header_line(report), "", header]
    for action, r in report["models"].items():
        ratio = "-" if r.get("mae_over_hgb") is None else f"{r['mae_over_hgb']:.2f}x"
        lines.append(f"  {action:<16}{r['episodes']:>9d}{r['examples']:>10d}{r['mae']:>9.3f}"
                     f"{percent(r['mae_relative']):>10}{ratio:>8}")
    lines += measure_mae_lines(report)
    for action, c in classifier_reports(report).items():
        lines.append(f"  success classifier of {action}: {percent(c['accuracy'])} correct on "
                     f"{c['confusion']['episodes']} fresh episodes, {false_success_text(c, 'failing ones')}")
    for action, r in report["models"].items():
        lines += feature_lines(action, r)
    compared = [f"{action} {_auto_against(r['space_comparison'])}" for action, r in report["models"].items()
                if r.get("space_comparison")]
    if compared:
        lines.append("  auto features' held-out MAE (Fig. 4.3, in the report): " + "; ".join(compared))
    return lines


def _auto_against(comparison: dict) -> str:
    """The auto space's MAE against gradient boosting on the raw parameters and the expert space, in a few words."""
    mae, hgb = space_mae(comparison), comparison["mae_hgb_raw"]
    if "auto" not in mae:
        return "-"
    text = f"{mae['auto']:.3f} s ({mae['auto'] / hgb:.2f}x HGB raw" if hgb else f"{mae['auto']:.3f} s ("
    return text + (f", {mae['auto'] / mae['expert']:.2f}x expert)" if mae.get("expert") else ")")
