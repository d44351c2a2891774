"""How sure an action model is of a prediction: the held-out error of the leaf it comes from.

Each leaf of a duration model tree gets a spread (s): the mean absolute error, on episodes the model did not
learn from, of the predictions that fall in that leaf. It is measured by K-fold cross-fitting at training time
(every successful episode is predicted once by a tree fitted on the other folds; its first example is then
routed to the stored tree's leaf), and shrunk towards the overall held-out error with PRIOR_EPISODES
pseudo-episodes, so a leaf few held-out episodes reach does not get a spread of 0 by luck. Held-out, not
training, residuals: the leaves a tree fits too well are exactly where the optimizer's curse lives.

The spread is constant in a leaf, so a risk-aware objective (duration + lambda * spread) is still one affine
function per leaf box, and the analytic minimization stays exact.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass, replace

import numpy as np
from tailor.errors import ModelFileError
from tailor.refinement.models.rules import Rule

KIND = "held_out_leaf_mae"  # the only kind so far: the JSON names it, so another can be added compatibly
FOLDS = 4  # cross-fitting folds: each fold's tree learns from three quarters, as the reported MAE's does
PRIOR_EPISODES = 5.0  # pseudo-episodes of the overall held-out MAE in each leaf's estimate


@dataclass(frozen=True, eq=False)
class LeafUncertainty:
    """Per leaf of a model tree (in leaf order): spread (s) and the held-out episodes it was measured on."""

    spread: np.ndarray  # (n_leaves,) s
    held_out: np.ndarray  # (n_leaves,) episodes
    overall: float  # the held-out MAE over all episodes (s): the spread of a leaf no episode reached
    folds: int = FOLDS
    prior_episodes: float = PRIOR_EPISODES

    @classmethod
    def from_residuals(cls, leaf: np.ndarray, residual: np.ndarray, n_leaves: int, folds: int = FOLDS,
                       prior_episodes: float = PRIOR_EPISODES) -> LeafUncertainty:
        """Shrunk per-leaf mean |residual| from held-out residuals and the stored tree's leaf of each."""
        error = np.abs(np.asarray(residual, dtype=float))
        leaf = np.asarray(leaf, dtype=np.intp)
        overall = float(error.mean()) if len(error) else 0.0
        count = np.bincount(leaf, minlength=n_leaves).astype(float)
        total = np.bincount(leaf, weights=error, minlength=n_leaves)
        spread = (total + prior_episodes * overall) / (count + prior_episodes)
        return cls(spread, count.astype(np.intp), overall, folds, prior_episodes)

    def of_leaves(self, leaf: np.ndarray) -> np.ndarray:
        return self.spread[leaf]

    def to_json(self) -> dict:
        return {
            "kind": KIND,
            "folds": int(self.folds),
            "prior_episodes": float(self.prior_episodes),
            "overall": float(self.overall),
            "spread": [float(v) for v in self.spread],
            "held_out": [int(v) for v in self.held_out],
        }

    @classmethod
    def from_json(cls, data, n_leaves: int, source: str) -> LeafUncertainty:
        """Check and rebuild; any problem is a ModelFileError naming `source`."""
        def fail(message: str) -> ModelFileError:
            return ModelFileError(f"uncertainty: {message}", file=source)

        if not isinstance(data, dict):
            raise fail("must be an object")
        if data.get("kind") != KIND:
            raise fail(f"kind is {data.get('kind')!r}, expected {KIND!r}")
        spread, held_out = data.get("spread"), data.get("held_out")
        if not isinstance(spread, list) or len(spread) != n_leaves or not all(_nonnegative(v) for v in spread):
            raise fail(f"spread must be a list of {n_leaves} finite numbers >= 0 (one per leaf)")
        if not isinstance(held_out, list) or len(held_out) != n_leaves or not all(_count(v) for v in held_out):
            raise fail(f"held_out must be a list of {n_leaves} integers >= 0 (one per leaf)")
        folds, prior, overall = data.get("folds"), data.get("prior_episodes"), data.get("overall")
        if not _count(folds) or folds < 2:
            raise fail(f"folds must be an integer >= 2, got {folds!r}")
        if not _nonnegative(prior) or not _nonnegative(overall):
            raise fail("prior_episodes and overall must be finite numbers >= 0")
        return cls(np.array(spread, dtype=float), np.array(held_out, dtype=np.intp), float(overall), int(folds),
                   float(prior))


class RiskAdjusted:
    """A model tree whose every leaf predicts duration + risk * spread: what a risk-aware objective sums.

    Quacks like the tree for the optimizers (`predict`, `rules`): the spread is constant in a leaf, so each
    rule only gets a larger intercept and the analytic minimization stays exact."""

    def __init__(self, tree, uncertainty: LeafUncertainty, risk: float) -> None:
        if len(uncertainty.spread) != tree.n_leaves_:
            raise ValueError(f"the uncertainty has {len(uncertainty.spread)} leaves, the tree {tree.n_leaves_}")
        self.tree, self.risk = tree, float(risk)
        self.penalty = self.risk * uncertainty.spread  # (n_leaves,) s

    def predict(self, X) -> np.ndarray:
        duration, leaf = self.tree.predict_with_leaf(X)
        return duration + self.penalty[leaf]

    def rules(self) -> list[Rule]:
        return [replace(rule, intercept=rule.intercept + float(p)) for rule, p in zip(self.tree.rules(), self.penalty)]


_adjusted: weakref.WeakKeyDictionary[object, dict[float, RiskAdjusted]] = weakref.WeakKeyDictionary()


def risk_adjusted(tree, uncertainty: LeafUncertainty, risk: float) -> RiskAdjusted:
    """One RiskAdjusted per (tree, risk), so the optimizers' caches of its rules last across windows."""
    per_risk = _adjusted.setdefault(tree, {})
    if float(risk) not in per_risk:
        per_risk[float(risk)] = RiskAdjusted(tree, uncertainty, risk)
    return per_risk[float(risk)]


def _nonnegative(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value >= 0


def _count(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0
