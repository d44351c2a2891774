"""Parallel work: ordered results from worker processes, and duration models fitted in workers equal to the
serial ones (the n_i x leaf-size grid and the learning curve are independent fits)."""

from __future__ import annotations

import os

import synthetic_episodes
from tailor.refinement.learning import duration_protocol as protocol
from tailor.refinement.learning.duration_protocol import train_duration_model
from tailor.sims.parallel import ordered_results

OBSERVED = ("x", "y", "phi", "v")


def pid_and_square(x: int) -> tuple[int, int]:
    return os.getpid(), x * x


def test_ordered_results_come_from_workers_in_the_order_of_the_calls():
    results = list(ordered_results(pid_and_square, [(k,) for k in range(40)], jobs=2))
    assert [square for _, square in results] == [k * k for k in range(40)]
    assert os.getpid() not in {pid for pid, _ in results}
    assert {pid for pid, _ in ordered_results(pid_and_square, [(1,), (2,)], jobs=1)} == {os.getpid()}


def test_one_by_one_hands_the_workers_single_calls_and_keeps_the_order(monkeypatch):
    import joblib

    sizes = []
    init = joblib.Parallel.__init__

    def spy(self, *args, **kwargs):
        sizes.append(kwargs.get("batch_size", "auto"))
        init(self, *args, **kwargs)

    monkeypatch.setattr(joblib.Parallel, "__init__", spy)
    results = list(ordered_results(pid_and_square, [(k,) for k in range(12)], jobs=2, one_by_one=True))
    assert [square for _, square in results] == [k * k for k in range(12)]
    assert os.getpid() not in {pid for pid, _ in results}
    list(ordered_results(pid_and_square, [(k,) for k in range(3)], jobs=2))
    assert sizes == [1, "auto"]


def test_a_duration_model_fitted_by_two_workers_is_the_serial_one(monkeypatch):
    episodes = synthetic_episodes.gather("soccer", "goToPose", 60, seed=4)
    batches = []
    results = protocol._results

    def spy(function, calls, jobs):
        batches.append((len(calls), jobs))
        return results(function, calls, jobs)

    monkeypatch.setattr(protocol, "_results", spy)
    kwargs = dict(seed=2, feature_space="pose", observed=OBSERVED, n_i_candidates=(1, 3, 5),
                  leaf_candidates=(5, 20, 40), episode_fractions=(0.5, 1.0))
    serial = train_duration_model("goToPose", episodes, jobs=1, **kwargs)
    parallel = train_duration_model("goToPose", episodes, jobs=2, **kwargs)
    assert parallel.report == serial.report
    assert parallel.model.to_json() == serial.model.to_json()
    # the n_i candidates at once, the leaf sizes not fitted yet at once, the learning curve's 2 x 2 fits at once,
    # the uncertainty's cross-fitting folds at once
    assert batches[len(batches) // 2:] == [(3, 2), (3, 2), (4, 2), (4, 2)]
