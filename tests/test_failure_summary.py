"""`tailor evaluate` counts failures: failure rates of greedy and refined side by side, and penalized means over
every scenario (a failed run costs its time plus FAILURE_PENALTY_S), beside the means over both-succeeded ones."""

import pytest

from tailor.refinement.evaluation.experiments import FAILURE_PENALTY_S, summarize_comparison


def _row(greedy, refined, greedy_ok=True, refined_ok=True):
    return {"greedy": greedy, "refined": refined, "greedy_ok": greedy_ok, "refined_ok": refined_ok,
            "predicted_greedy": greedy, "predicted_refined": refined, "analytic_seconds": 0.0, "ga_seconds": 0.0,
            "analytic_method": "analytic", "analytic_cost": 1.0, "ga_cost": 1.0, "problem": "p"}


def test_failures_are_counted_and_penalized():
    rows = [_row(10.0, 8.0), _row(10.0, 9.0), _row(10.0, 4.0, refined_ok=False), _row(6.0, 5.0, greedy_ok=False)]
    s = summarize_comparison(rows)
    assert s["episodes"] == 2 and s["scenarios"] == 4  # the plain means keep only both-succeeded scenarios
    assert s["refined_mean"] == pytest.approx(8.5)
    assert s["failure_rate_greedy"] == 0.25 and s["failure_rate_refined"] == 0.25
    assert s["penalized_greedy_mean"] == pytest.approx((10 + 10 + 10 + 6 + FAILURE_PENALTY_S) / 4)
    assert s["penalized_refined_mean"] == pytest.approx((8 + 9 + 4 + FAILURE_PENALTY_S + 5) / 4)
    gains = [1 - 8 / 10, 1 - 9 / 10, 1 - (4 + FAILURE_PENALTY_S) / 10, 1 - 5 / (6 + FAILURE_PENALTY_S)]
    assert s["penalized_improvement"] == pytest.approx(sum(gains) / 4)
