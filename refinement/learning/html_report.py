"""The training report as one self-contained HTML file: Table 4.3 (duration models), Table 4.4 (each success
classifier's confusion matrix), the learning curves and pictures embedded as base64 PNG, the learned rules in
collapsible sections. No external asset, script or style sheet: it opens offline, mailed or archived alone."""

from __future__ import annotations

import base64
import html
from collections.abc import Mapping

from tailor.refinement.learning.report import SPACE_LABELS, false_success_text, hours_minutes, percent, space_mae
from tailor.refinement.learning.trust import classifier_reports

STYLE = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 70em; padding: 0 1em; color: #222; }
table { border-collapse: collapse; margin: 0.5em 0 1em; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.6em; text-align: right; }
th:first-child, td:first-child { text-align: left; }
thead th { background: #f0f0f0; }
.warnings { background: #fff4e5; border-left: 4px solid #e67e00; padding: 0.5em 1em; }
figure { margin: 1em 0; }
figure img { max-width: 100%; height: auto; }
figcaption { font-size: 0.9em; color: #555; }
details { margin: 0.5em 0; }
summary { cursor: pointer; font-weight: bold; }
pre { font-size: 0.8em; overflow-x: auto; background: #f8f8f8; padding: 0.5em; }
.note { color: #555; font-size: 0.9em; }
"""

DURATION_COLUMNS = ("action", "episodes", "mean t (s)", "simulated h:mm", "n_i", "leaf size", "MAE (s)", "MAE / mean t",
                    "HGB MAE (s)", "MAE / HGB", "median-predictor MAE (s)", "leaves")


def _e(value) -> str:
    return html.escape(str(value), quote=True)


def _table(header: tuple[str, ...], rows: list[tuple], caption: str = "") -> str:
    head = "".join(f"<th>{_e(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{_e(c)}</td>" for c in row) + "</tr>" for row in rows)
    caption = f"<caption>{_e(caption)}</caption>" if caption else ""
    return f"<table>{caption}<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _number(value, pattern: str) -> str:
    return "-" if value is None else format(value, pattern)


def duration_rows(models: Mapping[str, dict]) -> list[tuple]:
    """Table 4.3's rows: one per duration model."""
    return [(action, r["episodes"], _number(r["mean_duration"], ".2f"), hours_minutes(r["simulated_hours"]), r["n_i"],
             r["min_samples_leaf"], _number(r["mae"], ".3f"), percent(r["mae_relative"]), _number(r["mae_hgb"], ".3f"),
             _number(r.get("mae_over_hgb"), ".2f"), _number(r.get("mae_constant"), ".3f"), r["leaves"])
            for action, r in models.items()]


def space_rows(models: Mapping[str, dict]) -> list[tuple]:
    """Fig. 4.3's rows: per action the held-out MAE on each feature space, gradient boosting on the raw
    parameters, and the auto space's ratios to both."""
    rows = []
    for action, r in models.items():
        comparison = r.get("space_comparison")
        if not comparison:
            continue
        mae, hgb = space_mae(comparison), comparison["mae_hgb_raw"]
        auto, expert = mae.get("auto"), mae.get("expert")
        rows.append((action, *(_number(mae.get(label), ".3f") for label in SPACE_LABELS), _number(hgb, ".3f"),
                     _number(None if auto is None or not hgb else auto / hgb, ".2f"),
                     _number(None if auto is None or not expert else auto / expert, ".2f")))
    return rows


def features_html(models: Mapping[str, dict]) -> str:
    """Each generated feature as a formula with its unit."""
    parts = []
    for action, r in models.items():
        features = r.get("features")
        if features:
            rows = [(f["name"], f["formula"], f.get("unit") or "") for f in features]
            parts.append(_table(("feature", "formula", "unit"), rows,
                                f"Features of {action}, generated from its quantities (Sec. 4.1.1)"))
    return "".join(parts)


def confusion_html(action: str, c: dict) -> str:
    """Table 4.4: shares of the fresh episodes by predicted and observed outcome, with totals."""
    counts, n = c["confusion"]["counts"], max(c["confusion"]["episodes"], 1)
    ff, fs = counts["predicted_fail_observed_fail"], counts["predicted_fail_observed_success"]
    sf, ss = counts["predicted_success_observed_fail"], counts["predicted_success_observed_success"]
    share = lambda k: percent(k / n)  # noqa: E731
    rows = [("predicted Fail", share(ff), share(fs), share(ff + fs)),
            ("predicted Success", share(sf), share(ss), share(sf + ss)),
            ("total", share(ff + sf), share(fs + ss), f"correct {percent(c['accuracy'])}")]
    table = _table(("", "observed Fail", "observed Success", "total"), rows,
                   f"Confusion matrix of the success classifier of {action} on {c['confusion']['episodes']} fresh "
                   "episodes (Table 4.4)")
    outcomes = ", ".join(f"{k}: {v}" for k, v in c.get("outcomes", {}).items())
    note = (f"Decision tree trained on {c['episodes']} episodes ({outcomes}); cost of a false success "
            f"{c['cost_false_success']:g} relative to the class balance, min_samples_leaf {c['min_samples_leaf']}, "
            f"{c['leaves']} leaves. {false_success_text(c).capitalize()}.")
    return f"<h3>{_e(action)}</h3><p class=\"note\">{_e(note)}</p>{table}"


def figure_html(name: str, png: bytes, caption: str) -> str:
    data = base64.b64encode(png).decode("ascii")
    return (f"<figure id=\"{_e(name)}\"><img src=\"data:image/png;base64,{data}\" alt=\"{_e(caption)}\">"
            f"<figcaption>{_e(caption)} ({_e(name)})</figcaption></figure>")


def html_report(report: dict, rules: Mapping[str, str], figures: Mapping[str, tuple[bytes, str]],
                warnings: list[str]) -> str:
    """The whole page. `rules`: section title -> rules text; `figures`: file name -> (PNG bytes, caption)."""
    title = f"Action models of domain {report['domain']}"
    meta = (f"Simulator {report.get('simulator', '?')}, seed {report['seed']}, {report['episodes_per_scenario']} "
            f"episodes per scenario; gathering {report['gather_seconds']:.0f} s, training "
            f"{report['train_seconds']:.0f} s.")
    parts = [f"<h1>{_e(title)}</h1>", f"<p>{_e(meta)}</p>"]
    if warnings:
        items = "".join(f"<li>{_e(w)}</li>" for w in warnings)
        parts.append(f"<div class=\"warnings\"><strong>This run is too small to trust:</strong><ul>{items}</ul></div>")
    parts += [
        "<h2>Duration models (Table 4.3)</h2>",
        "<p class=\"note\">Successful episodes and their mean duration, simulated time of all gathered episodes, "
        "the chosen examples per episode n_i and leaf size, the MAE on the held-out quarter (first example of each "
        "episode) beside that of gradient boosting (HGB) trained on the same examples and of always predicting the "
        "median duration; leaves of the stored model (trained on all episodes).</p>",
        _table(DURATION_COLUMNS, duration_rows(report["models"])),
    ]
    spaces = space_rows(report["models"])
    if spaces:
        parts += ["<h2>Feature spaces (Fig. 4.3)</h2>",
                  "<p class=\"note\">Held-out MAE (s) of the model tree on the raw parameters, Table 4.1's generic row "
                  "where the action's quantities match one, the simulator's expert space where it brings one, and the "
                  "generated space (auto), each with its leaf size chosen on validation at the model's n_i, beside "
                  "gradient boosting on the raw parameters; the same test episodes for every space.</p>",
                  _table(("action", *SPACE_LABELS, "HGB raw", "auto / HGB", "auto / expert"), spaces)]
    generated = features_html(report["models"])
    if generated:
        parts += ["<h2>Generated features</h2>", generated]
    for chain in report.get("subgoal_experience") or ():
        generator = chain.get("generator", chain.get("problem"))  # schema 2 named it the problem
        parts.append(f"<p class=\"note\">{_e(chain['action'])} also learned from {chain['episodes']} episodes "
                     f"started at the subgoals refinement chose in {chain['situations']} random "
                     f"'{_e(generator)}' situations ({chain['rounds']} round(s), Sec. 8.1); its row "
                     "covers both.</p>")
    classifiers = classifier_reports(report)
    if classifiers:
        parts.append("<h2>Success classifiers (Sec. 4.2.2, Table 4.4)</h2>")
        parts += [confusion_html(action, c) for action, c in classifiers.items()]
    if figures:
        parts.append("<h2>Learning curves and pictures</h2>")
        parts += [figure_html(name, png, caption) for name, (png, caption) in figures.items()]
    if rules:
        parts.append("<h2>Rules</h2>")
        parts += [f"<details><summary>{_e(name)}</summary><pre>{_e(text)}</pre></details>"
                  for name, text in rules.items()]
    body = "\n".join(parts)
    return (f"<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{_e(title)}</title>\n"
            f"<style>{STYLE}</style>\n</head>\n<body>\n{body}\n</body>\n</html>\n")
