"""Interval bounds for the certified optimizer: a model tree's prediction over boxes of its features, and whether
a success classifier can predict success anywhere in a box.

A model tree's leaves are boxes lower < x <= upper in feature space with a linear model each (App. C.3). Over
a box [a, b] of features the prediction is at least the smallest, over the leaves the box meets, of the leaf's
linear model minimized over the intersection (at the corner its gradient points away from, C.3.1): exact for
the box, so the only slack of a bound is in the enclosure of the features. Each box carries the leaves it may
still meet (`Candidates`): a sub-box meets a subset of them, so the work shrinks with the boxes.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np
from tailor.refinement.optimizers.structure import NotApplicable

# relative slack subtracted from every bound: the predictions themselves are sums rounded to float64
ROUNDING = 1e-12
PAIRS_PER_CHUNK = 400_000  # (box, leaf) pairs examined at once


@dataclass(frozen=True, eq=False)
class LeafTable:
    """A rule set as arrays: (R, F) lower (exclusive) and upper (inclusive) bounds, coefficients, (R,) intercepts."""

    lower: np.ndarray
    upper: np.ndarray
    coef: np.ndarray
    intercept: np.ndarray


_tables: weakref.WeakKeyDictionary[object, LeafTable] = weakref.WeakKeyDictionary()
_regions: weakref.WeakKeyDictionary[object, LeafTable] = weakref.WeakKeyDictionary()


def _cached(cache, key, make):
    try:
        return cache[key]
    except (KeyError, TypeError):
        pass
    value = make()
    try:
        cache[key] = value
    except TypeError:  # a model that cannot be weakly referenced is simply not cached
        pass
    return value


def leaf_table(model) -> LeafTable:
    """The model's rules (`rules()`: a model tree, a risk-adjusted one, any rule set) as a LeafTable."""
    def make() -> LeafTable:
        rules = getattr(model, "rules", None)
        if rules is None:
            raise NotApplicable(f"a model without rules ({type(model).__name__}) cannot be bounded")
        rules = rules()
        if not rules:
            raise NotApplicable("a model without rules cannot be bounded")
        return LeafTable(np.array([r.lower for r in rules], dtype=float), np.array([r.upper for r in rules], dtype=float),
                         np.array([r.coef for r in rules], dtype=float),
                         np.array([r.intercept for r in rules], dtype=float))

    return _cached(_tables, model, make)


def success_table(region) -> LeafTable:
    """The leaves where a success classifier predicts success, unshrunk (`regions()`, or `success_rules()` where a
    region offers only those): a box that meets none of them is predicted to fail everywhere."""
    def make() -> LeafTable:
        if hasattr(region, "regions"):
            boxes = [box for box in region.regions() if box.success]
        else:
            boxes = list(region.success_rules())
        n = len(np.atleast_1d(boxes[0].lower)) if boxes else 0
        lower = np.array([b.lower for b in boxes], dtype=float).reshape(len(boxes), n)
        upper = np.array([b.upper for b in boxes], dtype=float).reshape(len(boxes), n)
        return LeafTable(lower, upper, np.zeros_like(lower), np.zeros(len(boxes)))

    return _cached(_regions, region, make)


@dataclass(frozen=True, eq=False)
class Candidates:
    """Per box, the leaves of one table it may meet: pairs (box, leaf) sorted by box."""

    box: np.ndarray  # (P,) box index
    leaf: np.ndarray  # (P,) leaf index

    @classmethod
    def every(cls, table: LeafTable, n_boxes: int) -> Candidates:
        n_leaves = len(table.intercept)
        return cls(np.repeat(np.arange(n_boxes), n_leaves), np.tile(np.arange(n_leaves), n_boxes))


def meets(table: LeafTable, pairs: Candidates, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """(P,) bool: box pairs.box, [low, high] (its rows), meets leaf pairs.leaf (lower < x <= upper)."""
    out = np.empty(len(pairs.box), dtype=bool)
    for s in range(0, len(out), PAIRS_PER_CHUNK):
        b, k = pairs.box[s:s + PAIRS_PER_CHUNK], pairs.leaf[s:s + PAIRS_PER_CHUNK]
        out[s:s + PAIRS_PER_CHUNK] = np.all((low[b] <= table.upper[k]) & (high[b] > table.lower[k]), axis=1)
    return out


def minimum(table: LeafTable, pairs: Candidates, low: np.ndarray, high: np.ndarray, n_boxes: int) -> np.ndarray:
    """(n_boxes,) lower bound of the rule set's prediction over each box [low, high] (rows of `pairs.box`),
    over the leaves `pairs` names for it: +inf where it meets none of them."""
    out = np.full(n_boxes, np.inf)
    if np.isnan(low).any() or np.isnan(high).any():  # an enclosure that says nothing bounds nothing
        out[np.isnan(low).any(axis=1) | np.isnan(high).any(axis=1)] = -np.inf
    for s in range(0, len(pairs.box), PAIRS_PER_CHUNK):
        b, k = pairs.box[s:s + PAIRS_PER_CHUNK], pairs.leaf[s:s + PAIRS_PER_CHUNK]
        inside = np.all((low[b] <= table.upper[k]) & (high[b] > table.lower[k]), axis=1)
        b, k = b[inside], k[inside]  # (the leaves a box's enclosure meets: often few of those it may meet)
        a, z = low[b], high[b]
        lower, upper, coef = table.lower[k], table.upper[k], table.coef[k]
        # the linear model's minimum over the closure of the intersection: the corner its gradient points from
        with np.errstate(invalid="ignore", over="ignore"):
            corner = np.where(coef > 0, np.maximum(a, lower), np.minimum(z, upper))
            terms = np.where(coef != 0, coef * corner, 0.0)
            value = table.intercept[k] + terms.sum(axis=1)
            value -= ROUNDING * (1.0 + np.abs(table.intercept[k]) + np.abs(terms).sum(axis=1))
        value = np.where(np.isnan(value), -np.inf, value)
        box = b
        if len(box):  # pairs come sorted by box: one minimum per run of a box
            first = np.flatnonzero(np.concatenate([[True], box[1:] != box[:-1]]))
            out[box[first]] = np.minimum(out[box[first]], np.minimum.reduceat(value, first))
    return out


def float32_hull(low: np.ndarray, high: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A box grown to hold the float32 roundings of its points too (a decision tree compares features as
    float32, and rounding is monotone)."""
    with np.errstate(over="ignore"):
        return np.minimum(low, low.astype(np.float32).astype(float)), np.maximum(high, high.astype(np.float32).astype(float))
