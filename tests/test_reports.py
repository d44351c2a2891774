"""Output people read: the HTML training report (one self-contained file), the warnings of a run too small to
trust, file permissions, logging with -q / -v, the top-level help, and readable plots."""

from __future__ import annotations

import base64
import copy
import json
import logging
import os
import re
import stat
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from tailor.errors import OutputFileError
from tailor.planner_bridge.bundled import DOMAINS_DIR
from tailor.cli.logs import cli_logging, level, verbosity_of
from tailor.cli.main import COMMANDS, build_parser, main
from tailor.refinement.learning.html_report import html_report
from tailor.refinement.learning.trust import trust_warnings
from tailor.outputs import new_file_mode, write_atomically

PNG = b"\x89PNG\r\n\x1a\n"


def bundled_report(domain: str) -> dict:
    return json.loads((DOMAINS_DIR / domain / "training" / "report.json").read_text(encoding="utf-8"))


# --- the HTML report ----------------------------------------------------------------------------------------
class _Page(HTMLParser):
    """Every tag with its attributes, the text of table rows' first cells, and <details> sections."""

    def __init__(self) -> None:
        super().__init__()
        self.tags: list[tuple[str, dict]] = []
        self.rows: list[list[str]] = []
        self._cell: list[str] | None = None
        self.details = 0
        self.style = ""
        self._in_style = False

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))
        if tag == "tr":
            self.rows.append([])
        elif tag in ("td", "th"):
            self._cell = []
        elif tag == "details":
            self.details += 1
        elif tag == "style":
            self._in_style = True

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self.rows[-1].append("".join(self._cell).strip())
            self._cell = None
        elif tag == "style":
            self._in_style = False

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)
        if self._in_style:
            self.style += data


def parse_page(text: str) -> _Page:
    page = _Page()
    page.feed(text)
    page.close()
    return page


def assert_self_contained(text: str) -> _Page:
    """No external reference: every src/href is a data: URI or an anchor, no <link>, no script, no url()."""
    page = parse_page(text)
    for tag, attrs in page.tags:
        assert tag not in ("link", "script", "iframe", "object", "embed"), tag
        for key in ("src", "href", "data", "srcset", "poster"):
            value = attrs.get(key)
            if value is not None:
                assert value.startswith("data:") or value.startswith("#"), f"<{tag} {key}={value[:40]!r}>"
    assert "url(" not in page.style and "@import" not in page.style
    assert not re.search(r"(src|href)\s*=\s*[\"']?(https?:|file:|//)", text, re.I)
    return page


def test_html_report_of_the_bundled_models_is_one_self_contained_page():
    report = bundled_report("soccer")
    figures = {"a.png": (PNG + b"first", "first figure"), "b.png": (PNG + b"second", "second figure")}
    rules = {"Rules of goToPose (n_i = 3)": "dist <= 1 : LM1 (3)\nLM1: t = 1 < 2", "Rules of x": "r"}
    text = html_report(report, rules, figures, [])
    page = assert_self_contained(text)
    first_cells = [row[0] for row in page.rows if row]
    for action in report["models"]:  # every duration model's row of Table 4.3, with its numbers
        row = next(r for r in page.rows if r and r[0] == action)
        assert row[1] == str(report["models"][action]["episodes"])
        assert row[6] == f"{report['models'][action]['mae']:.3f}"
    assert {"predicted Fail", "predicted Success"} <= set(first_cells)  # Table 4.4
    images = [attrs["src"] for tag, attrs in page.tags if tag == "img"]
    assert [base64.b64decode(src.split(",", 1)[1]) for src in images] == [png for png, _ in figures.values()]
    assert all(src.startswith("data:image/png;base64,") for src in images)
    assert page.details == len(rules) and "LM1: t = 1 &lt; 2" in text  # rules collapsible, escaped
    assert "too small to trust" not in text


def test_html_report_shows_warnings_and_escapes_them():
    text = html_report(bundled_report("arm"), {}, {}, ["duration model of <reach>: thin"])
    assert "too small to trust" in text and "&lt;reach&gt;" in text and "<reach>" not in text


# --- warnings -----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("domain", ["soccer", "arm"])
def test_the_bundled_training_reports_raise_no_warning(domain):
    assert trust_warnings(bundled_report(domain)) == []


def _classifier(report: dict) -> dict:
    """The goToPose classifier's row of a training report (schema 3: by action; schema 2: `collision`)."""
    return report["classifiers"]["goToPose"] if "classifiers" in report else report["collision"]


def test_each_warning_fires_on_its_own_condition_only():
    report = bundled_report("soccer")
    action = next(iter(report["models"]))

    def changed(edit) -> list[str]:
        r = copy.deepcopy(report)
        edit(r)
        return trust_warnings(r)

    def few_test_episodes(r):
        r["models"][action]["test_episodes"] = 6

    def no_better_than_the_median(r):
        r["models"][action]["mae_constant"] = r["models"][action]["mae"]

    def better_than_the_median(r):
        r["models"][action]["mae_constant"] = 2 * r["models"][action]["mae"]

    def at_chance(r):  # predicts failure for a random half, whatever happens
        _classifier(r)["confusion"]["counts"] = {"predicted_fail_observed_fail": 80, "predicted_fail_observed_success":
                                                 420, "predicted_success_observed_fail": 80,
                                                 "predicted_success_observed_success": 420}
        _classifier(r)["accuracy"] = 0.5

    def one_outcome(r):
        _classifier(r)["confusion"]["counts"] = {"predicted_fail_observed_fail": 0, "predicted_fail_observed_success":
                                                 10, "predicted_success_observed_fail": 0,
                                                 "predicted_success_observed_success": 990}

    def few_failures(r):
        _classifier(r)["outcomes"] = {"collision": 3, "success": 5997}

    def few_fresh(r):
        _classifier(r)["confusion"]["episodes"] = 20

    cases = {few_test_episodes: f"duration model of {action}: MAE measured on only 6 held-out episodes",
             no_better_than_the_median: f"duration model of {action}: MAE",
             at_chance: "success classifier of goToPose: at chance level",
             one_outcome: "the fresh episodes hold only one outcome",
             few_failures: "learned from only 3 failing episodes",
             few_fresh: "evaluated on only 20 fresh episodes"}
    for edit, start in cases.items():
        warnings = changed(edit)
        assert len(warnings) == 1 and start in warnings[0], (edit.__name__, warnings)
    assert changed(better_than_the_median) == []


# --- files get the permissions of a new file ---------------------------------------------------------------
@pytest.mark.parametrize("mask, mode", [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_outputs_get_the_mode_of_a_new_file_under_the_umask(tmp_path, mask, mode):
    previous = os.umask(mask)
    try:
        assert new_file_mode() == mode
        target = write_atomically(tmp_path / "a" / "out.json", lambda p: p.write_text("new"))
        reference = tmp_path / "plain"
        reference.write_text("x")  # what open() gives a new file
    finally:
        os.umask(previous)
    assert target.read_text() == "new"
    assert stat.S_IMODE(target.stat().st_mode) == mode == stat.S_IMODE(reference.stat().st_mode)


def test_a_failed_write_leaves_the_old_file_and_no_staged_one(tmp_path):
    target = tmp_path / "out.png"
    target.write_text("old")

    def broken(path: Path) -> None:
        path.write_text("half")
        raise OSError(28, "No space left on device")

    with pytest.raises(OutputFileError, match="out.png: cannot write: No space left on device"):
        write_atomically(target, broken)
    assert [p.name for p in tmp_path.iterdir()] == ["out.png"] and target.read_text() == "old"


# --- logging: -q / -v ---------------------------------------------------------------------------------------
def test_verbosity_is_read_from_the_command_line():
    assert verbosity_of(["-q", "train", "x"]) == -1
    assert verbosity_of(["-qq", "evaluate"]) == -2
    assert verbosity_of(["--verbose", "refine", "-v"]) == 2
    assert verbosity_of(["plan", "--", "-q"]) == 0 and verbosity_of(["plan", "--quiet"]) == -1
    assert verbosity_of(["--qui", "plan"]) == -1 and verbosity_of(["--verb", "plan"]) == 1
    assert verbosity_of(["--ver", "plan", "--json", "--seed"]) == 0
    assert [level(v) for v in (-3, -2, -1, 0, 1, 2)] == [logging.ERROR, logging.ERROR, logging.WARNING,
                                                        logging.INFO, logging.DEBUG, logging.DEBUG]


def test_diagnostics_go_to_stderr_at_the_asked_level(capsys):
    log = logging.getLogger("tailor.refinement.somewhere")
    for verbosity, shown in ((-2, ["error"]), (-1, ["warning", "error"]), (0, ["note", "warning", "error"]),
                             (1, ["debug", "note", "warning", "error"])):
        with cli_logging(verbosity, "tailor x"):
            log.debug("d")
            log.info("i")
            log.warning("w")
            log.error("e")
        captured = capsys.readouterr()
        assert captured.out == ""
        assert [line.split(": ")[1] for line in captured.err.splitlines()] == shown
        assert all(line.startswith("tailor x: ") for line in captured.err.splitlines())
    log.warning("after the command")  # the handler is gone again
    assert "tailor x" not in capsys.readouterr().err


def test_quiet_silences_notes_but_not_results(capsys):
    argv = ["evaluate", "soccer", "--episodes", "0", "--horizon-episodes", "0", "--jobs", "1000"]
    assert main(argv) == 0
    loud = capsys.readouterr()
    assert "note: --jobs 1000 capped at" in loud.err
    assert main(["-q", *argv]) == 0
    quiet = capsys.readouterr()
    assert quiet.err == "" and quiet.out == loud.out  # the results unchanged on stdout
    assert main([*argv, "-q"]) == 0  # after the command too
    assert capsys.readouterr().err == ""


def test_verbose_adds_debug_lines_on_stderr_only(capsys):
    assert main(["refine", "soccer", "score"]) == 0
    plain = capsys.readouterr()
    assert main(["-v", "refine", "soccer", "score"]) == 0
    verbose = capsys.readouterr()
    timed = re.compile(r"^Optimizer: .*$", re.M)  # the optimizer's time differs from run to run
    assert timed.sub("", verbose.out) == timed.sub("", plain.out)
    assert "tailor refine: debug: planned and refined greedy and with h=2 in" in verbose.err
    assert "debug" not in plain.err


# --- the top-level help ------------------------------------------------------------------------------------
def test_top_level_help_speaks_to_users():
    text = build_parser().format_help()
    assert "tailor makes a robot execute a symbolic plan" in text
    for name in COMMANDS:  # every command with its one line
        assert re.search(rf"^\s+{name}\s+\S", text, re.M), name
    assert "examples:" in text and "tailor refine " in text and "--simulate" in text
    assert "README" in text and "tailor COMMAND --help" in text
    assert "-q, --quiet" in text and "-v, --verbose" in text


def test_help_examples_name_a_bundled_domain_that_runs():
    text = build_parser().format_help()
    domain, problem = re.search(r"tailor plan (\S+) (\S+)", text).groups()
    assert (DOMAINS_DIR / domain / "problems" / f"{problem}.pddl").is_file()
    assert any((DOMAINS_DIR / domain / "models").glob("*.json"))


# --- plots --------------------------------------------------------------------------------------------------
def _boxes(fig, texts):
    renderer = fig.canvas.get_renderer()
    return [t.get_window_extent(renderer) for t in texts if t.get_visible() and t.get_text()]


def test_polar_cost_panels_keep_markers_inside_and_labels_apart():
    from types import SimpleNamespace

    import matplotlib.pyplot as plt

    from tailor.refinement.refine_plots import POLAR_MARGIN, costs_figure
    from tailor.sims.protocol import Quantity

    parameter = SimpleNamespace(id="pos2.phi", low=-np.pi, high=np.pi)
    values = np.linspace(-np.pi, np.pi, 361)
    first = 5.0 + 3.0 * np.cos(values)
    curves = [("1 first", first), ("2 second", 9.0 - 2.0 * np.sin(values)), ("sum", first + 9.0 - 2.0 * np.sin(values))]
    fig = costs_figure(parameter, values, curves, [("greedy", 0.0), ("refined", 3.0)], Quantity("rad", angle=True))
    fig.canvas.draw()
    axes = fig.axes
    labels = []
    for ax, (_, predicted) in zip(axes, curves):
        assert ax.get_ylim()[1] >= POLAR_MARGIN * predicted.max() - 1e-9  # a marker at the maximum stays whole
        legend = [t.get_text() for t in ax.get_legend().get_texts()]
        assert legend[1].startswith("greedy: 0°") and legend[2].startswith("refined: 172°")
        labels.append(_boxes(fig, ax.get_xticklabels()) + _boxes(fig, ax.get_yticklabels()))
    for i in range(len(axes)):  # no angle label of one panel runs into one of the next (the old "0180°")
        for j in range(i + 1, len(axes)):
            assert not any(a.overlaps(b) for a in labels[i] for b in labels[j])
    for boxes in labels:  # nor within a panel
        assert not any(a.overlaps(b) for k, a in enumerate(boxes) for b in boxes[k + 1:])
    plt.close(fig)


def test_the_polar_cost_plot_is_chosen_by_the_declared_quantity_not_by_its_name():
    """A full-circle range is drawn on polar axes where the simulator declares its quantity an angle; a
    parameter named like a heading (or any undeclared one) spanning the same range stays Cartesian."""
    from types import SimpleNamespace

    import matplotlib.pyplot as plt

    from tailor.refinement.refine_plots import costs_figure, on_the_circle
    from tailor.sims import registry
    from tailor.sims.protocol import UNDECLARED

    full = SimpleNamespace(id="pos2.phi", low=-np.pi, high=np.pi)
    soccer, kitchen = registry.get("soccer"), registry.get("kitchen")
    assert on_the_circle(full, soccer.quantity(full.id)) and not on_the_circle(full, UNDECLARED)
    assert on_the_circle(SimpleNamespace(id="s1.heading", low=-np.pi, high=np.pi), kitchen.quantity("s1.heading"))
    assert not on_the_circle(SimpleNamespace(id="s1.heading", low=-1.0, high=1.0), kitchen.quantity("s1.heading"))
    values = np.linspace(-np.pi, np.pi, 31)
    fig = costs_figure(full, values, [("sum", 2.0 + np.cos(values))], [("refined", 0.0)])  # nothing declared
    assert fig.axes[0].name == "rectilinear" and fig.axes[0].get_xlabel() == "pos2.phi"
    plt.close(fig)


def test_execution_panels_mark_the_start_in_the_legend():
    import matplotlib.pyplot as plt

    from tailor.refinement.pipeline import Options, read_task, resolve_task, run
    from tailor.refinement.refine_plots import executions_figure

    result = run(read_task(resolve_task("soccer", "score")), Options(horizon=1, greedy=False, simulate=True))
    outcome = result.refined
    assert outcome.simulated.succeeded
    fig = executions_figure(result.binding.entry.views, [("greedy", outcome.simulated)])
    ax = fig.axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("x", "y")  # the field from above, not time over time
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "start" in legend and "subgoals reached" in legend
    plt.close(fig)


def test_cartesian_cost_panels_keep_tick_labels_and_legend_apart():
    from types import SimpleNamespace

    import matplotlib.pyplot as plt

    from tailor.refinement.refine_plots import costs_figure
    from tailor.sims.protocol import Quantity

    parameter = SimpleNamespace(id="f2.omega_a", low=-1.0, high=1.0)  # not an angle: Cartesian panels
    values = np.linspace(-1.0, 1.0, 201)
    curves = [("1 reach", 1.0 - 0.4 * values), ("2 reach", 0.8 - 0.3 * values), ("sum", 1.8 - 0.7 * values)]
    fig = costs_figure(parameter, values, curves, [("greedy", 0.96), ("refined", 0.978)], Quantity("rad/s"))
    fig.canvas.draw()
    assert fig.axes[0].get_xlabel() == "f2.omega_a (rad/s)"  # the declared unit on the axis
    for ax in fig.axes:
        ticks = _boxes(fig, ax.get_xticklabels())
        assert not any(a.overlaps(b) for k, a in enumerate(ticks) for b in ticks[k + 1:])
        legend = ax.get_legend().get_window_extent(fig.canvas.get_renderer())
        assert not legend.overlaps(ax.xaxis.label.get_window_extent(fig.canvas.get_renderer()))
    plt.close(fig)


@pytest.mark.parametrize("name", ["mae_vs_n_i", "mae_vs_episodes"])
def test_learning_curve_legends_hide_no_point(name, monkeypatch):
    """The legends of Figs. 4.5 / 4.6 sit beside the axes, where they cannot cover a curve."""
    import matplotlib.pyplot as plt

    from tailor.refinement.learning import plots
    from tailor.refinement.models.action_models import load_action_models

    reports = {a: m.report for a, m in load_action_models(DOMAINS_DIR / "soccer" / "models").items()}
    captured = []
    monkeypatch.setattr(plots, "_save", lambda fig, target, layout=True: captured.append(fig))
    getattr(plots, f"plot_{name}")(reports, None)
    fig = captured[0]
    fig.tight_layout()
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    ax = fig.axes[0]
    legend = ax.get_legend()
    assert len(legend.get_texts()) >= len(reports)
    assert not legend.get_window_extent(renderer).overlaps(ax.get_window_extent(renderer))
    assert legend.get_window_extent(renderer).x1 <= fig.bbox.x1  # not cut off at the figure's edge
    plt.close(fig)


def test_a_classifier_without_fresh_failures_does_not_claim_a_false_success_share():
    """With no failing fresh episode the false-success share is 0 by convention; the reports say there were
    none instead of printing 0.0% as if it were measured."""
    from tailor.refinement.learning.report import false_success_text

    none = {"confusion": {"observed_fail": 0.0}, "false_success": 0.0}
    some = {"confusion": {"observed_fail": 0.2}, "false_success": 0.25}
    assert false_success_text(none, "failing ones") == "no failing ones among the fresh episodes to predict"
    assert false_success_text(some) == "25.0% of the failing episodes were predicted to succeed"
