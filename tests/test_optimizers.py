"""The optimizer registry and the three optimizers compared on the same objectives."""

import numpy as np
import pytest

from tailor.errors import EmptyRangeError, TailorError
from tailor.refinement.optimizers import OPTIMIZERS, FreeParameter, Objective, Term, brute_force, optimize
from tailor.refinement.optimizers.synthetic import random_objective, pose_chain


def test_registry_names():
    assert list(OPTIMIZERS) == ["auto", "analytic", "certified", "ga", "sample"]


def test_unknown_method_and_empty_range_are_clear_errors():
    objective = random_objective(np.random.default_rng(0), 1, 1)
    with pytest.raises(TailorError, match="unknown optimizer 'newton'; choose one of auto, analytic, certified, ga, "
                                          "sample"):
        optimize(objective, "newton")
    empty = Objective((FreeParameter("ball.v", 0.3, 0.0),), objective.terms)
    message = r"free parameter ball.v has an empty or unbounded range \[0.3, 0.0\]"
    with pytest.raises(EmptyRangeError, match=message):
        optimize(empty)


def test_no_free_parameters():
    model = random_objective(np.random.default_rng(0), 1, 1).terms[0].model
    fixed = np.array([[0.1, 0.2, 0.3, 0.4]])
    objective = Objective((), (Term(model, lambda theta: np.repeat(fixed, len(theta), axis=0)),))
    result = optimize(objective, "ga")
    assert result.values == () and result.cost == model.predict(fixed)[0]


@pytest.mark.parametrize("seed", range(4))
def test_no_optimizer_beats_the_analytic_minimum(seed):
    objective = pose_chain(np.random.default_rng(seed), n_leaves=60)
    best = optimize(objective, "analytic")
    assert best.method == "analytic"
    for method in ("ga", "sample"):
        result = optimize(objective, method, seed=seed)
        assert result.method == method
        assert objective.cost(np.array([result.values]))[0] == result.cost
        assert best.cost <= result.cost + 1e-9
    assert best.cost <= brute_force(objective, 301).cost + 1e-9


def test_sampling_is_seeded_and_draws_1000_points():
    objective = random_objective(np.random.default_rng(4), 2, 2)
    first = optimize(objective, "sample", seed=3)
    again = optimize(objective, "sample", seed=3)
    assert (first.values, first.cost, first.evaluations) == (again.values, again.cost, 1000)
    assert optimize(objective, "sample", seed=4).values != first.values
    theta = np.random.default_rng(3).uniform(objective.low, objective.high, size=(1000, 2))
    assert first.cost == objective.cost(theta).min()
