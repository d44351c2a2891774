"""Refinement's shared feature batches (refine.LastBatch, Objective.cost with `inputs` and `derive`): the same
costs as evaluating every term alone, each distinct parameter row computed once, and the rows of the batch
before reused (the genetic algorithm's offspring keep their parents' values)."""

from __future__ import annotations

import numpy as np

from tailor.refinement.optimizers import FreeParameter, Objective, Term
from tailor.refinement.refine import LastBatch


class CountingFeatures:
    """A row-wise feature function that records how many rows it was asked for."""

    def __init__(self):
        self.rows = 0
        self.calls = 0

    def __call__(self, params: np.ndarray) -> np.ndarray:
        self.rows += len(params)
        self.calls += 1
        return np.column_stack([params.sum(axis=1), np.sin(params[:, 0]) * params[:, -1]])


class Linear:
    def predict(self, features: np.ndarray) -> np.ndarray:
        return features @ np.array([1.5, -0.25]) + 0.1


def test_last_batch_equals_the_function_and_computes_each_new_row_once():
    function = CountingFeatures()
    batch = LastBatch(function)
    rng = np.random.default_rng(0)
    first = rng.normal(size=(6, 3))
    rows = first[[0, 1, 1, 2, 0, 3, 4, 5, 5]]
    np.testing.assert_array_equal(batch(rows), CountingFeatures()(rows))
    assert function.rows == 6  # the 6 distinct rows, not 9
    fresh = rng.normal(size=(2, 3))
    later = np.vstack([first[[5, 2]], fresh, first[[2]]])
    np.testing.assert_array_equal(batch(later), CountingFeatures()(later))
    assert function.rows == 6 + 2  # rows 5 and 2 came from the batch before
    again = np.vstack([first[[0]], fresh[[1]]])  # row 0 was not in the last batch: computed again
    np.testing.assert_array_equal(batch(again), CountingFeatures()(again))
    assert function.rows == 6 + 2 + 1
    np.testing.assert_array_equal(batch(np.empty((0, 3))), np.empty((0, 2)))


def _terms(shared: bool):
    """Three actions of one model reading overlapping columns of theta (a chain of subgoals), and a fourth of
    another model; with `shared`, the first three share one derive."""
    counting = CountingFeatures()
    derive = LastBatch(counting)
    model, other = Linear(), Linear()

    def reads(*columns):
        return lambda theta: np.column_stack([np.atleast_2d(theta)[:, j] for j in columns] + [np.ones(len(theta))])

    terms = []
    for columns in ((0, 1, 1), (0, 1, 2), (2, 3, 3)):  # (an action model reads rows of one width)
        inputs = reads(*columns)
        terms.append(Term(model, lambda theta, i=inputs: derive(i(theta)), inputs=inputs if shared else None,
                          derive=derive if shared else None))
    lone = reads(1, 3)
    terms.append(Term(other, lambda theta: CountingFeatures()(lone(theta))))
    return terms, counting


def test_terms_sharing_a_derive_cost_what_each_alone_costs_in_one_call():
    free = tuple(FreeParameter(f"p{j}", -1.0, 1.0) for j in range(4))
    theta = np.random.default_rng(1).uniform(-1, 1, (50, 4))
    shared_terms, shared_counts = _terms(shared=True)
    alone_terms, alone_counts = _terms(shared=False)
    shared = Objective(free, tuple(shared_terms)).cost(theta)
    alone = Objective(free, tuple(alone_terms)).cost(theta)
    expected = sum(term.model.predict(term.features(theta)) for term in alone_terms)
    np.testing.assert_array_equal(shared, alone)
    np.testing.assert_allclose(shared, expected)
    assert shared_counts.calls == 1 and alone_counts.calls == 3 + 3  # (the sum above called each term again)
    radius = (0.1, 0.1, 0.1, 0.1)
    robust = Objective(free, tuple(shared_terms), neighbourhood=radius).robust_cost(theta)
    np.testing.assert_array_equal(robust, Objective(free, tuple(alone_terms), neighbourhood=radius).robust_cost(theta))
