"""`tailor evaluate DOMAIN --pareto W1,W2,...` (issue 31): the energy weights parsed, the summary's means, changes,
paired tests and front on hand-made rows, a situation whose choices follow its weight and its limit, and a tiny
run end to end with its JSON keys and plot."""

from __future__ import annotations

import argparse
import json

import numpy as np
import pytest
from scipy.stats import wilcoxon

from tailor.cli.evaluate_pareto import energy_weights
from tailor.cli.main import main
from tailor.planner_bridge import resolve_domain_dir
from tailor.refinement.binding import load_domain_binding
from tailor.refinement.evaluation.experiments import situation_seed
from tailor.refinement.evaluation.pareto import energy_objective, front, pareto_episode, summarize_pareto
from tailor.refinement.objective_grammar import DURATION_ONLY, MeasureBound
from tailor.refinement.situations import draw_situations


# --- the weight list ---------------------------------------------------------------------------------------------
def test_weights_are_sorted_without_repeats_and_always_hold_zero():
    assert energy_weights("0.3, 1,0.3") == (0.0, 0.3, 1.0)
    assert energy_weights("0,2") == (0.0, 2.0) and energy_weights("-0") == (0.0,)
    assert energy_objective(0.0) == DURATION_ONLY
    assert energy_objective(0.3).weights == (("duration", 1.0), ("energy", 0.3))


@pytest.mark.parametrize("text, message", [("", "expected comma-separated energy weights"),
                                           ("0.3,,1", "expected comma-separated energy weights"),
                                           ("0.3,x", "not a number: 'x'"), ("-1", "from 0 to"),
                                           ("inf", "from 0 to"), ("nan", "from 0 to")])
def test_a_weight_list_that_does_not_parse_is_refused(text, message):
    with pytest.raises(argparse.ArgumentTypeError, match=message):
        energy_weights(text)


def test_a_bad_weight_list_is_one_line_and_status_2(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["evaluate", "soccer", "--pareto", "0.3,heavy"])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1
    assert err.startswith("tailor evaluate: error: argument --pareto: not a number: 'heavy'") and "Traceback" not in err


@pytest.mark.parametrize("extra, message", [(["--max", "error=0.1"], "--max belongs to --pareto"),
                                            (["--pareto", "1", "--assertion"], "--pareto and --assertion"),
                                            (["--pareto", "1", "--max", "precision=1"], "--max: unknown measure")])
def test_options_that_do_not_go_with_pareto_are_one_line(capsys, extra, message):
    assert main(["evaluate", "soccer", "--episodes", "1", *extra]) == 2
    errors = [line for line in capsys.readouterr().err.splitlines() if "error:" in line]
    assert len(errors) == 1 and message in errors[0]


# --- the summary on hand-made rows -------------------------------------------------------------------------------
def _run(duration, energy, error=0.05, ok=True, within=None):
    run = {"ok": ok, "outcome": "success" if ok else "timeout", "duration": duration, "energy": energy,
           "error": error, "predicted_duration": duration, "predicted_energy": energy}
    if within is not None:
        run.update(within=within and ok, actions_within=[["a", within]], predicted_within=[["a", within]])
    return run


def _row(greedy, w0, w1, limited=None, binds=None):
    row = {"index": 0, "seed": 0, "problem": "p", "greedy": greedy, "weights": {"0": w0, "1": w1}}
    if limited is not None:
        row.update(limited={**limited, "unattainable": False}, binds=binds)
    return row


def test_means_are_over_the_situations_where_every_run_succeeded_and_failures_are_counted():
    rows = [_row(_run(12, 30), _run(10, 40), _run(10.5, 30)),
            _row(_run(14, 35), _run(11, 44), _run(11.5, 33)),
            _row(_run(13, 31), _run(10, 41), _run(10.2, 35)),
            _row(_run(13, 31), _run(10, 41), _run(99, 1, ok=False))]  # left out of every mean
    s = summarize_pareto(rows, (0.0, 1.0))
    assert (s["situations"], s["episodes"]) == (4, 3)
    assert s["greedy"]["duration"] == pytest.approx(13) and s["greedy"]["failed"] == 0
    w0, w1 = s["pareto"]
    assert (w0["weight"], w0["duration"], w0["energy"], w0["failed"]) == (0.0, pytest.approx(31 / 3), 125 / 3, 0)
    assert (w1["weight"], w1["energy"], w1["failed"]) == (1.0, pytest.approx(98 / 3), 1)
    assert w1["energy_change"] == pytest.approx(98 / 125 - 1) and w1["duration_change"] == pytest.approx(32.2 / 31 - 1)
    assert w0["p_energy"] is None and w0["energy_change"] == 0.0
    assert w1["p_energy"] == pytest.approx(wilcoxon(np.array([30, 33, 35]) - np.array([40, 44, 41])).pvalue)
    assert s["p_energy"] == {"1": w1["p_energy"]}
    # greedy is slower than W=1 and costs less energy than W=0: every point is on the front here
    assert s["greedy"]["front"] and w0["front"] and w1["front"]


def test_the_front_keeps_the_points_no_other_beats_in_both():
    assert front([(10, 40), (11, 30), (12, 35), (10, 45), (None, 1)]) == [True, True, False, False, False]
    assert front([(10, 40), (10, 40)]) == [True, True]  # equal points dominate neither


def test_the_limit_shares_count_a_failed_run_as_not_within():
    rows = [_row(_run(12, 30), _run(10, 40, within=False), _run(11, 35), _run(11, 40, within=True), binds=True),
            _row(_run(12, 30), _run(10, 40, within=True), _run(11, 35), _run(10, 40, within=True), binds=False),
            _row(_run(12, 30), _run(10, 40, within=False), _run(11, 35), _run(12, 40, ok=False, within=True),
                 binds=True)]
    limit = summarize_pareto(rows, (0.0, 1.0), (MeasureBound("error", 0.1),))["limit"]
    assert (limit["binds"], limit["binds_share"]) == (2, pytest.approx(2 / 3))
    assert limit["within_duration_only"] == pytest.approx(1 / 3) and limit["within_limited"] == pytest.approx(2 / 3)
    assert limit["within_duration_only_where_binding"] == 0.0 and limit["within_limited_where_binding"] == 0.5
    assert limit["failed_limited"] == 1 and limit["episodes"] == 2
    assert limit["duration_change"] == pytest.approx(21 / 20 - 1)
    assert limit["actions_within"] == {"duration_only": {"a": pytest.approx(1 / 3)}, "limited": {"a": 1.0}}


# --- one situation: the weight and the limit decide the choices -------------------------------------------------
@pytest.fixture(scope="module")
def situation():
    domain_dir = resolve_domain_dir("soccer")
    binding = load_domain_binding(domain_dir)
    (item,) = draw_situations(domain_dir, binding, "score", [(0, situation_seed(0, 0))], 0, {})
    return item


def test_the_energy_weight_and_the_limit_change_what_is_chosen(situation):
    """Weight 10 chooses a parameterization predicted to spend less energy than the duration alone (ignoring the
    weight would choose the same); the 8 cm limit on the error keeps goToPose within it where duration-only
    refinement does not (dropping the limit would not)."""
    job, index, objects = situation
    row = pareto_episode(job, index, objects, (0.0, 10.0), (MeasureBound("error", 0.08),), "ga")
    plain, heavy = row["weights"]["0"], row["weights"]["10"]
    assert heavy["predicted_energy"] < plain["predicted_energy"] - 1.0  # J
    assert heavy["predicted_duration"] > plain["predicted_duration"]
    assert row["binds"] and dict(plain["predicted_within"])["goToPose"] is False
    assert dict(row["limited"]["predicted_within"])["goToPose"] is True
    assert row["greedy"]["ok"] and all(run["ok"] for run in row["weights"].values())


# --- end to end --------------------------------------------------------------------------------------------------
def test_a_tiny_pareto_run_prints_its_json_and_draws_the_front(capsys, tmp_path):
    picture = tmp_path / "front.png"
    assert main(["-q", "evaluate", "soccer", "--pareto", "3", "--episodes", "2", "--optimizer", "ga",
                 "--max", "error=0.08", "--json", "--plot", str(picture)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["schema"] == "tailor.evaluate_pareto/1" and report["situations"] == 2
    assert {"duration", "energy", "error", "failed", "front"} <= set(report["greedy"])
    assert [e["weight"] for e in report["pareto"]] == [0.0, 3.0]
    for entry in report["pareto"]:
        assert {"weight", "duration", "energy", "error", "p_energy", "energy_change", "duration_change"} <= set(entry)
    assert set(report["p_energy"]) == {"3"} and "Wilcoxon" in report["test"]
    assert report["limit"]["bounds"] == {"error": 0.08} and len(report["rows"]) == 2
    assert report["measure_units"] == {"duration": "s", "energy": "J", "error": "m"}
    assert picture.stat().st_size > 10_000


def test_the_text_report_is_a_table_per_weight(capsys):
    assert main(["-q", "evaluate", "soccer", "--pareto", "1", "--episodes", "1", "--optimizer", "ga"]) == 0
    out = capsys.readouterr().out
    assert "greedy (h=1)" in out and "W=0 " in out and "W=1 " in out and "energy (J)" in out
