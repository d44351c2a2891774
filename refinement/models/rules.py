"""Rules of a model tree: each leaf is a bounded hyperplane (App. C.3).

A rule holds where lower < x <= upper for every feature (bounds may be -inf / +inf, following the
`x <= threshold` / `x > threshold` tests of the tree), and predicts coef @ x + intercept there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class Rule:
    lower: np.ndarray  # (n_features,) exclusive lower bounds
    upper: np.ndarray  # (n_features,) inclusive upper bounds
    coef: np.ndarray  # (n_features,) linear model; smoothing already folded in
    intercept: float

    def contains(self, X: np.ndarray) -> np.ndarray:
        X = np.atleast_2d(X)
        return np.all((X > self.lower) & (X <= self.upper), axis=1)

    def predict(self, X: np.ndarray) -> np.ndarray:
        return np.atleast_2d(X) @ self.coef + self.intercept


def leaf_boxes(left, right, feature, threshold, is_leaf, n_features: int):
    """Yield (node, lower, upper) for every leaf of a binary tree of `x <= threshold` tests, depth-first, left
    before right: the box of feature values that reaches the leaf (lower exclusive, upper inclusive)."""
    stack = [(0, np.full(n_features, -np.inf), np.full(n_features, np.inf))]
    while stack:
        node, lower, upper = stack.pop()
        if is_leaf(node):
            yield node, lower, upper
            continue
        f, t = feature[node], threshold[node]
        left_upper, right_lower = upper.copy(), lower.copy()
        left_upper[f] = min(upper[f], t)
        right_lower[f] = max(lower[f], t)
        stack.append((right[node], right_lower, upper))
        stack.append((left[node], lower, left_upper))
