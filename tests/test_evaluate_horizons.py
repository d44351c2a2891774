"""Issue 32: `tailor evaluate` listed h=3 and h=4 for a two-action problem. A horizon longer than a sequence is
its length: it is refined once per situation, and a horizon longer than every sequence is not reported."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from tailor.refinement.evaluation import experiments
from tailor.refinement.evaluation.experiments import (distinct_horizons, effective_horizon, horizon_episode,
                                                     horizon_rows, summarize_horizons)


def test_a_horizon_longer_than_the_sequence_is_its_length():
    assert [effective_horizon(h, 2) for h in (1, 2, 3, 4)] == [1, 2, 2, 2]
    assert effective_horizon(3, 0) == 1  # (an empty sequence: greedy)
    rows = [{"actions": 2}, {"actions": 3}]
    assert distinct_horizons(rows, (1, 2, 3, 4)) == (1, 2, 3)  # h=3 differs in the longer situation
    assert distinct_horizons([{"actions": 2}], (1, 2, 3, 4)) == (1, 2)
    assert distinct_horizons([{"actions": 1}], (1, 2, 3, 4)) == (1,)


def test_each_effective_horizon_is_refined_once_and_marked(monkeypatch):
    """A two-action situation run with horizons 1-4: two refinements (h=1, h=2), h=3 and h=4 repeat h=2's
    results; the summary counts, per horizon, the situations with fewer actions."""
    asked = []

    def refine_stage(sequence, models, success, options):
        asked.append(options.horizon)
        refined = SimpleNamespace(predicted_total=10.0 - options.horizon, windows=[SimpleNamespace(method="analytic")])
        simulated = SimpleNamespace(duration=20.0 - options.horizon, succeeded=True, results=[])
        return SimpleNamespace(refined=SimpleNamespace(refined=refined, simulated=simulated))

    monkeypatch.setattr(experiments, "asserted_situation", lambda job, objects: (SimpleNamespace(actions=[1, 2]), {}))
    monkeypatch.setattr(experiments, "job_models", lambda job, sequence: {})
    monkeypatch.setattr(experiments, "refine_stage", refine_stage)
    job = SimpleNamespace(seed=0, plan=SimpleNamespace(problem="two"))
    row = horizon_episode(job, 0, {}, (1, 2, 3, 4))
    assert asked == [1, 2]
    assert row["actions"] == 2 and row["h3"] == row["h4"] == row["h2"] == 18.0
    shown = distinct_horizons([row], (1, 2, 3, 4))
    assert shown == (1, 2)
    summary = summarize_horizons([row, {**row, "actions": 4, "h1": 21.0}], (1, 2, 3, 4))
    assert [h["shorter"] for h in summary["horizons"]] == [0, 0, 1, 1]
    assert summary["horizons"][3]["improvement_over_previous"] == pytest.approx(0.0)
    listed = horizon_rows([row], {0: {}}, shown)[0]
    assert listed["actions"] == 2 and [h["effective"] for h in listed["horizons"]] == [1, 2]
    assert [h["effective"] for h in horizon_rows([row], {}, (1, 2, 3, 4))[0]["horizons"]] == [1, 2, 2, 2]
