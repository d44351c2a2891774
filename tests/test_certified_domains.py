"""The certified optimizer on the bundled domains' own problems: their feature spaces declare bounds, so it runs
and certifies their windows (the robust objective of soccer's `score` included; the kitchen's first), and
its lower bound is never above the genetic algorithm's choice on the same window (a certificate the GA could beat
would be false)."""

from __future__ import annotations

import pytest
import tailor
from tailor.refinement.optimizers import certified

SLACK = 1e-9


@pytest.mark.parametrize(("domain", "problem", "certifies"), [("arm", "letter-l", (True, True)),
                                                         ("kitchen", "scenario1", (True, False, False)),
                                                         ("soccer", "score", (True,))])
def test_the_bundled_problems_windows_are_certified(domain, problem, certifies):
    """Each window certified within the tolerance, but the kitchen's second and last (the crossing and the
    navigate from the door, then put): with each navigate's cruise speed free their boxes close too slowly for
    the budget (the last's optimum also lies at a jump of the navigate tree); the gap is then stated, and the
    lower bound is still no false certificate."""
    refined = tailor.refine(domain, problem, optimizer="certified").refined
    assert refined.windows and all(w.method == "certified" for w in refined.windows)
    assert [w.gap <= certified.tolerance_of(w.cost) for w in refined.windows] == list(certifies)
    assert all("budget of 200000 boxes spent" in w.note for w, ok in zip(refined.windows, certifies) if not ok)
    ga = tailor.refine(domain, problem, optimizer="ga").refined.windows
    assert refined.windows[0].lower_bound <= ga[0].cost + SLACK * (1 + abs(ga[0].cost))  # the same first window
    assert refined.windows[0].cost <= ga[0].cost * (1 + 1e-3)


def test_every_kitchen_window_bounds_the_genetic_algorithm_on_the_same_window():
    """The windows after the first see the choices made before them: `compare` runs the genetic algorithm on
    each window as the certified optimizer saw it, the one it does not certify included."""
    from tailor.planner_bridge import resolve_problem
    from tailor.refinement.models.action_models import load_action_models
    from tailor.refinement.refine import refine
    from test_picture_labels import _sequence

    models = load_action_models(resolve_problem("kitchen", "scenario1")[0].parent / "models")
    refined = refine(_sequence("kitchen", "scenario1"), models, horizon=2, method="certified", risk=1.0,
                     compare="ga")
    assert len(refined.windows) == len(refined.compared) == 3
    for window, ga in zip(refined.windows, refined.compared):
        assert ga.method == "ga" and window.lower_bound <= ga.cost + SLACK * (1 + abs(ga.cost))


def test_auto_certifies_a_letter_of_the_arm_and_says_so():
    windows = tailor.refine("arm", "letter-l").refined.windows
    assert [w.method for w in windows] == ["certified", "certified"]
    assert all("branch and bound" in w.note and "analytic not applicable" in w.note for w in windows)
