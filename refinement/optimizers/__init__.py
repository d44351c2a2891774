"""Optimizers of the free parameters of an action sequence (Sec. 5.4), looked up by name in OPTIMIZERS.

`optimize(objective, method, seed)` runs one. "auto", the default, runs the fastest that applies and says in
the result's note why each other did not: the analytic minimization of the merged model trees (App. C.3) where
every feature is piecewise affine in one free parameter (C.3.4); else the certified branch and bound over the
features' bounds (certified.py) within a budget of boxes; else, or where that budget ends before the gap is
within its tolerance, the genetic algorithm (the better choice kept, the certified lower bound still given).
"analytic" and "certified" alone fall back to the genetic algorithm where they do not apply.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np
from tailor.errors import EmptyRangeError, TailorError
from tailor.refinement.optimizers import analytic, certified, genetic, sampling
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
    "DEFAULT_OPTIMIZER",
    "OPTIMIZERS",
    "FreeParameter",
    "Objective",
    "OptimizationResult",
    "Term",
    "brute_force",
    "optimize",
]


# auto's budget of the certified optimizer before the genetic algorithm runs, in boxes (not a clock: the same
# window gets the same choice on any machine, which golden files and `tailor evaluate`'s pairing of each window
# with the GA's rely on): AUTO_BUDGET for up to AUTO_FREE free parameters (the bundled windows of 4 free
# parameters need up to 37,000 boxes, 0.3 s), divided by AUTO_WIDE for each one more (no bundled window of 6
# free parameters measured closed its gap in 40,000 boxes: 625 cost one of the costlier ones 0.07 s), and at most
# AUTO_ROWS boxes times stencil rows under a neighbourhood (each box is bounded once per offset: the bundled
# robust windows that close need 2,000-8,000 boxes of 9 rows); and none where closing the gap within that budget
# would take it falling faster than certified.FASTEST / n halvings per doubling of the boxes while they are wide
# (n free parameters; judged from 64 boxes on, no window measured that closes is given up so: the chains of four
# or six free parameters whose gap stays above 1000% for thousands of boxes stop after 64 to 450 boxes, the
# other bundled windows of six free parameters after 64), where it stalls, or where closing it looks
# like taking more than AUTO_PROSPECT boxes (certified.minimize's prospect, judged from 500 boxes on: the windows
# that closed looked like at most 270,000 after 2,000 boxes; those near a jump of the planned path or an unbounded
# guard like millions)
AUTO_BUDGET = 40_000
AUTO_FREE = 4
AUTO_WIDE = 8
AUTO_ROWS = 100_000
AUTO_PROSPECT = 1_000_000


def auto_budget(free: int, rows: int = 1) -> int:
    """The boxes auto lets the certified optimizer bound in a window of `free` free parameters whose boxes are each
    bounded over `rows` stencil rows (1 without a neighbourhood)."""
    return min(AUTO_BUDGET // AUTO_WIDE ** max(0, free - AUTO_FREE), AUTO_ROWS // max(1, rows))


def _with_ga(objective: Objective, seed: int, start: float, notes: list[str]) -> OptimizationResult:
    """The genetic algorithm's result, its note after `notes` (why the others did not run)."""
    result = genetic.minimize(objective, seed)
    return replace(result, seconds=time.perf_counter() - start, note="; ".join(notes + [result.note]))


def _or_ga(name: str, minimize) -> Callable[[Objective, int], OptimizationResult]:
    """`minimize` where it applies, the genetic algorithm otherwise (the note says why)."""

    def run(objective: Objective, seed: int = 0) -> OptimizationResult:
        start = time.perf_counter()
        try:
            return minimize(objective, seed)
        except NotApplicable as why:
            log.debug("%s not applicable (%s): the genetic algorithm instead", name, why)
            return _with_ga(objective, seed, start, [f"{name} not applicable: {why}"])

    run.__doc__ = f"{name} where it applies, the genetic algorithm otherwise."
    return run


_analytic_or_ga = _or_ga("analytic", analytic.minimize)
_certified_or_ga = _or_ga("certified", certified.minimize)


def auto(objective: Objective, seed: int = 0) -> OptimizationResult:
    """Analytic where it applies, else certified within auto_budget boxes (and AUTO_PROSPECT), else (or where the
    gap is still above the tolerance) the genetic algorithm; the note says which ran and why each other did not."""
    start = time.perf_counter()
    notes = []
    try:
        return analytic.minimize(objective, seed)
    except NotApplicable as why:
        notes.append(f"analytic not applicable: {why}")
    try:
        rows = len(objective.offsets) if any(objective.neighbourhood) else 1
        bounded = certified.minimize(objective, seed, budget=auto_budget(len(objective.free), rows),
                                     prospect=AUTO_PROSPECT)
    except NotApplicable as why:
        notes.append(f"certified not applicable: {why}")
        log.debug("%s: the genetic algorithm instead", "; ".join(notes))
        return _with_ga(objective, seed, start, notes)
    if bounded.gap is not None and bounded.gap <= certified.tolerance_of(bounded.cost):
        return replace(bounded, seconds=time.perf_counter() - start, note="; ".join(notes + [bounded.note]))
    notes.append(f"certified: {bounded.note}: the genetic algorithm too")
    log.debug("%s", "; ".join(notes))
    result = genetic.minimize(objective, seed)
    chosen = result if result.cost < bounded.cost else bounded
    which = "the genetic algorithm's" if chosen is result else "the certified optimizer's"
    return replace(chosen, lower_bound=bounded.lower_bound, seconds=time.perf_counter() - start,
                   note="; ".join(notes + [result.note, f"{which} choice kept"]))


OPTIMIZERS: dict[str, Callable[[Objective, int], OptimizationResult]] = {
    "auto": auto,
    "analytic": _analytic_or_ga,
    "certified": _certified_or_ga,
    "ga": genetic.minimize,
    "sample": sampling.minimize,
}
DEFAULT_OPTIMIZER = "auto"


def optimize(objective: Objective, method: str = DEFAULT_OPTIMIZER, seed: int = 0) -> OptimizationResult:
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
        return OptimizationResult((), cost, method, 1, time.perf_counter() - start, "no free parameters",
                                  lower_bound=cost)
    return OPTIMIZERS[method](objective, seed)
