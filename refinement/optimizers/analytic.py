"""Analytic minimization of sums of model trees over the free parameters (App. C.3).

Each rule of a model tree is a bounded hyperplane over the features. Where every feature is affine in one
free parameter between breakpoints (detected by `structure.detect`), a rule restricted to one piece of each
free parameter is a box in the free-parameter space with a linear cost (C.3.1; bound features just drop
the rules they violate, C.3.2). The rule sets of all terms are merged by intersecting their boxes and summing
their linear models, dropping contradictory pairs (C.3.3), and the minimum of each merged rule is at the
corner its gradient points away from. The best corners are checked with the true objective.

Knife-edge optima: the cheapest corner of a box often lies on a split of a tree, where the smallest perturbation
(execution noise, a printed value's rounding) lands in the neighbouring leaf and its time. With the objective's
margin, each box is shrunk by it at every bound that is a split of the term's model (not at the ends of the
range, and not at a piece edge of the feature map, which is a kink of a continuous prediction): the chosen
values then lie at least the margin from every split, and a leaf thinner than twice the margin is never chosen.

A term with a predicted-success region (Alg. 6: a success classifier's leaves, axis-aligned boxes in its
feature space) contributes those leaves as rules with a zero linear model: merged like any rule set, they cut
every box down to where success is predicted, so the minimum is the minimum within the region.

The result's lower bound is the minimum over the merged boxes without margins and with every success leaf
unshrunk: no valid choice costs less (and a worst case over a neighbourhood never less than the point), exact
over the affine pieces `structure.detect` finds. The gap then shows what the margin and the neighbourhood cost.
"""

from __future__ import annotations

import time
import weakref
from dataclasses import replace

import numpy as np

from tailor.refinement.models.rules import Rule
from tailor.refinement.optimizers.objective import Objective, OptimizationResult, neighbourhood_offsets
from tailor.refinement.optimizers.structure import LOCATE_TOL, NotApplicable, TermStructure, detect

MAX_MERGED_PAIRS = 4_000_000  # box pairs examined when merging two rule sets (C.3.3 worst case r1 * r2)
CANDIDATES = 32  # best predicted corners checked with the true objective (more if all are invalid)
NUDGE = 100 * LOCATE_TOL  # fraction of max(1, range) by which an open corner is moved inside its box
_rule_cache: "weakref.WeakKeyDictionary[object, tuple]" = weakref.WeakKeyDictionary()


def rule_arrays(model) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The model's rules stacked as (lower, upper, coef) of shape (R, n_features) and intercept (R,)."""
    try:
        return _rule_cache[model]
    except (KeyError, TypeError):
        pass
    rules = model.rules()
    if not rules:  # e.g. a success classifier without a success leaf: no box to merge
        raise NotApplicable("a model without rules (a success region that predicts success nowhere)")
    arrays = (
        np.array([r.lower for r in rules], dtype=float),
        np.array([r.upper for r in rules], dtype=float),
        np.array([r.coef for r in rules], dtype=float),
        np.array([r.intercept for r in rules], dtype=float),
    )
    try:
        _rule_cache[model] = arrays
    except TypeError:  # a model that cannot be weakly referenced is simply not cached
        pass
    return arrays


class _SuccessRules:
    """A success region seen as a rule set (zero linear models), so it merges like a model tree's rules."""

    def __init__(self, region) -> None:
        self.region = region

    def rules(self):
        return self.region.success_rules()


_region_cache: "weakref.WeakKeyDictionary[object, _SuccessRules]" = weakref.WeakKeyDictionary()


def region_rules(region) -> _SuccessRules:
    """The region's rule set, one object per region so that `rule_arrays` caches its arrays."""
    try:
        return _region_cache[region]
    except (KeyError, TypeError):
        pass
    rules = _SuccessRules(region)
    try:
        _region_cache[region] = rules
    except TypeError:
        pass
    return rules


def term_boxes(structure: TermStructure, model, margin: tuple[float, ...] = ()
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One term's rules as boxes in free-parameter space: lo, hi (n, d), gradient (n, d), constant (n,); with a
    margin per free parameter, each box kept that far (and a hair more) inside the splits of the model."""
    lower, upper, coef, intercept = rule_arrays(model)
    bound = structure.var_of < 0
    c = structure.const[bound]
    keep = np.all((lower[:, bound] < c) & (c <= upper[:, bound]), axis=1)  # C.3.2: bound features
    constant = intercept + coef[:, bound] @ c
    per_var = []
    for j, edges in enumerate(structure.edges):
        dep = np.flatnonzero(structure.var_of == j)
        s = structure.slope[j][dep][None]  # (1, nd, P)
        o = structure.offset[j][dep][None]
        lo_f, hi_f = lower[:, dep, None], upper[:, dep, None]  # (R, nd, 1)
        rising, falling = s > 0, s < 0
        with np.errstate(divide="ignore", invalid="ignore"):
            a = np.where(rising, (lo_f - o) / s, np.where(falling, (hi_f - o) / s, -np.inf))
            b = np.where(rising, (hi_f - o) / s, np.where(falling, (lo_f - o) / s, np.inf))
        flat_ok = (s != 0) | ((lo_f < o) & (o <= hi_f))  # a feature constant on the piece holds or not
        a = np.where(flat_ok, a, np.inf)
        split_lo, split_hi = a.max(axis=1, initial=-np.inf), b.min(axis=1, initial=np.inf)
        lo = np.maximum(split_lo, edges[:-1])  # (R, P)
        hi = np.minimum(split_hi, edges[1:])
        if margin and margin[j] > 0:  # strictly more than the margin: a perturbation by it stays in the leaf
            m = margin[j] + NUDGE * max(1.0, float(edges[-1] - edges[0]))
            lo = np.where(split_lo > edges[:-1], lo + m, lo)
            hi = np.where(split_hi < edges[1:], hi - m, hi)
        grad = coef[:, dep] @ structure.slope[j][dep]  # (R, P)
        const = coef[:, dep] @ structure.offset[j][dep]
        per_var.append((lo, hi, grad, const))
    n_free = len(per_var)
    shape = (len(intercept),) + tuple(v[0].shape[1] for v in per_var)
    ok = keep.reshape((-1,) + (1,) * n_free)
    for j, (lo, hi, _, _) in enumerate(per_var):
        ok = ok & (lo <= hi).reshape(_axis_shape(len(intercept), n_free, j, lo.shape[1]))
    index = np.nonzero(np.broadcast_to(ok, shape))
    r = index[0]
    box_lo = np.stack([per_var[j][0][r, index[j + 1]] for j in range(n_free)], axis=1)
    box_hi = np.stack([per_var[j][1][r, index[j + 1]] for j in range(n_free)], axis=1)
    grad = np.stack([per_var[j][2][r, index[j + 1]] for j in range(n_free)], axis=1)
    const = constant[r] + sum(per_var[j][3][r, index[j + 1]] for j in range(n_free))
    return box_lo, box_hi, grad, const


def _axis_shape(n_rules: int, n_free: int, j: int, n_pieces: int) -> tuple[int, ...]:
    shape = [n_rules] + [1] * n_free
    shape[j + 1] = n_pieces
    return tuple(shape)


def _inside(boxes, margin: tuple[float, ...], low: np.ndarray, high: np.ndarray):
    """Region boxes shrunk by `margin` per free parameter (not at the ends of the range, beyond which there is
    nothing to be robust against); boxes that vanish are dropped."""
    if not margin or not any(margin):
        return boxes
    lo, hi, grad, const = boxes
    m = np.asarray(margin, dtype=float)
    lo = np.where(lo > low, lo + m, lo)
    hi = np.where(hi < high, hi - m, hi)
    keep = np.all(lo <= hi, axis=1)
    return lo[keep], hi[keep], grad[keep], const[keep]


def merge(first, second):
    """C.3.3: every pair of rules, boxes intersected and linear models summed; contradictory pairs dropped."""
    lo1, hi1, g1, c1 = first
    lo2, hi2, g2, c2 = second
    if len(lo1) * len(lo2) > MAX_MERGED_PAIRS:
        raise NotApplicable(f"merging {len(lo1)} x {len(lo2)} rules exceeds the budget of {MAX_MERGED_PAIRS}")
    lo = np.maximum(lo1[:, None], lo2[None])
    hi = np.minimum(hi1[:, None], hi2[None])
    i, k = np.nonzero(np.all(lo <= hi, axis=2))
    return lo[i, k], hi[i, k], g1[i] + g2[k], c1[i] + c2[k]


class _SuccessLeaves:
    """Every leaf where a success classifier predicts success, grown by a float32 step each way (it compares
    features as float32), as a rule set: a superset of where it predicts success, for the lower bound."""

    def __init__(self, region) -> None:
        self.region = region

    def rules(self):
        if not hasattr(self.region, "regions"):
            return self.region.success_rules()
        out = []
        for box in self.region.regions():
            if box.success:
                with np.errstate(over="ignore"):
                    lower = np.nextafter(box.lower.astype(np.float32), np.float32(-np.inf)).astype(float)
                    upper = np.nextafter(box.upper.astype(np.float32), np.float32(np.inf)).astype(float)
                out.append(Rule(np.minimum(lower, box.lower), np.maximum(upper, box.upper),
                                np.zeros(len(box.lower)), 0.0))
        return out


_leaves_cache: "weakref.WeakKeyDictionary[object, _SuccessLeaves]" = weakref.WeakKeyDictionary()


def _region_structures(objective: Objective) -> list:
    """Per term, the structure of its success region's features (None where it has no region)."""
    low, high = objective.low, objective.high
    names = tuple(p.id for p in objective.free)
    return [detect(replace(term, features=term.region_features), low, high, names) if term.region is not None
            else None for term in objective.terms]


def _merged_boxes(objective: Objective, structures, regions, margin: tuple[float, ...], bound: bool = False):
    """The terms' rule sets (and success regions) merged into one set of boxes; how many regions took part.
    With `bound`, every success leaf unshrunk (no region margin): the boxes then cover every valid choice."""
    low, high = objective.low, objective.high
    merged = None
    taking = 0
    for term, structure, region in zip(objective.terms, structures, regions):
        boxes = term_boxes(structure, term.model, margin)
        merged = boxes if merged is None else merge(merged, boxes)
        if region is not None:
            if bound:
                leaves = _leaves_cache.get(term.region) if _cacheable(term.region) else None
                if leaves is None:
                    leaves = _SuccessLeaves(term.region)
                    if _cacheable(term.region):
                        _leaves_cache[term.region] = leaves
                merged = merge(merged, term_boxes(region, leaves))
            else:
                merged = merge(merged, _inside(term_boxes(region, region_rules(term.region)), term.region_margin,
                                               low, high))
            taking += 1
    return merged, taking


def _cacheable(region) -> bool:
    try:
        weakref.ref(region)
        return True
    except TypeError:
        return False


def lower_bound(objective: Objective, structures, regions) -> float:
    """The minimum of the merged rules over every choice the success regions may allow, without margins: below
    every valid choice's cost, and below its worst case over a neighbourhood (never under the point's cost)."""
    (lo, hi, grad, const), _ = _merged_boxes(objective, structures, regions, (), bound=True)
    if not len(lo):
        return np.inf
    return float(np.min(const + np.einsum("nd,nd->n", grad, np.where(grad > 0, lo, hi))))


def minimize(objective: Objective, seed: int = 0) -> OptimizationResult:
    """The minimum over the corners of the merged rule set, or NotApplicable (the caller falls back)."""
    del seed  # deterministic; the argument keeps the optimizers interchangeable
    start = time.perf_counter()
    low, high = objective.low, objective.high
    names = tuple(p.id for p in objective.free)
    structures = [detect(term, low, high, names) for term in objective.terms]
    regions_of = _region_structures(objective)
    margin_note = ""
    merged, regions = _merged_boxes(objective, structures, regions_of, objective.margin)
    if len(merged[0]) == 0 and any(objective.margin):
        # every combination of leaves is thinner than twice the margin somewhere: choose without it
        merged, regions = _merged_boxes(objective, structures, regions_of, ())
        margin_note = ", no leaf box wider than twice the margin: chosen without it"
    elif any(objective.margin):
        margin_note = ", a margin inside every leaf box"
    lo, hi, grad, const = merged
    if len(lo) == 0:
        where = " within the predicted-success regions" if regions else ""
        raise NotApplicable(f"no rule combination covers the free-parameter ranges{where}")
    corner = np.where(grad > 0, lo, hi)
    predicted = const + np.einsum("nd,nd->n", grad, corner)
    bound = lower_bound(objective, structures, regions_of)
    # an open bound inside the range is approached from inside its box; the range bounds are closed
    inward = np.where(grad > 0, 1.0, -1.0) * NUDGE * np.maximum(1.0, high - low)
    interior = (corner > low) & (corner < high)
    nudged = np.where(interior, np.clip(corner + inward, lo, hi), corner)
    nudged = np.where(interior & (hi - lo < 2 * np.abs(inward)), (lo + hi) / 2, nudged)
    order = np.argsort(predicted, kind="stable")
    note = f"{len(lo)} merged rules" + (f", within {regions} success region(s)" if regions else "") + margin_note
    if any(objective.neighbourhood):
        result = _robust(objective, order, predicted, (lo, hi, corner, nudged), start, note)
        return replace(result, lower_bound=min(bound, result.cost))
    evaluations = 0
    for chunk in range(0, len(order), CANDIDATES):
        pick = order[chunk : chunk + CANDIDATES]
        points = np.concatenate([corner[pick], nudged[pick]])
        cost = objective.cost(points)
        evaluations += len(points)
        cost = np.where(objective.valid(points), cost, np.inf)
        best = int(np.argmin(cost))
        if np.isfinite(cost[best]):
            return OptimizationResult(
                values=tuple(float(v) for v in points[best]),
                cost=float(cost[best]),
                method="analytic",
                evaluations=evaluations,
                seconds=time.perf_counter() - start,
                note=note,
                lower_bound=min(bound, float(cost[best])),
            )
    raise NotApplicable("every corner of the merged rule set is marked invalid")


def _robust(objective: Objective, order: np.ndarray, predicted: np.ndarray, boxes, start: float,
            note: str) -> OptimizationResult:
    """The neighbourhood's worst case minimized over candidates of every box that could still win: its cheapest
    corner (and that corner nudged inside), the corner moved the neighbourhood's radius inward (toward the
    middle where the box is thinner), and its middle. Boxes come cheapest first; since the worst case is never
    below the box's own minimum, the search stops at the first box whose minimum is above the best worst case."""
    lo, hi, corner, nudged = boxes
    radius = np.asarray(objective.neighbourhood, dtype=float)
    middle = (lo + hi) / 2
    inset = np.where(corner <= lo, np.minimum(lo + radius, middle), np.maximum(hi - radius, middle))
    best_cost, best_point, evaluations = np.inf, None, 0
    for chunk in range(0, len(order), CANDIDATES):
        pick = order[chunk : chunk + CANDIDATES]
        if predicted[pick[0]] >= best_cost:
            break
        points = np.concatenate([corner[pick], nudged[pick], inset[pick], middle[pick]])
        valid = objective.valid(points)
        cost = np.full(len(points), np.inf)
        if valid.any():
            cost[valid] = objective.robust_cost(points[valid])
        evaluations += int(valid.sum()) * len(neighbourhood_offsets(radius))
        i = int(np.argmin(cost))
        if cost[i] < best_cost:
            best_cost, best_point = float(cost[i]), points[i]
    if best_point is None:
        raise NotApplicable("every corner of the merged rule set is marked invalid")
    return OptimizationResult(values=tuple(float(v) for v in best_point), cost=best_cost, method="analytic",
                              evaluations=evaluations, seconds=time.perf_counter() - start,
                              note=note + ", worst case over the neighbourhood")
