"""Random sampling of the free parameters (the third optimizer, for comparison with Sec. 5.4.2-5.4.3)."""

from __future__ import annotations

import time

import numpy as np

from tailor.refinement.optimizers.objective import Objective, OptimizationResult

SAMPLES = 1000


def minimize(objective: Objective, seed: int = 0) -> OptimizationResult:
    """Best valid one of SAMPLES uniform draws within the ranges (one vectorized objective call)."""
    start = time.perf_counter()
    rng = np.random.default_rng(seed)
    theta = rng.uniform(objective.low, objective.high, size=(SAMPLES, len(objective.free)))
    cost = objective.cost(theta)
    valid = objective.valid(theta)
    best = int(np.lexsort((cost, ~valid))[0])
    return OptimizationResult(
        values=tuple(float(v) for v in theta[best]),
        cost=float(cost[best]),
        method="sample",
        evaluations=SAMPLES,
        seconds=time.perf_counter() - start,
        note="" if valid[best] else "no valid parameterization found",
    )
