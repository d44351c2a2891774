"""The refinement objective: the summed predicted duration of the actions within the horizon (Sec. 5.4).

A free parameter is one continuous value left open by instantiation (e.g. the heading at a subgoal, shared by
the action that reaches it and the one that leaves it). A term is one action's model called on the features
that the free values induce; the objective sums the terms. Every optimizer returns an OptimizationResult: the
choice, its cost, which optimizer made it and, where one is known, a lower bound of the objective (the gap).
A term may carry an enclosure of its features over boxes of free values (`feature_bounds`): the certified
optimizer needs it for every term. A weighted objective (Ch. 8.1: duration + 0.3 * energy) is a sum of terms
too, one per action and measure, each model `scaled` by its weight (>= 0): its predictions and the linear
models of its rules multiplied, its leaves' boxes unchanged, so every optimizer minimizes it as it is.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass, replace
from functools import cached_property
from typing import Callable

import numpy as np


@dataclass(frozen=True)
class FreeParameter:
    """A free action parameter with its id (shared by the actions it links) and its closed range."""

    id: str
    low: float
    high: float


Bounds = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True, eq=False)
class Term:
    """One action's predicted duration: its action model called on features derived from the free values."""

    model: object  # predict(F) -> (n,) and rules() -> list[Rule]
    features: Callable[[np.ndarray], np.ndarray]  # theta (batch, n_free) -> (batch, n_features)
    # theta -> (batch,) bool; False where the model marks the parameterization invalid (predicted failure)
    valid: Callable[[np.ndarray], np.ndarray] | None = None
    label: str = ""
    # the predicted-success region behind `valid`, for the analytic optimizer: success_rules() -> list[Rule]
    # (axis-aligned boxes with a zero linear model) over region_features(theta) (batch, n_region_features)
    region: object | None = None
    region_features: Callable[[np.ndarray], np.ndarray] | None = None
    region_margin: tuple[float, ...] = ()  # per free parameter: how far inside the region a choice must lie
    # optional, for a batch shared with other terms: theta -> the action's parameter rows, and the (row-wise)
    # features of such rows; terms with the same `derive` and `model` are evaluated in one call of each
    # (Objective.cost), so costly features (a planned path per row) pay numpy's per-call cost once per batch
    inputs: Callable[[np.ndarray], np.ndarray] | None = None
    derive: Callable[[np.ndarray], np.ndarray] | None = None
    # optional, for the certified optimizer: a guaranteed enclosure of `features` over boxes of theta, (low, high)
    # each (k, n_free) -> (feature_low, feature_high) each (k, n_features); likewise of `region_features`;
    # `no_bounds` says why a term has none (e.g. its feature space declares none), for the optimizers' notes
    feature_bounds: Bounds | None = None
    region_bounds: Bounds | None = None
    no_bounds: str = ""
    # optional: the columns of theta the term depends on (None: any); a neighbourhood's offsets along other
    # columns leave its prediction unchanged, so `robust_cost` evaluates it on fewer points
    reads: tuple[int, ...] | None = None


@dataclass(frozen=True, eq=False)
class Objective:
    """Sum of the terms' predicted durations as a function of the free parameters."""

    free: tuple[FreeParameter, ...]
    terms: tuple[Term, ...]
    # per free parameter: how far from every split of a term's model a choice must lie (knife-edge optima: a
    # value on a split may predict another leaf's time once perturbed by execution noise or rounding); the
    # analytic optimizer keeps it inside every leaf box, () keeps none
    margin: tuple[float, ...] = ()
    # per free parameter: the radius of the neighbourhood a choice is judged by (execution noise): with it the
    # optimizers minimize `robust_cost`, the worst predicted cost within it; () judges each point alone
    neighbourhood: tuple[float, ...] = ()

    @property
    def low(self) -> np.ndarray:
        return np.array([p.low for p in self.free], dtype=float)

    @property
    def high(self) -> np.ndarray:
        return np.array([p.high for p in self.free], dtype=float)

    def cost(self, theta: np.ndarray) -> np.ndarray:
        """Summed predicted duration (s) of each row of theta (batch, n_free)."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        total = np.zeros(len(theta))
        for values in self.term_values([theta] * len(self.terms)):  # summed in the terms' order
            total += values
        return total

    def term_values(self, points: list[np.ndarray]) -> list[np.ndarray]:
        """Each term's prediction at rows of theta of its own (`points[i]` for term i); terms with the same
        `derive` and `model` in one call of each."""
        predicted: dict[int, np.ndarray] = {}
        for group in self._shared_batches:
            model, derive = self.terms[group[0]].model, self.terms[group[0]].derive
            rows = np.concatenate([self.terms[i].inputs(points[i]) for i in group])
            ends = np.cumsum([len(points[i]) for i in group])[:-1]
            for i, part in zip(group, np.split(np.asarray(model.predict(derive(rows)), dtype=float), ends)):
                predicted[i] = part
        return [predicted[i] if i in predicted else
                np.asarray(term.model.predict(term.features(points[i])), dtype=float)
                for i, term in enumerate(self.terms)]

    @cached_property
    def _shared_batches(self) -> list[list[int]]:
        """Indices of the terms evaluated as one batch: those with the same `derive` and `model` (once per
        objective, not per call: the genetic algorithm calls `cost` every generation)."""
        shared: dict[tuple[int, int], list[int]] = {}
        for i, term in enumerate(self.terms):
            if term.inputs is not None and term.derive is not None:
                shared.setdefault((id(term.model), id(term.derive)), []).append(i)
        return list(shared.values())

    @cached_property
    def offsets(self) -> np.ndarray:
        """The neighbourhood's stencil (neighbourhood_offsets): (1 + 4 n, n_free), row 0 the point itself."""
        return neighbourhood_offsets(np.asarray(self.neighbourhood, dtype=float))

    @cached_property
    def stencils(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Per term: the stencil rows that can change its prediction (the point, and the offsets along the
        columns it reads), and for every stencil row the position among them of the row giving its value."""
        offsets = self.offsets
        column = np.abs(offsets).argmax(axis=1)  # the column each offset moves (row 0: none)
        out = []
        for term in self.terms:
            if term.reads is None:
                out.append((np.arange(len(offsets)), np.arange(len(offsets))))
                continue
            use = np.flatnonzero(np.isin(column, term.reads) & (np.arange(len(offsets)) > 0))
            use = np.concatenate([[0], use])
            position = np.zeros(len(offsets), dtype=int)
            position[use] = np.arange(len(use))
            out.append((use, position))
        return out

    def robust_cost(self, theta: np.ndarray) -> np.ndarray:
        """The worst summed predicted duration (s) within the neighbourhood of each row of theta: over the
        point and, per free parameter, half and all the radius to either side (kept within the ranges). The
        point where the models predict a dip narrower than the execution noise is not a subgoal the robot can
        hit: this is what the optimizers minimize when the objective has a neighbourhood. Each term is
        evaluated only where it can change (`Term.reads`): the same sums as over the whole stencil."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        if not any(self.neighbourhood):
            return self.cost(theta)
        offsets = self.offsets
        moved = np.clip(theta[:, None, :] + offsets[None], self.low, self.high)  # (m, S, n)
        m, n = theta.shape
        stencils = self.stencils
        values = self.term_values([moved[:, use].reshape(-1, n) for use, _ in stencils])
        total = np.zeros((m, len(offsets)))
        for (use, position), v in zip(stencils, values):  # summed in the terms' order
            total += v.reshape(m, len(use))[:, position]
        return total.max(axis=1)

    def valid(self, theta: np.ndarray) -> np.ndarray:
        """True where no term's model marks the parameterization invalid (e.g. a predicted failure)."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        ok = np.ones(len(theta), dtype=bool)
        for term in self.terms:
            if term.valid is not None:
                ok &= np.asarray(term.valid(theta), dtype=bool)
        return ok


class Scaled:
    """A model (`predict`, `rules`) times a weight >= 0: what a weighted measure adds to the objective. Its rules
    are the model's with coefficients and intercept multiplied (the same leaf boxes), so the analytic
    minimization and the certified bounds (min of w * f is w * min f for w >= 0) hold for it unchanged."""

    def __init__(self, model, weight: float) -> None:
        if not (math.isfinite(weight) and weight >= 0):
            raise ValueError(f"a measure's weight must be a finite number >= 0, not {weight!r}")
        self.model, self.weight = model, float(weight)

    def predict(self, X) -> np.ndarray:
        return self.weight * np.asarray(self.model.predict(X), dtype=float)

    def rules(self) -> list:
        return [replace(rule, coef=self.weight * np.asarray(rule.coef, dtype=float),
                        intercept=self.weight * float(rule.intercept)) for rule in self.model.rules()]


_scaled: weakref.WeakKeyDictionary[object, dict[float, Scaled]] = weakref.WeakKeyDictionary()


def scaled(model, weight: float):
    """`model` times `weight`: the model itself at weight 1, else one Scaled per (model, weight), so that the
    optimizers' caches of its rules last across windows (a model that cannot be weakly referenced gets a new one)."""
    if weight == 1:
        return model
    try:
        per_weight = _scaled.setdefault(model, {})
    except TypeError:
        return Scaled(model, weight)
    if float(weight) not in per_weight:
        per_weight[float(weight)] = Scaled(model, weight)
    return per_weight[float(weight)]


def neighbourhood_offsets(radius: np.ndarray) -> np.ndarray:
    """(1 + 4 n, n) offsets of a neighbourhood stencil: none, and half and all of each radius to either side."""
    steps = [np.zeros(len(radius))]
    for j, r in enumerate(radius):
        if r > 0:
            for share in (-1.0, -0.5, 0.5, 1.0):
                step = np.zeros(len(radius))
                step[j] = share * r
                steps.append(step)
    return np.array(steps)


@dataclass(frozen=True)
class OptimizationResult:
    """The chosen free values (in the order of Objective.free), their predicted cost, how they were found."""

    values: tuple[float, ...]
    cost: float
    method: str  # the optimizer whose choice this is (analytic and auto may fall back to "ga")
    evaluations: int  # parameterizations whose cost was evaluated
    seconds: float
    note: str = ""  # e.g. why analytic fell back to the genetic algorithm
    # a lower bound of the objective over every valid parameterization (the certified optimizer's bound, or the
    # analytic minimum over the merged rules); None: unknown (the genetic algorithm and sampling give none)
    lower_bound: float | None = None

    @property
    def gap(self) -> float | None:
        """How far the choice may be above the optimum of the models (s): cost - lower bound; None if unknown."""
        if self.lower_bound is None or not np.isfinite(self.cost):
            return None
        return max(0.0, float(self.cost - self.lower_bound))

    @property
    def gap_share(self) -> float | None:
        """The gap as a share of the cost; None if unknown."""
        gap = self.gap
        if gap is None:
            return None
        return gap / abs(self.cost) if self.cost else (0.0 if gap == 0 else float("inf"))


def brute_force(objective: Objective, points_per_dim: int) -> OptimizationResult:
    """Best valid point of a regular grid over the free ranges (endpoints included); the reference optimum."""
    import time

    start = time.perf_counter()
    axes = [np.linspace(p.low, p.high, points_per_dim) for p in objective.free]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(axes))
    cost = objective.cost(grid)
    cost = np.where(objective.valid(grid), cost, np.inf)
    best = int(np.argmin(cost))
    return OptimizationResult(
        values=tuple(float(v) for v in grid[best]),
        cost=float(cost[best]),
        method="grid",
        evaluations=len(grid),
        seconds=time.perf_counter() - start,
        note="" if np.isfinite(cost[best]) else "no valid grid point",
    )
