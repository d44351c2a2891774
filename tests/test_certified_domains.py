"""The certified optimizer on the bundled domains' own problems: their feature spaces declare bounds, so it runs
and certifies their windows (the robust objective of soccer's `score` included), and its lower bound is never
above the genetic algorithm's choice on the same window (a certificate the GA could beat would be false)."""

from __future__ import annotations

import pytest
import tailor
from tailor.refinement.optimizers import certified

SLACK = 1e-9


@pytest.mark.parametrize(("domain", "problem"), [("arm", "letter-l"), ("kitchen", "scenario1"), ("soccer", "score")])
def test_the_bundled_problems_windows_are_certified(domain, problem):
    refined = tailor.refine(domain, problem, optimizer="certified").refined
    assert refined.windows and all(w.method == "certified" for w in refined.windows)
    assert all(w.gap <= certified.tolerance_of(w.cost) for w in refined.windows)
    first = tailor.refine(domain, problem, optimizer="ga").refined.windows[0]  # the same first window
    assert refined.windows[0].lower_bound <= first.cost + SLACK * (1 + abs(first.cost))
    assert refined.windows[0].cost <= first.cost * (1 + 1e-3)


def test_auto_certifies_a_letter_of_the_arm_and_says_so():
    windows = tailor.refine("arm", "letter-l").refined.windows
    assert [w.method for w in windows] == ["certified", "certified"]
    assert all("branch and bound" in w.note and "analytic not applicable" in w.note for w in windows)
