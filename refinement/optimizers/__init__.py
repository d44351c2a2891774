"""Optimizers of the free parameters of an action sequence (Sec. 5.4), looked up by name in OPTIMIZERS.

`optimize(objective, method, seed)` runs one; "analytic" minimizes the merged model trees exactly (App. C.3)
and falls back to the genetic algorithm, saying why in the result's note, where the free parameters do not
enter the features piecewise affinely (C.3.4).
"""

from __future__ import annotations

import logging
import time
from dataclasses import replace
from typing import Callable

import numpy as np

from tailor.errors import EmptyRangeError, TailorError
from tailor.refinement.optimizers import analytic, genetic, sampling
from tailor.refinement.optimizers.objective import (
    FreeParameter,
    Objective,
    OptimizationResult,
    Term,
    brute_force,
)
from tailor.refinement.optimizers.structure import NotApplicable

log = logging.getLogger(__name__)

__all__ = [
    "OPTIMIZERS",
    "FreeParameter",
    "Objective",
    "OptimizationResult",
    "Term",
    "brute_force",
    "optimize",
]


def _analytic_or_ga(objective: Objective, seed: int = 0) -> OptimizationResult:
    """Analytic minimization where the models are mergeable, the genetic algorithm otherwise."""
    start = time.perf_counter()
    try:
        return analytic.minimize(objective, seed)
    except NotApplicable as why:
        log.debug("analytic minimization not applicable (%s): the genetic algorithm instead", why)
        result = genetic.minimize(objective, seed)
        return replace(result, seconds=time.perf_counter() - start,
                       note=f"analytic not applicable: {why}" + (f"; {result.note}" if result.note else ""))


OPTIMIZERS: dict[str, Callable[[Objective, int], OptimizationResult]] = {
    "analytic": _analytic_or_ga,
    "ga": genetic.minimize,
    "sample": sampling.minimize,
}


def optimize(objective: Objective, method: str = "analytic", seed: int = 0) -> OptimizationResult:
    """Choose the free parameters of `objective` minimizing its summed predicted duration."""
    if method not in OPTIMIZERS:
        raise TailorError(f"unknown optimizer {method!r}; choose one of {', '.join(OPTIMIZERS)}")
    for p in objective.free:
        if not (np.isfinite(p.low) and np.isfinite(p.high) and p.low <= p.high):
            raise EmptyRangeError(
                f"free parameter {p.id} has an empty or unbounded range [{p.low}, {p.high}]"
            )
    if not objective.free:  # everything bound: nothing to choose
        start = time.perf_counter()
        cost = float(objective.cost(np.zeros((1, 0)))[0])
        return OptimizationResult((), cost, method, 1, time.perf_counter() - start, "no free parameters")
    return OPTIMIZERS[method](objective, seed)
