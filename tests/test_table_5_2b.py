"""Table 5.2(b): `tailor evaluate` reports, for the horizon sequence (soccer's four way-points), the mean duration
of each action with h = 1 (greedy) and h = 2 (refined), as Table 5.2(a) does for the comparison."""

from __future__ import annotations

import json
from types import SimpleNamespace

import pytest

from tailor.refinement.evaluation import experiments
from tailor.refinement.evaluation.experiments import horizon_episode, summarize_horizons


def test_each_horizon_keeps_its_per_action_durations_and_the_summary_averages_them(monkeypatch):
    """Four actions, horizons 1-4: per action, greedy is h=1's duration and refined h=2's, averaged over the
    situations where every horizon succeeded; each column sums to its horizon's mean (Table 5.3)."""

    calls = []

    def refine_stage(sequence, models, success, options):
        h, k = options.horizon, len(calls) // 4  # k: the situation (four horizons each)
        calls.append(h)
        results = [SimpleNamespace(action="goToPose", duration=d) for d in (4.0 + h * (1 + k), 5.0 - h, 6.0, 7.0 - h)]
        refined = SimpleNamespace(predicted_total=20.0, windows=[SimpleNamespace(method="analytic")])
        simulated = SimpleNamespace(duration=sum(r.duration for r in results), succeeded=True, results=results)
        return SimpleNamespace(refined=SimpleNamespace(refined=refined, simulated=simulated))

    monkeypatch.setattr(experiments, "asserted_situation", lambda job, objects: (SimpleNamespace(actions=[1] * 4), {}))
    monkeypatch.setattr(experiments, "job_models", lambda job, sequence: {})
    monkeypatch.setattr(experiments, "refine_stage", refine_stage)
    job = SimpleNamespace(seed=0, plan=SimpleNamespace(problem="waypoints"))
    rows = [horizon_episode(job, i, {}, (1, 2, 3, 4)) for i in range(2)]
    failed = {**rows[0], "h3_ok": False, "h1_actions": [["goToPose", 100.0]] * 4}  # not in Table 5.3: not here
    summary = summarize_horizons([*rows, failed], (1, 2, 3, 4))
    table = summary["per_action"]
    assert [(r["step"], r["action"], r["situations"]) for r in table] == [(k, "goToPose", 2) for k in (1, 2, 3, 4)]
    assert [r["greedy_mean"] for r in table] == [5.5, 4.0, 6.0, 6.0]
    assert [r["refined_mean"] for r in table] == [7.0, 3.0, 6.0, 5.0]
    means = {h["horizon"]: h["mean"] for h in summary["horizons"]}
    assert sum(r["greedy_mean"] for r in table) == pytest.approx(means[1])
    assert sum(r["refined_mean"] for r in table) == pytest.approx(means[2])


def test_evaluate_soccer_reports_table_5_2b_in_json_and_text(capsys):
    from tailor.cli import evaluate
    from tailor.cli.main import main

    assert main(["evaluate", "soccer", "--episodes", "0", "--oracle-episodes", "0", "--horizon-episodes", "1",
                 "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    horizons = data["horizons"]
    table = horizons["per_action"]
    assert [(r["problem"], r["step"], r["action"]) for r in table] == [("waypoints", k, "goToPose") for k in (1, 2, 3, 4)]
    means = {h["horizon"]: h["mean"] for h in horizons["horizons"]}
    assert sum(r["greedy_mean"] for r in table) == pytest.approx(means[1])
    assert sum(r["refined_mean"] for r in table) == pytest.approx(means[2])
    evaluate._print_text(data)  # the text report of the same numbers
    text = capsys.readouterr().out
    assert "Table 5.2(b)" in text
    lines = [line for line in text.splitlines() if line.strip().startswith("waypoints (1)")]
    assert len(lines) == 4 and all(f"{r['greedy_mean']:.2f}" in line and f"{r['refined_mean']:.2f}" in line
                                   for r, line in zip(table, lines))
