"""An M5 model tree (Quinlan 1992) as a scikit-learn regressor: the action models of Chapter 4 / App. C.2.

Splits by standard-deviation reduction, a least-squares linear model in each node (over all features;
constant features get 0, near-collinear directions are cut by a truncated SVD rather than M5's attribute
restriction), bottom-up pruning with M5's (n + v) / (n - v) error estimate, and M5 smoothing folded into
each leaf's coefficients. So every leaf is one bounded hyperplane (`rules()`), which is what the analytic
minimization of App. C.3 needs; the rules print like WEKA's M5 output and save as JSON without pickle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted, validate_data

from tailor.errors import ModelFileError
from tailor.refinement.models.model_tree_grow import GrowParams, TreeArrays, grow_tree
from tailor.refinement.models.model_tree_io import export_text, tree_from_json, tree_to_json
from tailor.refinement.models.rules import Rule, leaf_boxes

HYPERPARAMETERS = (
    "min_samples_leaf",
    "max_depth",
    "sd_fraction",
    "prune",
    "pruning_factor",
    "smoothing",
    "smoothing_k",
    "split_target",
    "node_features",
)
SPLIT_TARGETS = ("residual", "target")
NODE_FEATURES = ("tested", "all")


# Batches up to this many rows find their leaf by one matrix product instead of a loop over tree levels (the
# same leaves). Larger products go to the BLAS, whose threads cost milliseconds on a shared machine: measured
# on 2 loaded cores with a 307-leaf tree, 100 rows took 3.6 ms as a product and 0.17 ms by the loop, 1-4 rows
# 14-33 us as a product and 100 us by the loop. The genetic algorithm's generations are batches of 100-150.
SMALL_BATCH_ROWS = 8
# The path matrix of that product is built only for trees with at most this many (internal x leaf) entries.
PATH_MATRIX_MAX_ENTRIES = 1_000_000


@dataclass(frozen=True, eq=False)
class _Router:
    """The tree in the shapes `predict` uses to find each row's leaf without a per-row Python loop.

    Large batches step all rows down one level per iteration (leaves loop onto themselves). Small batches
    (a GA's calls) evaluate every split test at once: with B[r, a] = 1 where row r goes right at internal
    node a, the row's leaf is the one whose path agrees on every test, i.e. where B @ path_matrix, which
    adds +1 for each right turn and -1 for each left turn on the leaf's path, reaches its right turns.
    """

    feature: np.ndarray  # (n_nodes,) feature tested, 0 at leaves (whose threshold +inf sends x to itself)
    threshold: np.ndarray
    children: np.ndarray  # (2 * n_nodes,) left, right of each node
    leaf: np.ndarray
    depth: int
    internal_feature: np.ndarray  # (n_internal,)
    internal_threshold: np.ndarray
    path_matrix: np.ndarray | None  # (n_internal, n_leaves) float32 of -1, 0, +1
    right_turns: np.ndarray  # (n_leaves,) float32


class ModelTree(RegressorMixin, BaseEstimator):
    """M5 model tree regressor.

    Parameters
    ----------
    min_samples_leaf : samples at least in each child of a split (M5P's -M); a node with fewer than twice
        as many is a leaf.
    max_depth : depth limit of the grown tree, or None.
    sd_fraction : a node whose target SD is at most this fraction of the root's is not split (M5: 0.05).
    prune : prune bottom-up where a node's model has no larger estimated error than its subtree.
    pruning_factor : multiplies v in the numerator of M5's error factor (n + f v) / (n - v); 1 is M5.
    smoothing : fold M5 smoothing p' = (n p + k q) / (n + k) along each leaf's path into the leaf.
    smoothing_k : the k of the smoothing formula (M5: 15).
    split_target : what SDR is computed on when choosing a split: "target" is Quinlan's SDR of y;
        "residual" (default) the SDR of the residuals of a plane fitted to the node over all features,
        which spends splits on kinks and steps instead of trends a leaf's plane fits anyway.
    node_features : the features a node's linear model starts from before M5's greedy elimination:
        "tested" (M5) those tested in its subtree (so unsplit leaves start constant), "all" every feature.
    """

    def __init__(
        self,
        min_samples_leaf: int = 4,
        max_depth: int | None = None,
        sd_fraction: float = 0.05,
        prune: bool = True,
        pruning_factor: float = 1.0,
        smoothing: bool = True,
        smoothing_k: float = 15.0,
        split_target: str = "residual",
        node_features: str = "tested",
    ):
        self.min_samples_leaf = min_samples_leaf
        self.max_depth = max_depth
        self.sd_fraction = sd_fraction
        self.prune = prune
        self.pruning_factor = pruning_factor
        self.smoothing = smoothing
        self.smoothing_k = smoothing_k
        self.split_target = split_target
        self.node_features = node_features

    def fit(self, X, y) -> "ModelTree":
        """Grow, prune and smooth the tree on X (n_samples, n_features) and the target y."""
        X, y = validate_data(self, X, y, dtype=np.float64, y_numeric=True)
        y = np.asarray(y, dtype=np.float64)
        self._set_tree(grow_tree(X, y, self._grow_params()))
        return self

    def predict(self, X) -> np.ndarray:
        """Each row's value on the hyperplane of the leaf it falls in (vectorized over rows)."""
        check_is_fitted(self)
        if not self._is_ready_matrix(X):
            X = validate_data(self, X, dtype=np.float64, reset=False)
        X = np.ascontiguousarray(X)  # einsum's summation order depends on the memory layout
        leaf = self._leaf_of(X)
        return np.einsum("ij,ij->i", X, self.tree_.coef[leaf]) + self.tree_.intercept[leaf]

    def predict_with_leaf(self, X) -> tuple[np.ndarray, np.ndarray]:
        """`predict(X)` and `apply(X)` from one routing of the rows (what a per-leaf correction needs)."""
        check_is_fitted(self)
        if not self._is_ready_matrix(X):
            X = validate_data(self, X, dtype=np.float64, reset=False)
        X = np.ascontiguousarray(X)
        leaf = self._leaf_of(X)
        return np.einsum("ij,ij->i", X, self.tree_.coef[leaf]) + self.tree_.intercept[leaf], leaf

    def apply(self, X) -> np.ndarray:
        """The index of the leaf (0 .. n_leaves_-1, the order of `rules()`) each row falls in."""
        check_is_fitted(self)
        return self._leaf_of(validate_data(self, X, dtype=np.float64, reset=False))

    def rules(self) -> list[Rule]:
        """One Rule per leaf, in leaf order: its box (lower exclusive, upper inclusive) and hyperplane."""
        check_is_fitted(self)
        tree = self.tree_
        return [Rule(lower, upper, tree.coef[tree.leaf[node]].copy(), float(tree.intercept[tree.leaf[node]]))
                for node, lower, upper in leaf_boxes(tree.left, tree.right, tree.feature, tree.threshold,
                                                     lambda k: tree.leaf[k] >= 0, self.n_features_in_)]

    def export_text(self, feature_names=None) -> str:
        """The tree and its linear models in WEKA's M5 layout (App. C.3.1)."""
        check_is_fitted(self)
        return export_text(self.tree_, self._feature_names(feature_names))

    def to_json(self) -> dict:
        """A JSON-serializable dict (schema tailor.model_tree/1); from_json gives identical predictions."""
        check_is_fitted(self)
        names = getattr(self, "feature_names_in_", None)
        return tree_to_json(
            self.tree_,
            {name: getattr(self, name) for name in HYPERPARAMETERS},
            self.n_features_in_,
            None if names is None else [str(n) for n in names],
        )

    @classmethod
    def from_json(cls, data: dict, source: str = "<model>") -> "ModelTree":
        """Rebuild a fitted tree from `to_json` output; raises ModelFileError naming `source` if invalid."""
        tree, hyper, n_features, names = tree_from_json(data, source, HYPERPARAMETERS)
        model = cls(**hyper)
        try:
            model._grow_params()
        except ValueError as exc:
            raise ModelFileError(f"hyperparameters: {exc}", file=source) from None
        model.n_features_in_ = n_features
        if names is not None:
            model.feature_names_in_ = np.asarray(names, dtype=object)
        model._set_tree(tree)
        return model

    # -- internals -------------------------------------------------------------------------------------

    def _grow_params(self) -> GrowParams:
        """Check the hyperparameters (here, not in __init__, as scikit-learn requires) and bundle them."""
        msl, depth = self.min_samples_leaf, self.max_depth
        if isinstance(msl, bool) or not isinstance(msl, (int, np.integer)) or msl < 1:
            raise ValueError(f"min_samples_leaf must be an integer >= 1, got {msl!r}")
        if depth is not None and (isinstance(depth, bool) or not isinstance(depth, (int, np.integer)) or depth < 0):
            raise ValueError(f"max_depth must be None or an integer >= 0, got {depth!r}")
        for name in ("sd_fraction", "pruning_factor", "smoothing_k"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 <= value < np.inf:
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
        if self.split_target not in SPLIT_TARGETS:
            raise ValueError(f"split_target must be one of {SPLIT_TARGETS}, got {self.split_target!r}")
        if self.node_features not in NODE_FEATURES:
            raise ValueError(f"node_features must be one of {NODE_FEATURES}, got {self.node_features!r}")
        return GrowParams(
            int(msl), None if depth is None else int(depth), float(self.sd_fraction), bool(self.prune),
            float(self.pruning_factor), bool(self.smoothing), float(self.smoothing_k), self.split_target,
            self.node_features,
        )

    def _set_tree(self, tree: TreeArrays) -> None:
        self.tree_ = tree
        self.n_leaves_ = int(len(tree.intercept))
        self._router = _make_router(tree)

    def _is_ready_matrix(self, X) -> bool:
        """True if validate_data would return X unchanged; skipping it (~60 us) keeps small calls fast."""
        return (
            type(X) is np.ndarray
            and X.dtype == np.float64
            and X.ndim == 2
            and X.shape[0] > 0
            and X.shape[1] == self.n_features_in_
            and not hasattr(self, "feature_names_in_")
            and bool(np.isfinite(X).all())
        )

    def _leaf_of(self, X: np.ndarray) -> np.ndarray:
        r = self._router
        n, d = X.shape
        if r.path_matrix is not None and n <= SMALL_BATCH_ROWS:
            right = (X.take(r.internal_feature, axis=1) > r.internal_threshold).astype(np.float32)
            return np.argmax(right @ r.path_matrix - r.right_turns, axis=1)  # exact: small integers
        flat = X.ravel()
        row_start = np.arange(0, n * d, d)
        node = np.zeros(n, dtype=np.intp)
        for _ in range(r.depth):
            go_right = flat.take(row_start + r.feature.take(node)) > r.threshold.take(node)
            node = r.children.take(2 * node + go_right)
        return r.leaf.take(node)

    def _feature_names(self, feature_names) -> list[str]:
        if feature_names is None:
            names = getattr(self, "feature_names_in_", None)
            return [f"x{i}" for i in range(self.n_features_in_)] if names is None else [str(n) for n in names]
        names = [str(n) for n in feature_names]
        if len(names) != self.n_features_in_:
            raise ValueError(f"feature_names has {len(names)} names, the tree has {self.n_features_in_} features")
        return names


def _make_router(tree: TreeArrays) -> _Router:
    n_nodes, n_leaves = len(tree.feature), len(tree.intercept)
    internal = np.flatnonzero(tree.leaf < 0)
    column = np.full(n_nodes, -1, dtype=np.intp)
    column[internal] = np.arange(len(internal))
    depth = np.zeros(n_nodes, dtype=np.intp)
    small = len(internal) * n_leaves <= PATH_MATRIX_MAX_ENTRIES
    path = np.zeros((n_nodes, len(internal)), dtype=np.float32) if small else None  # per node: its path
    for node in range(n_nodes):  # preorder: parents come before their children
        if tree.leaf[node] < 0:
            for child, turn in ((tree.left[node], -1.0), (tree.right[node], 1.0)):
                depth[child] = depth[node] + 1
                if path is not None:
                    path[child] = path[node]
                    path[child, column[node]] = turn
    path_matrix, right_turns = None, np.zeros(n_leaves, dtype=np.float32)
    if path is not None:
        leaf_nodes = np.flatnonzero(tree.leaf >= 0)[np.argsort(tree.leaf[tree.leaf >= 0])]
        path_matrix = np.ascontiguousarray(path[leaf_nodes].T)
        right_turns = (path_matrix > 0).sum(axis=0).astype(np.float32)
    return _Router(
        feature=np.where(tree.feature < 0, 0, tree.feature).astype(np.intp),
        threshold=tree.threshold.copy(),
        children=np.stack([tree.left, tree.right], axis=1).ravel().astype(np.intp),
        leaf=tree.leaf.copy(),
        depth=int(depth.max()),
        internal_feature=tree.feature[internal].astype(np.intp),
        internal_threshold=tree.threshold[internal].copy(),
        path_matrix=path_matrix,
        right_turns=right_turns,
    )
