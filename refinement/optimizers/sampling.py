"""Random sampling of the free parameters (the third optimizer, for comparison with Sec. 5.4.2-5.4.3).

Where a term marks parameterizations invalid (Alg. 6: predicted failure), samples are drawn by rejection: more
batches are drawn until SAMPLES valid ones are in hand (as Sec. 6.2 samples a thousand states from the success
set), at most MAX_BATCHES batches."""

from __future__ import annotations

import time

import numpy as np

from tailor.refinement.optimizers.objective import Objective, OptimizationResult

SAMPLES = 1000
MAX_BATCHES = 20


def minimize(objective: Objective, seed: int = 0) -> OptimizationResult:
    """Best of SAMPLES valid uniform draws within the ranges (rejection sampling; one objective call a batch)."""
    start = time.perf_counter()
    rng = np.random.default_rng(seed)
    thetas, costs, valids = [], [], []
    n_valid = 0
    while n_valid < SAMPLES and len(thetas) < MAX_BATCHES:
        theta = rng.uniform(objective.low, objective.high, size=(SAMPLES, len(objective.free)))
        valid = objective.valid(theta)
        thetas.append(theta)
        valids.append(valid)
        costs.append(objective.robust_cost(theta))
        n_valid += int(valid.sum())
    theta, cost, valid = np.concatenate(thetas), np.concatenate(costs), np.concatenate(valids)
    best = int(np.lexsort((cost, ~valid))[0])
    note = "" if valid.all() else f"rejection: {int(valid.sum())} of {len(valid)} draws valid"
    if not valid[best]:
        note = "no valid parameterization found"
    if any(objective.neighbourhood):
        note = "; ".join(filter(None, [note, "worst case over the neighbourhood"]))
    return OptimizationResult(
        values=tuple(float(v) for v in theta[best]),
        cost=float(cost[best]),
        method="sample",
        evaluations=len(theta),
        seconds=time.perf_counter() - start,
        note=note,
    )
