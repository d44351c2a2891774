"""A certified global minimum of the merged model trees over any bounded feature map: branch and bound.

Where App. C.3's conditions fail (a feature curved in a free parameter, or mixing two), the sum of the terms'
predictions is still a sum of model trees over features of the free parameters. Over a box of free values each
term's features lie in a box its `feature_bounds` encloses, and over that box the tree's prediction is at least
the smallest leaf minimum the box meets (intervals.minimum): a lower bound of the term, summed over the terms
a lower bound of the objective. The search splits the boxes with the lowest bounds in two, along the widest
free parameter (relative to its range) while a box is wide, else along the one whose halves gain most bound
(a jump of a feature, whose enclosure stays wide however small the box, is cut off across its parameter; the
halves share no float, so a jump between two floats is cut too; while few boxes are open, a wide one is halved
more than once, so a step bounds as many boxes as a full one); it bounds the halves, evaluates their middles
(and the point of each nearest the best so far; once the boxes are narrow, only of the halves bounded lowest)
with the true objective for a better choice, and stops when the best choice is within the tolerance of the
lowest bound still open: the returned gap is then a proof that no valid choice is more than that below it
(under the enclosures). An enclosure that does not shrink to the features' values at a single point could
never close the gap: such a term is refused at once.

Robust objective (a neighbourhood): the worst case at x is the largest cost over the stencil x + o (clipped to
the ranges), so over a box B it is at least, for every offset o, the cost's bound over the box B + o; the
largest of these is the bound (taken over the point and the stencil's ends only: a subset of the offsets bounds
the worst case as well, and the inner ones seldom raise it). Validity (Alg. 6): a box whose region features (`region_bounds`) meet no leaf
where the success classifier predicts success, or whose box moved by the guard's margin to either side along a
free parameter meets none (a valid choice needs success there too), holds no valid choice and is dropped;
every other box stays, so a bound is never raised by a validity the bounds cannot prove.

Deterministic: no random step, and the work is bounded by a number of boxes (`budget`, and a `prospect` that
gives up on a gap that could not close within the budget unless it fell faster than the gaps that closed did, or
that stalls or falls too slowly), not by a clock, so the same problem gives the same answer on any machine.
"""

from __future__ import annotations

import heapq
import time
from dataclasses import dataclass

import numpy as np
from tailor.refinement.optimizers import intervals
from tailor.refinement.optimizers.intervals import Candidates, LeafTable
from tailor.refinement.optimizers.objective import Objective, OptimizationResult
from tailor.refinement.optimizers.structure import NotApplicable

TOLERANCE = 1e-3  # the gap allowed: the best cost at most this share above the lower bound (so above any choice) ...
ABSOLUTE_TOLERANCE = 1e-6  # ... and in the objective's unit (s) where the cost is near 0
BUDGET = 200_000  # boxes bounded at most by a call of `minimize` (the `certified` optimizer)
BATCH = 64  # boxes split per step (while fewer are open, each wide one more than once, to as many pieces)
STRONG_WIDTH = 1 / 8  # boxes narrower than this share of every range are split where it helps most
ACTIVE_WIDTH = 2.0  # a neighbourhood's offset along a free parameter bounds boxes at most this many radii wide
INNER_WIDTH = 0.5  # ... and an inner offset of the stencil (less than a radius) boxes at most this many
POINT_CHECKS = (0.5, 0.25, 0.8)  # where along the diagonal of the ranges an enclosure is checked at a point
POINT_TOLERANCE = 1e-6  # relative: how wide an enclosure of a single point may be
TIE = 1e-9  # relative: bounds of halves this close count as equal (the widest parameter is split then)
EVALUATED = 4  # after WIDE boxes, the 1 / EVALUATED of the halves of a step with the lowest bounds are evaluated
CHECKPOINT = 64  # boxes: a search with a `prospect` is judged from this many on, at each doubling, and given up
FASTEST = 12  # ... while it has bounded at most WIDE boxes, where closing its gap within its budget would take a
WIDE = 512  # fall faster than FASTEST / n halvings per doubling of the boxes (n free parameters; see `minimize`);
SLOW_FROM = 500  # ... from this many boxes on, where the gap falls too slowly for the prospect (see `minimize`)
STALLED = 0.1  # ... or by less than this share over the last two doublings (a bound stuck at a jump) ...
STALL_FROM = 2000  # ... from this many boxes on (some gaps stall for one doubling before they close), and where
UNBOUNDED_FROM = 256  # its lower bound is still unbounded after this many


@dataclass(frozen=True, eq=False)
class _Bounded:
    """One term as the search bounds it."""

    table: LeafTable
    features: object  # (low, high) -> (feature_low, feature_high)
    region: LeafTable | None
    region_features: object | None
    use: np.ndarray  # the stencil rows that can change the term (Objective.stencils)
    position: np.ndarray
    margin: tuple[float, ...] = ()  # Term.region_margin: how far inside the region a valid choice lies


def _check_tight(term, objective: Objective) -> None:
    """NotApplicable unless the term's enclosure shrinks to its features' values at single points (a few,
    fixed): the search splits boxes down to points, and an enclosure wide even there bounds nothing closer."""
    low, high = objective.low, objective.high
    points = low + (high - low) * np.array(POINT_CHECKS)[:, None]
    f_lo, f_hi = _enclosure(term.feature_bounds, points, points)
    values = np.asarray(term.features(points), dtype=float)
    slack = POINT_TOLERANCE * (1.0 + np.abs(values))
    wrong = (f_lo > values + slack) | (f_hi < values - slack)
    loose = f_hi - f_lo > slack
    for bad, what in ((wrong, "its enclosure misses"), (loose, "cannot be bounded closely:")):
        if bad.any():
            row, feature = np.argwhere(bad)[0]
            raise NotApplicable(f"term {term.label!r} {what} its feature {feature} is enclosed in "
                                f"[{f_lo[row, feature]:.4g}, {f_hi[row, feature]:.4g}] at a single point where it "
                                f"is {values[row, feature]:.4g}")


def bounded_terms(objective: Objective) -> list[_Bounded]:
    """The terms with their leaf tables and enclosures, or NotApplicable naming the first that has none or whose
    enclosure does not shrink to the features at a point."""
    out = []
    stencils = objective.stencils if any(objective.neighbourhood) else [(np.zeros(1, int), np.zeros(1, int))] * len(
        objective.terms)
    for term, (use, position) in zip(objective.terms, stencils):
        if term.feature_bounds is None:
            why = term.no_bounds or "its features declare no bounds"
            raise NotApplicable(f"term {term.label!r} cannot be bounded: {why}")
        _check_tight(term, objective)
        region = None
        if term.region is not None and term.region_bounds is not None:
            region = intervals.success_table(term.region)
        out.append(_Bounded(intervals.leaf_table(term.model), term.feature_bounds, region, term.region_bounds,
                            use, position, tuple(term.region_margin)))
    return out


class _Search:
    """The open boxes: rows of growing arrays, a heap of (bound, row) to take the lowest first, and per term the
    leaves each box may still meet."""

    def __init__(self, objective: Objective, terms: list[_Bounded]):
        self.objective, self.terms = objective, terms
        self.low, self.high = objective.low, objective.high
        self.scale = np.where(self.high > self.low, self.high - self.low, np.inf)  # fixed parameters never split
        self.radius = (np.asarray(objective.neighbourhood, dtype=float) if any(objective.neighbourhood)
                       else np.zeros(len(self.low)))
        self.offsets = objective.offsets if any(objective.neighbourhood) else np.zeros((1, len(self.low)))
        self.column = np.abs(self.offsets).argmax(axis=1)  # the free parameter each offset moves (row 0: none)
        # the stencil's inner rows (between the point and its ends): they bound a box only once it is at most
        # INNER_WIDTH radii wide along them (see evaluate)
        extent = np.abs(self.offsets[np.arange(len(self.offsets)), self.column])
        self.inner = (np.arange(len(self.offsets)) > 0) & (extent < self.radius[self.column])
        self.lo = np.empty((1024, len(self.low)))
        self.hi = np.empty((1024, len(self.low)))
        self.bound = np.empty(1024)
        self.rows = 0
        self.heap: list[tuple[float, int]] = []
        self.leaves: list[list[np.ndarray | None]] = [[] for _ in terms]  # per term, per row
        self.boxes = 0  # boxes bounded so far
        self.widths: list[np.ndarray] = []  # per term: its features' enclosure widths over the whole range
        self.spread = np.empty(0)  # of the last boxes evaluated: their enclosures' widths, summed relative

    def evaluate(self, lo: np.ndarray, hi: np.ndarray, parents: list[list[np.ndarray]] | None, cap: float = np.inf
                 ) -> tuple[np.ndarray, np.ndarray, list[list[np.ndarray]]]:
        """Bounds of the boxes [lo, hi] (k, n), whether each may hold a valid choice, and the leaves each may
        meet per term (`parents`: per term, the leaves of each box's parent; None: every leaf). A box bounded at
        `cap` or above is closed whatever its validity: it counts as possible, unchecked."""
        k = len(lo)
        if k == 0:
            return np.empty(0), np.empty(0, dtype=bool), [[] for _ in self.terms]
        self.boxes += k
        grown_lo = np.clip(lo - self.radius, self.low, self.high)
        grown_hi = np.clip(hi + self.radius, self.low, self.high)
        total = np.zeros((len(self.offsets), k))
        # an offset counts where the box is at most ACTIVE_WIDTH radii wide along it: over a wider box the moved
        # box bounds little more than the box itself (leaving an offset out keeps the bound a bound)
        active = np.ones((len(self.offsets), k), dtype=bool)
        if self.radius.any():
            column = self.column[1:]
            active[1:] = (hi - lo)[:, column].T <= ACTIVE_WIDTH * self.radius[column][:, None]
            # an inner row, once the box is narrower than its spacing: where the worst case over the neighbourhood
            # lies at an inner row, the ends alone bound it below that, and the gap at the optimum never closes
            inner = (hi - lo)[:, column].T <= INNER_WIDTH * self.radius[column][:, None]
            active[1:] &= ~self.inner[1:, None] | inner
        spread = np.zeros(k)
        possible = np.ones(k, dtype=bool)
        leaves = []
        for t, term in enumerate(self.terms):
            use, position = term.use, term.position
            if parents is None:
                pairs = Candidates.every(term.table, k)
            else:
                counts = np.array([len(a) for a in parents[t]])
                pairs = Candidates(np.repeat(np.arange(k), counts), np.concatenate(parents[t]))
            # the grown box (the leaves its neighbourhood may meet), and the box moved by each stencil offset that
            # can change the term (its bound): one enclosure call for both (a call costs more than its rows)
            if self.radius.any():  # (without a neighbourhood the grown box is the box itself)
                # only the moved boxes whose offset is active are enclosed (an inactive one bounds nothing; its
                # rows stay unbounded and out of the minimum below)
                on_rows = np.flatnonzero(active[use].ravel())  # (offset, box) rows, offset-major
                shift = self.offsets[use][on_rows // k]
                s_lo = np.clip(lo[on_rows % k] + shift, self.low, self.high)
                s_hi = np.clip(hi[on_rows % k] + shift, self.low, self.high)
                e_lo, e_hi = _enclosure(term.features, np.concatenate([grown_lo, s_lo]),
                                        np.concatenate([grown_hi, s_hi]))
                g_lo, g_hi = e_lo[:k], e_hi[:k]
                f_lo = np.full((len(use) * k, e_lo.shape[1]), -np.inf)
                f_hi = np.full((len(use) * k, e_lo.shape[1]), np.inf)
                f_lo[on_rows], f_hi[on_rows] = e_lo[k:], e_hi[k:]
            else:
                g_lo, g_hi = f_lo, f_hi = _enclosure(term.features, grown_lo, grown_hi)
            hit = intervals.meets(term.table, pairs, g_lo, g_hi)
            pairs = Candidates(pairs.box[hit], pairs.leaf[hit])
            ends = np.cumsum(np.bincount(pairs.box, minlength=k)).tolist()
            leaves.append([pairs.leaf[a:b] for a, b in zip([0] + ends[:-1], ends)])
            width = np.minimum(f_hi[:k] - f_lo[:k], 1e300)  # the box itself: the first rows (offset 0)
            if len(self.widths) <= t:  # the root's enclosure: the scale of each feature's width
                self.widths.append(np.where(width[0] > 0, width[0], 1.0))
            with np.errstate(over="ignore"):  # (enclosures 1e300 wide sum to inf: as wide as can be)
                spread += (width / self.widths[t]).sum(axis=1)
            u = len(use)
            box = (np.arange(u)[:, None] * k + pairs.box[None]).ravel()
            on = active[use][:, pairs.box].ravel()
            moved = Candidates(box[on], np.tile(pairs.leaf, u)[on])
            value = intervals.minimum(term.table, moved, f_lo, f_hi, u * k).reshape(u, k)
            with np.errstate(invalid="ignore"):  # (an inactive offset's +inf beside another term's -inf)
                total += value[position]
        self.spread = spread
        bound = np.where(active, total, -np.inf).max(axis=0)
        bound = np.where(np.isnan(bound), -np.inf, bound)  # (NaN: no bound)
        check = np.flatnonzero(bound < cap)
        for term in self.terms:
            if term.region is not None and len(check):
                ok = self.may_succeed(term, lo[check], hi[check])
                possible[check[~ok]] = False
                check = check[ok]
        return bound, possible, leaves

    def may_succeed(self, term: _Bounded, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """(k,) bool: whether the box may hold a choice the term's success classifier finds valid: its region
        features meet a leaf predicting success, and so do the box's moved by the term's margin to either side
        along each free parameter (Term.valid asks success there too, the moved point kept within the ranges)."""
        k = len(lo)
        boxes = [(lo, hi)]
        for j, m in enumerate(term.margin):
            for step in (-m, m) if m > 0 else ():
                m_lo, m_hi = lo.copy(), hi.copy()
                m_lo[:, j] = np.clip(lo[:, j] + step, self.low[j], self.high[j])
                m_hi[:, j] = np.clip(hi[:, j] + step, self.low[j], self.high[j])
                boxes.append((m_lo, m_hi))
        r_lo, r_hi = intervals.float32_hull(*_enclosure(
            term.region_features, np.concatenate([b[0] for b in boxes]), np.concatenate([b[1] for b in boxes])))
        success = Candidates.every(term.region, len(r_lo))
        hit = intervals.meets(term.region, success, r_lo, r_hi)
        return (np.bincount(success.box[hit], minlength=len(r_lo)) > 0).reshape(len(boxes), k).all(axis=0)

    def add(self, lo: np.ndarray, hi: np.ndarray, bound: np.ndarray, leaves: list[list[np.ndarray]]) -> None:
        k = len(lo)
        if self.rows + k > len(self.bound):
            size = max(2 * len(self.bound), self.rows + k)
            for name in ("lo", "hi", "bound"):
                old = getattr(self, name)
                new = np.empty((size,) + old.shape[1:])
                new[:self.rows] = old[:self.rows]
                setattr(self, name, new)
        rows = np.arange(self.rows, self.rows + k)
        self.lo[rows], self.hi[rows], self.bound[rows] = lo, hi, bound
        self.rows += k
        for t in range(len(self.terms)):
            self.leaves[t].extend(leaves[t])
        for b, row in zip(bound.tolist(), rows.tolist()):
            heapq.heappush(self.heap, (b, row))

    def take(self, count: int, below: float = np.inf) -> np.ndarray:
        """The rows of the `count` open boxes with the lowest bounds, closed: their leaves are handed over. Only
        boxes bounded below `below` (a box bounded there or above holds nothing better: it is left)."""
        rows = []
        while self.heap and len(rows) < count and self.heap[0][0] < below:
            rows.append(heapq.heappop(self.heap)[1])
        return np.array(rows, dtype=int)

    def leaves_of(self, rows: np.ndarray) -> list[list[np.ndarray]]:
        out = []
        for per_row in self.leaves:
            out.append([per_row[r] for r in rows])
            for r in rows:
                per_row[r] = None  # closed: its halves hold their own
        return out

    def lowest(self) -> float:
        return self.heap[0][0] if self.heap else np.inf


def _halves(lo: np.ndarray, hi: np.ndarray, axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The boxes halved along `axis` (one per box; wider than one float there): the lower halves, then the
    upper ones."""
    rows = np.arange(len(lo))
    a, b = lo[rows, axis], hi[rows, axis]
    middle = np.minimum(a + (b - a) / 2, np.nextafter(b, -np.inf))  # below b: two adjacent floats part
    left_hi, right_lo = hi.copy(), lo.copy()
    left_hi[rows, axis] = middle
    right_lo[rows, axis] = np.nextafter(middle, np.inf)  # the halves share no float: a jump between is cut
    return np.concatenate([lo, right_lo]), np.concatenate([left_hi, hi])


def _split(search: _Search, lo, hi, parent_bound, parent_leaves, cap: float, levels: int = 1,
           close_at: float = np.inf):
    """Each box halved, bounded and checked (the lower halves, then the upper ones): along its widest free
    parameter (relative to its range) while it is wider than STRONG_WIDTH of it, else along the parameter
    whose halves gain most bound over it, up to `cap` (strong branching: a jump of a feature, whose enclosure
    stays wide however small the box, is cut off along the parameter it lies across). A wide box is halved
    `levels` times over (each piece along its widest parameter, while every piece is still wide), and only the
    last pieces bounded: the step of a search with few boxes open bounds as many as a full one."""
    k, n = lo.shape
    relative = (hi - lo) / search.scale
    axis = np.argmax(relative, axis=1)
    strong = (relative[np.arange(k), axis] <= STRONG_WIDTH) & (n > 1)
    plain, rows = np.flatnonzero(~strong), np.flatnonzero(strong)
    m = len(rows)
    c_lo, c_hi = _halves(lo[plain], hi[plain], axis[plain])
    half = np.concatenate([plain, plain])  # each piece's box
    for _ in range(levels - 1):
        relative_piece = (c_hi - c_lo) / search.scale
        piece_axis = np.argmax(relative_piece, axis=1)
        if not np.all(relative_piece[np.arange(len(c_lo)), piece_axis] > STRONG_WIDTH):
            break
        c_lo, c_hi = _halves(c_lo, c_hi, piece_axis)
        half = np.concatenate([half, half])
    axes = np.tile(np.arange(n), m)  # every strong box halved along every parameter, its best pair kept below
    s_lo, s_hi = _halves(np.repeat(lo[rows], n, axis=0), np.repeat(hi[rows], n, axis=0), axes)
    p = len(c_lo)  # both bounded in one call (a call of the enclosures costs more than its rows)
    bound, possible, leaves = search.evaluate(
        np.concatenate([c_lo, s_lo]), np.concatenate([c_hi, s_hi]),
        [[part[r] for r in half] + [part[r] for r in rows for _ in range(n)] * 2 for part in parent_leaves],
        close_at)
    if m:
        s_bound, s_possible, s_spread = bound[p:], possible[p:], search.spread[p:]
        s_leaves = [part[p:] for part in leaves]
        bound, possible, leaves = bound[:p], possible[:p], [part[:p] for part in leaves]
        halves = np.maximum(np.where(s_possible, s_bound, np.inf).reshape(2, m, n), parent_bound[rows, None])
        # what the halves gain over the box, each at most up to the best cost (beyond, a half is closed anyway)
        with np.errstate(invalid="ignore"):  # (-inf - -inf: a half no better bounded than its box gains nothing)
            gain = np.minimum(halves, np.maximum(cap, parent_bound[rows, None])) - parent_bound[rows, None]
        gain = np.where(np.isnan(gain), 0.0, gain)
        score = np.where(relative[rows] > 0, gain.sum(axis=0), -np.inf)
        spread = s_spread.reshape(2, m, n).sum(axis=0)  # how wide the halves' feature enclosures stay
        top = score.max(axis=1, keepdims=True)
        tie = score >= top - TIE * (1.0 + np.abs(np.where(np.isfinite(top), top, 0.0)))
        # of the best, the one whose halves enclose their features most tightly (a jump cut off), then the widest
        choice = np.argmin(np.where(tie, spread - 1e-12 * relative[rows], np.inf), axis=1)
        pick = np.concatenate([np.arange(m) * n + choice, m * n + np.arange(m) * n + choice])
        c_lo, c_hi = np.concatenate([c_lo, s_lo[pick]]), np.concatenate([c_hi, s_hi[pick]])
        bound, possible = np.concatenate([bound, s_bound[pick]]), np.concatenate([possible, s_possible[pick]])
        leaves = [a + [b[i] for i in pick] for a, b in zip(leaves, s_leaves)]
        half = np.concatenate([half, rows, rows])
    return c_lo, c_hi, np.maximum(bound, parent_bound[half]), possible, leaves


def _enclosure(bounds, lo, hi) -> tuple[np.ndarray, np.ndarray]:
    f_lo, f_hi = bounds(lo, hi)
    f_lo, f_hi = np.asarray(f_lo, dtype=float), np.asarray(f_hi, dtype=float)
    if f_lo.shape != f_hi.shape or f_lo.ndim != 2 or len(f_lo) != len(lo):
        raise NotApplicable(f"feature bounds gave shapes {f_lo.shape}, {f_hi.shape} for {len(lo)} boxes")
    # an end that says nothing (NaN) is unbounded: no leaf is ruled out by it
    return np.where(np.isnan(f_lo), -np.inf, f_lo), np.where(np.isnan(f_hi), np.inf, f_hi)


def tolerance_of(cost: float, tolerance: float = TOLERANCE) -> float:
    """The gap allowed below a best cost `cost`: cost - lower <= it where cost <= (1 + tolerance) lower (for
    durations, positive), so that the choice is never more than `tolerance` above the optimum nor any other
    optimizer's choice; at least ABSOLUTE_TOLERANCE."""
    return max(ABSOLUTE_TOLERANCE, tolerance * abs(cost) / (1.0 + tolerance))


def minimize(objective: Objective, seed: int = 0, budget: int = BUDGET, tolerance: float = TOLERANCE,
             prospect: float | None = None) -> OptimizationResult:
    """Branch and bound to within `tolerance` of the optimum, or until `budget` boxes are bounded (the gap then
    says how far it got); NotApplicable where a term cannot be bounded or no valid choice is found.

    With a `prospect` (boxes), also at a checkpoint (CHECKPOINT boxes and each doubling): while the boxes are
    wide (at most WIDE bounded), where closing the gap within `budget` would take it falling faster than
    FASTEST / n halvings per doubling of the boxes, n free parameters (a box's widths halve once per n doublings;
    of the bundled windows measured, those of the evaluations and of the way-point chain, none that
    closed its gap is given up so, nor with 8 in place of FASTEST, while the windows of four or six free
    parameters whose gap stays above 1000% are given up after 64 to 450 boxes); from SLOW_FROM boxes on, where
    the gap fell by less than STALLED over the last two doublings of the boxes (from STALL_FROM on: a bound stuck
    at a jump; of the windows measured that closed, two stalled for one doubling, none for two), or where closing
    it looks like taking more than `prospect` boxes both at the rate it fell over the last doubling and as if it
    fell in proportion to the boxes (the searches that close fall one way or the other: some slowly until the boxes
    are small, then at once; some fast from a wide start); or where the lower bound is still unbounded after
    UNBOUNDED_FROM boxes. All in boxes: the same problem stops at the same box on any machine."""
    del seed  # deterministic; the argument keeps the optimizers interchangeable
    start = time.perf_counter()
    search = _Search(objective, bounded_terms(objective))
    low, high = objective.low, objective.high
    root_bound, possible, leaves = search.evaluate(low[None], high[None], None)
    best_cost, best_point, evaluations, pruned = np.inf, None, 0, np.inf

    def consider(points: np.ndarray) -> None:
        nonlocal best_cost, best_point, evaluations
        if not len(points):  # (every half pruned or bounded within the tolerance)
            return
        valid = objective.valid(points)
        if not valid.any():
            return
        cost = np.full(len(points), np.inf)
        cost[valid] = objective.robust_cost(points[valid])
        evaluations += int(valid.sum())
        i = int(np.argmin(cost))
        if cost[i] < best_cost:
            best_cost, best_point = float(cost[i]), points[i].copy()

    def tol() -> float:
        return tolerance_of(best_cost, tolerance) if np.isfinite(best_cost) else 0.0

    checkpoint, gaps, hopeless = CHECKPOINT, [(0, np.inf), (0, np.inf)], ""  # (boxes, gap) at the checkpoints
    free = int(np.sum(high > low))  # the parameters a box is split along

    def beyond_prospect(gap: float) -> str:
        """Why the gap looks too far to close within `prospect` boxes (at a checkpoint), or ""."""
        nonlocal checkpoint
        if prospect is None or search.boxes < checkpoint:
            return ""
        checkpoint, before, (earlier_boxes, earlier) = 2 * search.boxes, gaps[-1][1], gaps[-2]
        gaps.append((search.boxes, gap))
        if np.isinf(gap) and np.isinf(before) and search.boxes >= UNBOUNDED_FROM:
            return f"stopped after {search.boxes} boxes: its lower bound still unbounded"
        if not (np.isfinite(gap) and gap > tol()):
            return ""
        if search.boxes <= WIDE:
            fastest = search.boxes * 2.0 ** min(free * np.log2(gap / tol()) / FASTEST, 1000.0)
            if fastest > budget:
                return (f"stopped after {search.boxes} boxes: its gap of {100 * gap / abs(best_cost):.3g}% would take "
                        f"{fastest:.2g} boxes to close even at the fastest fall (over a budget of {budget})")
        if search.boxes < SLOW_FROM:
            return ""
        if gap > (1.0 - STALLED) * earlier and search.boxes >= STALL_FROM:
            return (f"stopped after {search.boxes} boxes: its gap of {100 * gap / abs(best_cost):.3g}% fell by "
                    f"{100 * (1 - gap / earlier):.2g}% over the last {search.boxes - earlier_boxes}")
        rate = np.log2(before / gap)  # halvings of the gap per doubling of the boxes (inf: unbounded before)
        doublings = np.log2(gap / tol()) * min(1.0, 1.0 / rate if rate > 0.0 else np.inf)
        projected = search.boxes * 2.0 ** min(doublings, 1000.0)  # the better of that rate and 1 / boxes
        return (f"stopped after {search.boxes} boxes: its gap of {100 * gap / abs(best_cost):.3g}% would take "
                f"{projected:.2g} boxes to close at best" if projected > prospect else "")

    if possible[0]:
        search.add(low[None], high[None], root_bound, leaves)
        consider((low + high)[None] / 2)
    while True:
        lowest = min(search.lowest(), pruned)
        if lowest == np.inf or (np.isfinite(best_cost) and best_cost - lowest <= tol()) or search.boxes >= budget:
            break
        hopeless = beyond_prospect(best_cost - lowest)
        if hopeless:
            break
        slots = search.take(BATCH, best_cost - tol() if np.isfinite(best_cost) else np.inf)
        lo, hi, parent_bound = search.lo[slots], search.hi[slots], search.bound[slots]
        parent_leaves = search.leaves_of(slots)
        levels = int(np.log2(BATCH // len(slots)))  # few boxes open (at first): each halved more than once
        c_lo, c_hi, bound, possible, leaves = _split(search, lo, hi, parent_bound, parent_leaves,
                                                      best_cost if np.isfinite(best_cost) else np.inf, max(1, levels),
                                                      best_cost - tol() if np.isfinite(best_cost) else np.inf)
        # a half bounded within the tolerance of the best so far holds nothing worth evaluating
        promising = possible & (bound < best_cost - tol()) if np.isfinite(best_cost) else possible
        if search.boxes > WIDE:  # once narrowed, where the bounds are lowest (and every single point: dropped below)
            evaluated = ~np.any(c_hi > c_lo, axis=1)
            evaluated[np.argsort(bound, kind="stable")[:max(1, len(bound) // EVALUATED)]] = True
            promising &= evaluated
        candidates = [((c_lo + c_hi) / 2)[promising]]
        if best_point is not None:  # and the point of each half nearest the best so far (optima sit on edges)
            candidates.append(np.clip(best_point, c_lo, c_hi)[promising])
        consider(np.concatenate(candidates))
        keep = possible & (bound < best_cost - tol()) if np.isfinite(best_cost) else possible
        if np.any(possible & ~keep):
            pruned = min(pruned, float(bound[possible & ~keep].min()))
        keep &= np.any(c_hi > c_lo, axis=1)  # a single point is its middle, evaluated above
        index = np.flatnonzero(keep)
        search.add(c_lo[index], c_hi[index], bound[index], [[part[i] for i in index] for part in leaves])
    if best_point is None:
        raise NotApplicable("no valid choice found" + (" (every box is predicted to fail)" if lowest == np.inf
                                                       else f" within {budget} boxes"))
    lower = min(search.lowest(), pruned, best_cost)
    gap = best_cost - lower
    certified = gap <= tol()
    note = (f"branch and bound: {search.boxes} boxes, gap {gap:.3g} s"
            + (f" ({100 * gap / abs(best_cost):.3g}%)" if best_cost else "")
            + ("" if certified else f", {hopeless or f'budget of {budget} boxes spent'} before the tolerance "
                                     f"{tolerance:g}")
            + ("; worst case over the neighbourhood" if any(objective.neighbourhood) else ""))
    return OptimizationResult(values=tuple(float(v) for v in best_point), cost=best_cost, method="certified",
                              evaluations=evaluations, seconds=time.perf_counter() - start, note=note,
                              lower_bound=float(lower))
