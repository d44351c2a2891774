"""Raced feature selection (learning.feature_selection): the trials of a step and the candidate sets of the end
are fitted for the first fold, and only those close to the best there for the others; a set that finishes gets
the K-fold MAE it gets alone, so the choice is the full search's at a fraction of the fits (these tests fail
with racing switched off: every set then runs every fold)."""

from __future__ import annotations

import numpy as np
import pytest

from tailor.refinement.learning import feature_selection
from tailor.refinement.learning.feature_selection import cv_mae, race, select_features
from tailor.sims.episode import Episode
from tailor.sims.protocol import ActionSpec, Quantity, SimulatorEntry

UNITS = {"pos": Quantity("cm"), "vel": Quantity("cm/s")}
RAIL = ActionSpec("slide", "toy", ("pos", "vel"), ("target", "target_vel"), ("pos", "vel"), ("pos", "vel"))


def _entry() -> SimulatorEntry:
    return SimulatorEntry("toy", {RAIL.name: RAIL}, create=lambda seed, noise=None: None, units=UNITS)


def _rail_episodes(n: int, seed: int) -> list[Episode]:
    """A move along a rail at 1 m/s and 0.5 m/s^2 at most, from rest to rest, with a little noise."""
    rng = np.random.default_rng(seed)
    x, g = rng.uniform(0, 300, n), rng.uniform(0, 300, n)
    v, vg = rng.uniform(-40, 40, n), rng.uniform(-40, 40, n)
    d = np.abs(g - x)
    t = np.where(d < 200, 2 * np.sqrt(d / 50), 2 + (d - 200) / 100) + np.abs(v - vg) / 80 + rng.normal(0, 0.02, n)
    return [Episode("slide", np.array([x[k], v[k], g[k], vg[k]]), np.zeros(1), np.array([[x[k], v[k]]]),
                    ("pos", "vel"), "success", float(t[k]), k) for k in range(n)]


def _columns(n: int = 600, seed: int = 0) -> tuple[list[np.ndarray], np.ndarray, list[np.ndarray]]:
    rng = np.random.default_rng(seed)
    a, b, noise = rng.uniform(0, 1, n), rng.uniform(0, 1, n), rng.uniform(0, 1, (n, 3))
    y = 3 * a + np.abs(b - 0.5) + rng.normal(0, 0.01, n)
    sets = [np.column_stack([a, b]), np.column_stack([a, b, noise[:, 0]]), noise, np.column_stack([a])]
    return sets, y, np.array_split(rng.permutation(n), 3)


def test_a_set_that_finishes_the_race_has_its_exact_k_fold_mae():
    sets, y, folds = _columns()
    raced = race(sets, y, folds, leaf=10)
    for X, result in zip(sets, raced.results):
        if result is not None:
            mae, predicted = cv_mae(X, y, folds, 10)
            assert result[0] == mae and np.array_equal(result[1], predicted)  # to the last bit
    assert raced.results[0] is not None  # the best set finishes
    assert raced.results[2] is None  # noise alone is far behind after the first fold: not fitted again


def test_the_best_of_a_group_finishes_however_far_behind():
    sets, y, folds = _columns()
    raced = race(sets, y, folds, leaf=10, groups=((2,),))
    assert raced.results[2] is not None and raced.results[2][0] == cv_mae(sets[2], y, folds, 10)[0]
    assert raced.first_fold[2] > 2 * raced.first_fold[0]


def test_a_bar_leaves_every_set_behind_where_none_comes_near_it():
    sets, y, folds = _columns()
    raced = race(sets, y, folds, leaf=10, bar=0.1 * min(race(sets, y, folds, leaf=10).first_fold))
    assert all(result is None for result in raced.results)


@pytest.fixture
def fits(monkeypatch):
    """Counts the model trees the selection fits."""
    counted = []
    tree = feature_selection.ModelTree

    class Counted(tree):
        def fit(self, X, y):
            counted.append(len(y))
            return super().fit(X, y)

    monkeypatch.setattr(feature_selection, "ModelTree", Counted)
    return counted


def test_racing_keeps_the_full_searchs_choice_at_far_fewer_fits(fits, monkeypatch):
    episodes = _rail_episodes(600, 0)
    raced = select_features(RAIL, _entry(), episodes, seed=0)
    raced_fits = len(fits)
    fits.clear()
    monkeypatch.setattr(feature_selection, "RACE_MARGIN", np.inf)  # racing off: every trial runs every fold
    full = select_features(RAIL, _entry(), episodes, seed=0)
    assert [s["feature"] for s in raced.report["steps"]] == [s["feature"] for s in full.report["steps"]]
    assert [s["cv_mae"] for s in raced.report["steps"]] == [s["cv_mae"] for s in full.report["steps"]]
    assert raced.generated.names == full.generated.names
    assert raced.report["generated_sets"]["forward"] == full.report["generated_sets"]["forward"]
    assert raced_fits < 0.7 * len(fits)


def test_the_forward_sets_error_is_not_fitted_twice(monkeypatch):
    raced_sets = []

    def recorded(sets, *args, **kwargs):
        raced_sets.append(len(sets))
        return race(sets, *args, **kwargs)

    monkeypatch.setattr(feature_selection, "race", recorded)
    selection = select_features(RAIL, _entry(), _rail_episodes(300, 1), seed=1, others={})
    assert set(selection.report["generated_sets"]) | set(selection.report["raced_out"]) == \
        {"forward", "generic row", "forward and generic row"}
    assert raced_sets[-1] == 2  # the generic row, alone and joined: the forward set's MAE is its last step's
    assert selection.report["generated_sets"]["forward"] == selection.report["steps"][-1]["cv_mae"]
