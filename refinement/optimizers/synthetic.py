"""Synthetic refinement problems: random model trees over feature maps like those of two pose actions in a chain.

Used by the optimizer tests and benchmarks, independent of learned models. A feature is bound (a constant),
affine in one free parameter, an absolute wrapped angle (like angle_to), a wrapped angle (like angle_at of
the first action), a sign flip (like angle_at of the second), or, to exercise the fallback, curved (a
distance over a free coordinate) or mixed (two free parameters in one feature).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tailor.refinement.optimizers.objective import FreeParameter, Objective, Term
from tailor.refinement.models.rules import Rule

KINDS = ("bound", "affine", "abs", "wrap", "sign")  # piecewise affine in one free parameter
ANGLE_KINDS = ("abs", "wrap", "sign")  # only for free parameters that are angles
RANGE_SAMPLES = 4000  # random points used to find each feature's range before drawing split thresholds


def wrap(angle: np.ndarray) -> np.ndarray:
    """Angle normalized to [-pi, pi)."""
    return (angle + np.pi) % (2 * np.pi) - np.pi


class RandomModelTree:
    """A model tree with random axis-aligned splits and a random linear model in each leaf."""

    def __init__(self, low: np.ndarray, high: np.ndarray, n_leaves: int, rng: np.random.Generator):
        self.feature, self.threshold, self.left, self.right = [-1], [0.0], [-1], [-1]
        self.coef, self.intercept = [None], [0.0]
        boxes = {0: (np.asarray(low, float).copy(), np.asarray(high, float).copy())}
        leaves = [0]
        while len(leaves) < n_leaves:
            node = leaves.pop(int(rng.integers(len(leaves))))
            lo, hi = boxes[node]
            f = int(rng.integers(len(lo)))
            thr = float(rng.uniform(lo[f], hi[f]))
            self.feature[node], self.threshold[node] = f, thr
            for side in (0, 1):
                child = len(self.feature)
                for column, empty in ((self.feature, -1), (self.threshold, 0.0), (self.left, -1),
                                      (self.right, -1), (self.coef, None), (self.intercept, 0.0)):
                    column.append(empty)
                clo, chi = lo.copy(), hi.copy()
                (chi if side == 0 else clo)[f] = thr
                boxes[child] = (clo, chi)
                (self.left if side == 0 else self.right)[node] = child
                leaves.append(child)
        for leaf in leaves:
            self.coef[leaf] = rng.normal(0.0, 1.0, len(low))
            self.intercept[leaf] = float(rng.uniform(1.0, 3.0))
        self.n_features = len(low)
        self._arrays = (
            np.array(self.feature), np.array(self.threshold), np.array(self.left), np.array(self.right),
            np.array([c if c is not None else np.zeros(self.n_features) for c in self.coef]),
            np.array(self.intercept),
        )

    def _leaf(self, F: np.ndarray) -> np.ndarray:
        feature, threshold, left, right = self._arrays[:4]
        node = np.zeros(len(F), dtype=int)
        while True:
            inner = feature[node] >= 0
            if not inner.any():
                return node
            n = node[inner]
            go_left = F[np.flatnonzero(inner), feature[n]] <= threshold[n]
            node[inner] = np.where(go_left, left[n], right[n])

    def predict(self, F: np.ndarray) -> np.ndarray:
        F = np.atleast_2d(F)
        leaf = self._leaf(F)
        coef, intercept = self._arrays[4:]
        return np.einsum("nf,nf->n", F, coef[leaf]) + intercept[leaf]

    def rules(self) -> list[Rule]:
        out = []
        stack = [(0, np.full(self.n_features, -np.inf), np.full(self.n_features, np.inf))]
        while stack:
            node, lo, hi = stack.pop()
            f = self.feature[node]
            if f < 0:
                out.append(Rule(lo, hi, self.coef[node], self.intercept[node]))
                continue
            lhi, rlo = hi.copy(), lo.copy()
            lhi[f] = min(hi[f], self.threshold[node])
            rlo[f] = max(lo[f], self.threshold[node])
            stack.append((self.right[node], rlo, hi))
            stack.append((self.left[node], lo, lhi))
        return out


@dataclass(frozen=True)
class FeatureMap:
    """One feature as a function of the free parameters: kind, the parameter(s) it uses, its constants."""

    kind: str
    var: int
    a: float
    b: float
    other: int = -1

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        t = theta[:, self.var] if self.var >= 0 else np.zeros(len(theta))
        if self.kind == "bound":
            return np.full(len(theta), self.b)
        if self.kind == "affine":
            return self.a * t + self.b
        if self.kind == "abs":
            return np.abs(wrap(self.a - t))
        if self.kind == "wrap":
            return wrap(t - self.a)
        if self.kind == "sign":
            return np.where(wrap(self.a - t) >= 0, 1.0, -1.0) * self.b
        if self.kind == "curved":
            return np.hypot(t - self.a, self.b)
        if self.kind == "mixed":
            return t + self.a * theta[:, self.other]
        raise ValueError(f"unknown feature kind {self.kind!r}")


PAD = 1e-15  # relative, outward, of the enclosure of hypot (the other maps are monotone in each rounding step)


def _wrap_interval(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Enclosure of wrap(x) for x in [lo, hi]: its values at the ends where no jump lies between them (wrap
    rises by hi - lo there; each rounding step of wrap is monotone), else [-pi, pi]; a point gives its value."""
    w_lo, w_hi = wrap(lo), wrap(hi)
    steady = (hi - lo < np.pi) & (np.abs((w_hi - w_lo) - (hi - lo)) <= 1e-6)
    return np.where(steady, w_lo, -np.pi), np.where(steady, w_hi, np.pi)


def _abs_wrap_interval(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Enclosure of |wrap(x)| for x in [lo, hi] (continuous: the angle to the nearest multiple of 2 pi): 0 where a
    multiple of 2 pi lies inside, pi where an odd multiple of pi does, else its values at the ends."""
    v_lo, v_hi = np.abs(wrap(lo)), np.abs(wrap(hi))
    near = 1e-9
    zero = np.floor(hi / (2 * np.pi) + near) >= np.ceil(lo / (2 * np.pi) - near)
    half = np.floor((hi - np.pi) / (2 * np.pi) + near) >= np.ceil((lo - np.pi) / (2 * np.pi) - near)
    return np.where(zero, 0.0, np.minimum(v_lo, v_hi)), np.where(half, np.pi, np.maximum(v_lo, v_hi))


def _abs_interval(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return (np.where(lo > 0, lo, np.where(hi < 0, -hi, 0.0)), np.maximum(np.abs(lo), np.abs(hi)))


def _map_bounds(m: FeatureMap, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Enclosure of feature map `m` over the boxes [lo, hi] (k, n_free): interval arithmetic on the same
    floating-point steps as the map (rounding is monotone, so the ends' values bound the values between)."""
    k = len(lo)
    t_lo, t_hi = (lo[:, m.var], hi[:, m.var]) if m.var >= 0 else (np.zeros(k), np.zeros(k))
    if m.kind == "bound":
        return np.full(k, m.b), np.full(k, m.b)
    if m.kind == "affine":
        a, b = m.a * t_lo + m.b, m.a * t_hi + m.b
        return np.minimum(a, b), np.maximum(a, b)
    if m.kind in ("abs", "sign"):
        if m.kind == "abs":
            return _abs_wrap_interval(m.a - t_hi, m.a - t_lo)
        w_lo, w_hi = _wrap_interval(m.a - t_hi, m.a - t_lo)
        sign_lo = np.where(w_lo >= 0, 1.0, -1.0)
        sign_hi = np.where(w_hi >= 0, 1.0, -1.0)
        a, b = sign_lo * m.b, sign_hi * m.b
        return np.minimum(a, b), np.maximum(a, b)
    if m.kind == "wrap":
        return _wrap_interval(t_lo - m.a, t_hi - m.a)
    if m.kind == "curved":
        d_lo, d_hi = _abs_interval(t_lo - m.a, t_hi - m.a)
        return np.hypot(d_lo, m.b) * (1 - PAD), np.hypot(d_hi, m.b) * (1 + PAD)
    if m.kind == "mixed":
        o_lo, o_hi = lo[:, m.other], hi[:, m.other]
        a, b = m.a * o_lo, m.a * o_hi
        return t_lo + np.minimum(a, b), t_hi + np.maximum(a, b)
    raise ValueError(f"unknown feature kind {m.kind!r}")


def feature_bounds(maps: list[FeatureMap]):
    """The enclosure of `feature_function(maps)` over boxes of the free parameters (Term.feature_bounds)."""
    def bounds(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = np.atleast_2d(lo), np.atleast_2d(hi)
        pairs = [_map_bounds(m, lo, hi) for m in maps]
        return np.stack([p[0] for p in pairs], axis=1), np.stack([p[1] for p in pairs], axis=1)

    return bounds


def reads(maps: list[FeatureMap]) -> tuple[int, ...]:
    """The free parameters the maps depend on (Term.reads)."""
    return tuple(sorted({j for m in maps for j in (m.var, m.other) if j >= 0 and m.kind != "bound"}))


def feature_function(maps: list[FeatureMap]):
    def features(theta: np.ndarray) -> np.ndarray:
        theta = np.atleast_2d(theta)
        return np.stack([m(theta) for m in maps], axis=1)

    return features


def random_map(kind: str, var: int, rng: np.random.Generator, n_free: int = 1) -> FeatureMap:
    if kind == "mixed":
        return FeatureMap(kind, var, float(rng.uniform(0.5, 2)), 0.0, other=(var + 1) % n_free)
    return FeatureMap(kind, var, float(rng.uniform(-np.pi, np.pi)), float(rng.uniform(0.2, 2.0)))


def random_objective(
    rng: np.random.Generator,
    n_free: int,
    n_terms: int,
    n_leaves: int = 30,
    n_features: int = 4,
    extra_kind: str | None = None,
) -> Objective:
    """Terms sharing n_free parameters (even ones angles in [-pi, pi], odd ones speeds in [0, 2])."""
    free = tuple(
        FreeParameter(f"p{j}.phi", -np.pi, np.pi) if j % 2 == 0 else FreeParameter(f"p{j}.v", 0.0, 2.0)
        for j in range(n_free)
    )
    terms = []
    for k in range(n_terms):
        maps = []
        for i in range(n_features):
            var = int(rng.integers(n_free)) if i > 0 else (k % n_free)  # the first feature uses a free one
            kinds = KINDS if free[var].id.endswith("phi") else ("bound", "affine")
            kind = str(rng.choice(kinds[1:] if i == 0 else kinds))
            maps.append(random_map(kind, -1 if kind == "bound" else var, rng))
        if extra_kind is not None and k == 0:
            maps.append(random_map(extra_kind, 0, rng, n_free))
        terms.append(_term(maps, n_leaves, free, rng, label=f"term{k}"))
    return Objective(free, tuple(terms))


def _term(maps, n_leaves, free, rng, label) -> Term:
    features = feature_function(maps)
    low = np.array([p.low for p in free])
    high = np.array([p.high for p in free])
    sample = features(rng.uniform(low, high, size=(RANGE_SAMPLES, len(free))))
    tree = RandomModelTree(sample.min(axis=0), sample.max(axis=0), n_leaves, rng)
    return Term(model=tree, features=features, label=label, feature_bounds=feature_bounds(maps), reads=reads(maps))


def pose_chain(rng: np.random.Generator, n_leaves: int = 100) -> Objective:
    """Two pose actions in a chain with the shared subgoal's heading phi and speed v free (the shape of
    Figs. 5.8/5.9: arrive at a subgoal, then leave it)."""
    free = (FreeParameter("sub.phi", -np.pi, np.pi), FreeParameter("sub.v", 0.0, 0.3))
    a1, a2 = rng.uniform(-np.pi, np.pi, size=2)
    arrive = [  # dist, angle_to (bound: the start pose is known), angle_at (phi free), v, vg
        FeatureMap("bound", -1, 0.0, float(rng.uniform(0.5, 4))),
        FeatureMap("bound", -1, 0.0, float(rng.uniform(0, np.pi))),
        FeatureMap("wrap", 0, float(a1), 0.0),
        FeatureMap("bound", -1, 0.0, 0.0),
        FeatureMap("affine", 1, 1.0, 0.0),
    ]
    leave = [  # dist, angle_to (phi free), angle_at (sign flips with phi), v (free), vg
        FeatureMap("bound", -1, 0.0, float(rng.uniform(0.5, 4))),
        FeatureMap("abs", 0, float(a2), 0.0),
        FeatureMap("sign", 0, float(a2), float(rng.uniform(0.1, np.pi))),
        FeatureMap("affine", 1, 1.0, 0.0),
        FeatureMap("bound", -1, 0.0, 0.0),
    ]
    terms = (
        _term(arrive, n_leaves, free, rng, "arrive"),
        _term(leave, n_leaves, free, rng, "leave"),
    )
    return Objective(free, terms)
