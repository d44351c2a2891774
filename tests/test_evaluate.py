"""`tailor evaluate`: the statistics of Sec. 5.5 on hand-made rows, and a tiny end-to-end run."""

from __future__ import annotations

import json
import tomllib

import numpy as np
import pytest

from tailor.planner_bridge.bundled import DOMAINS_DIR
from tailor.refinement.binding import EvaluationPlan, RefinementDefaults, load_domain_binding, parse_binding
from tailor.cli.main import main
from tailor.errors import BindingError
from tailor.refinement.evaluation.experiments import (
    summarize_comparison,
    summarize_horizons,
)


def _row(greedy, refined, oracle=None, ok=(True, True), zero=None):
    row = {"problem": "score", "greedy": greedy, "refined": refined, "greedy_ok": ok[0], "refined_ok": ok[1],
           "predicted_greedy": greedy, "predicted_refined": refined, "analytic_seconds": 0.002,
           "analytic_method": "analytic", "ga_seconds": 0.05, "analytic_cost": refined, "ga_cost": refined * 1.02}
    if oracle is not None:
        row["oracle"], row["oracle_method"] = oracle, "grid"
    if zero is not None:
        row["zero"], row["zero_ok"] = zero
    return row


def test_score_statistics_follow_eq_5_3_and_table_5_4():
    rows = [_row(10.0, 8.0, oracle=7.5), _row(10.0, 10.05), _row(10.0, 11.0, oracle=10.0), _row(12.0, 9.0),
            _row(10.0, 9.0, ok=(False, True))]
    s = summarize_comparison(rows)
    assert (s["scenarios"], s["episodes"], s["failed_greedy"], s["failed_refined"]) == (5, 4, 1, 0)
    assert s["problems"] == ["score"] and s["oracle_methods"] == ["grid"] and s["oracle_episodes"] == 2
    assert s["improvement"] == pytest.approx(np.mean([0.2, -0.005, -0.1, 0.25]))  # mean of 1 - t_h2 / t_h1
    assert (s["better"], s["equal"], s["worse"]) == (2, 1, 1)  # within 1% counts as equal
    assert s["oracle_ratio"] == pytest.approx((8.0 + 11.0) / (7.5 + 10.0))
    assert s["greedy_oracle_ratio"] == pytest.approx(20.0 / 17.5)
    assert s["analytic_ga_agree"] == 0.0  # 2% apart in every row
    assert s["p_value"] == pytest.approx(__import__("scipy").stats.ttest_rel([10, 10, 10, 12], [8, 10.05, 11, 9]).pvalue)
    assert "zero_mean" not in s  # no zero baseline in these rows


def test_zero_baseline_is_paired_with_refined_where_both_succeeded():
    rows = [_row(10.0, 8.0, zero=(16.0, True)), _row(10.0, 9.0, zero=(12.0, True)), _row(10.0, 9.0, zero=(5.0, False))]
    s = summarize_comparison(rows)
    assert (s["zero_episodes"], s["failed_zero"], s["zero_mean"]) == (2, 1, 14.0)
    assert s["improvement_over_zero"] == pytest.approx(np.mean([0.5, 0.25]))
    assert s["p_value_zero"] == pytest.approx(__import__("scipy").stats.ttest_rel([16, 12], [8, 9]).pvalue)


def test_the_improvement_is_stated_against_the_stronger_of_greedy_and_the_zero_baseline():
    """Where stopping at every way-point (the zero baseline) is faster than greedy, an improvement over greedy
    overstates what refinement adds: it is also stated against the zero baseline, over the situations where
    all three succeeded."""
    rows = [_row(10.0, 8.0, zero=(9.0, True)), _row(12.0, 9.0, zero=(10.5, True)), _row(10.0, 9.0, zero=(5.0, False))]
    s = summarize_comparison(rows)
    assert s["stronger_baseline"] == "zero" and s["stronger_baseline_episodes"] == 2
    assert s["improvement_over_stronger_baseline"] == pytest.approx(np.mean([1 - 8 / 9, 1 - 9 / 10.5]))
    assert summarize_comparison([_row(10.0, 8.0, zero=(11.0, True))])["stronger_baseline"] == "greedy"
    assert summarize_comparison([_row(10.0, 8.0)])["stronger_baseline"] == "greedy"  # no zero baseline


def _windowed(method, cost, ga_cost, seconds, gap=None, action=0):
    window = {"method": method, "seconds": seconds, "cost": cost, "gap": gap, "action": action}
    if method != "ga":
        window.update(ga_cost=ga_cost, ga_seconds=0.3)
    return window


def test_per_optimizer_share_time_and_costs_against_the_ga_on_the_same_windows():
    rows = [{**_row(10.0, 8.0), "windows": [_windowed("certified", 5.0, 5.01, 0.02, 0.001),
                                            _windowed("ga", 4.0, 4.0, 0.2, action=1)],
             "refined_actions": [["a", 4.0], ["b", 4.0]]},
            {**_row(11.0, 8.5), "windows": [_windowed("certified", 6.003, 6.0, 0.04, 0.002),
                                            _windowed("analytic", 3.0, 3.0, 0.005, 0.0, action=1)],
             "refined_actions": [["a", 4.0], ["b", 4.0]]}]
    s = summarize_comparison(rows)["optimizers"]
    assert sorted(s) == ["analytic", "certified", "ga"]
    assert s["certified"]["share"] == 0.5 and s["certified"]["median_ms"] == pytest.approx(30.0)
    assert s["certified"]["gap_share_max"] == pytest.approx(0.002 / 6.003)
    v = s["certified"]["vs_ga"]
    assert (v["windows"], v["below_ga"], v["above_ga_by_more_than_0.1%"]) == (2, 1, 0)
    assert v["above_ga_max"] == pytest.approx(0.0005)
    assert "vs_ga" not in s["ga"] and s["ga"]["certified_windows"] == 0


def test_execution_waits_only_for_what_the_optimizer_takes_beyond_the_action_before():
    """Each window is refined while the action before it executes: the first window delays the start, a later
    one only where it takes longer than the action before it."""
    from tailor.refinement.evaluation.experiments import _wait_share

    row = {"refined_actions": [["a", 2.0], ["b", 1.0], ["c", 1.0]],
           "windows": [{"action": 0, "seconds": 0.1}, {"action": 1, "seconds": 0.5}, {"action": 2, "seconds": 1.5}]}
    assert _wait_share(row) == pytest.approx((0.1 + 0.0 + 0.5) / 4.0)


def test_per_action_tables_keep_asserted_sequences_apart():
    """Assertion inserts an action in some situations of a problem: Table 5.2 has a table per executed sequence
    (the most frequent first), never a step of one sequence averaged with another's (nor an index error)."""
    plain = [("goToPose", 4.0), ("dribbleBall", 12.0)]
    asserted = [("goToPose", 3.0), ("goToPose", 2.0), ("dribbleBall", 10.0)]
    rows = [{**_row(16.0, 15.0), "greedy_actions": plain, "refined_actions": [("goToPose", 5.0), ("dribbleBall", 10.0)]},
            {**_row(15.0, 15.0), "greedy_actions": asserted, "refined_actions": asserted},
            {**_row(16.0, 14.0), "greedy_actions": plain, "refined_actions": [("goToPose", 3.0), ("dribbleBall", 11.0)]}]
    table = summarize_comparison(rows)["per_action"]
    assert [(r["step"], r["action"], r["situations"], r["greedy_mean"], r["refined_mean"]) for r in table] == [
        (1, "goToPose", 2, 4.0, 4.0), (2, "dribbleBall", 2, 12.0, 10.5),
        (1, "goToPose", 1, 3.0, 3.0), (2, "goToPose", 1, 2.0, 2.0), (3, "dribbleBall", 1, 10.0, 10.0)]


def test_the_evaluation_plan_and_refinement_defaults_are_typed_data_in_the_binding():
    soccer = load_domain_binding(DOMAINS_DIR / "soccer")
    assert soccer.require_evaluation() == EvaluationPlan("score", "waypoints", "approach")
    assert soccer.refinement == RefinementDefaults(filter=False, neighbourhood=0.02, zero_baseline=False)
    assert load_domain_binding(DOMAINS_DIR / "arm").refinement.zero_baseline is True
    head = 'schema = 2\nsimulator = "soccer"\n'
    for table, message in (("", r"\[evaluation\] missing"),
                           ('[evaluation]\ncomparison = "tour"\n',
                            r"\[evaluation\] comparison = 'tour' is not a situation generator of simulator 'soccer' "
                            r"\(known: score, score_anywhere, waypoints, approach, approach_far_side\)"),
                           ('[evaluation]\ncomparison = "score"\nhorizon = "waypoints"\n',
                            r"\[evaluation\] unknown key 'horizon'"),
                           ('[refinement]\nzero_baseline = 1\n',
                            r"\[refinement\] zero_baseline must be true or false, not 1"),
                           ('[refinement]\nneighbourhood = -0.1\n',
                            r"\[refinement\] neighbourhood must be a share of each free range in \[0, 0.5\), not -0.1"),
                           ('[refinement]\nneighborhood = 0.1\n', r"\[refinement\]: unknown key 'neighborhood'"),
                           ('[evaluation]\ncomparison = "score"\nfilter = true\n[refinement]\nfilter = false\n',
                            r"\[evaluation\] filter and \[refinement\] filter both given")):
        with pytest.raises(BindingError, match=r"^e.toml: " + message):
            parse_binding(tomllib.loads(head + table), "e.toml").require_evaluation()
    # a binding written before [refinement] existed still reads: its keys in [evaluation] are refinement defaults
    old = parse_binding(tomllib.loads(head + '[evaluation]\ncomparison = "waypoints"\nzero_baseline = true\n'))
    assert old.require_evaluation() == EvaluationPlan("waypoints", None, None)
    assert old.refinement == RefinementDefaults(zero_baseline=True)


def test_horizon_statistics_compare_each_horizon_with_greedy_and_the_previous():
    rows = [{f"h{h}": t, f"h{h}_ok": True, f"h{h}_methods": ["analytic"]} for h, t in ((1, 20.0), (2, 18.0))]
    rows = [{"problem": "waypoints", **rows[0], **rows[1]},
            {"problem": "waypoints", "h1": 10.0, "h1_ok": True, "h1_methods": ["analytic"], "h2": 9.0,
             "h2_ok": True, "h2_methods": ["ga"]}]
    w = summarize_horizons(rows, (1, 2))
    assert (w["episodes"], w["scenarios"], w["problems"]) == (2, 2, ["waypoints"])
    assert [h["mean"] for h in w["horizons"]] == [15.0, 13.5]
    assert w["horizons"][1]["improvement"] == pytest.approx(0.1)
    assert w["horizons"][1]["methods"] == ["analytic", "ga"]


def test_tiny_evaluation_end_to_end(capsys):
    assert main(["evaluate", "soccer", "--episodes", "3", "--oracle-episodes", "1", "--horizon-episodes", "1",
                 "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    for key in ("episodes", "greedy_mean", "refined_mean", "improvement", "p_value", "better", "equal", "worse",
                "oracle_ratio", "horizons"):
        assert key in report
    assert (report["domain"], report["simulator"], report["comparison"]) == ("soccer", "soccer", "score")
    assert report["scenarios"] == 3 and report["problems"] == ["score"]
    assert report["horizon_situations"] == "waypoints" and report["horizons"]["problems"] == ["waypoints"]
    assert report["better"] + report["equal"] + report["worse"] == report["episodes"] <= 3
    assert report["oracle_episodes"] <= 1 and [h["horizon"] for h in report["horizons"]["horizons"]] == [1, 2, 3, 4]
    if report["oracle_episodes"]:
        assert report["oracle_ratio"] > 0.9  # the grid optimum is a real simulated time, near the refined one


def test_a_small_evaluation_runs_as_many_horizon_situations_as_episodes(monkeypatch, capsys):
    """Without --horizon-episodes the horizons run on 100 situations, or on --episodes where that is fewer (a
    two-episode run of the arm took minutes on 100 letters)."""
    from tailor.sims import parallel as progress

    asked = []

    class Stop(Exception):
        pass

    def run_in_workers(function, items, jobs, desc, *args, **kwargs):
        if desc.startswith("horizons"):
            asked.append(len(items))
            raise Stop
        return []  # (the comparison's episodes are not what this is about)

    monkeypatch.setattr(progress, "run_in_workers", run_in_workers)
    with pytest.raises(Stop):
        main(["-q", "evaluate", "soccer", "--episodes", "2", "--oracle-episodes", "0"])
    assert asked == [2]


def test_a_share_that_is_not_known_prints_as_a_dash_not_as_dash_percent(capsys):
    """Issue 32: `evaluate` printed "-%" where a share had no value (too few situations)."""
    from tailor.cli.evaluate import _pct

    assert (_pct(None), _pct(0.1234)) == ("-", "12.3%")
    assert main(["-q", "evaluate", "soccer", "--episodes", "1", "--oracle-episodes", "0", "--horizon-episodes", "1"]) == 0
    out = capsys.readouterr().out
    assert "-%" not in out and "%" in out
