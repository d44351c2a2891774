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
