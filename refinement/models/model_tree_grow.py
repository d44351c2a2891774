"""Growing, pruning and smoothing an M5 model tree (Quinlan 1992; App. C.2 of the dissertation).

The tree is grown by standard-deviation reduction (SDR), a least-squares linear model is fitted in every
node, the tree is pruned bottom-up with M5's error estimate, and M5's smoothing is folded into each leaf's
coefficients, so the result is a flat `TreeArrays`: a binary tree whose leaves are single hyperplanes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tailor.refinement.models.model_tree_linear import fit_node_model, m5_factor

# Ridge on the unit-diagonal Gram matrix of the residual fit that guides splitting (keeps it solvable).
SPLIT_RIDGE = 1e-10
# A split's SDR must exceed this share of the node's SD: below it the "reduction" is rounding noise.
MIN_RELATIVE_SDR = 1e-12
# Mean absolute residuals below this share of the root SD count as this share (a perfect fit): it makes
# pruning deterministic on noise-free data, where both sides of the comparison are rounding noise.
RESIDUAL_FLOOR = 1e-9


@dataclass(frozen=True)
class GrowParams:
    min_samples_leaf: int
    max_depth: int | None
    sd_fraction: float
    prune: bool
    pruning_factor: float
    smoothing: bool
    smoothing_k: float
    split_target: str  # "residual": SDR of the node's linear-model residuals; "target": Quinlan's SDR of y
    node_features: str  # "tested": M5's features tested in the subtree; "all": every feature


@dataclass(frozen=True, eq=False)
class TreeArrays:
    """A fitted tree in preorder (node 0 is the root, a left child directly follows its parent).

    Internal nodes send x to `left` when x[feature] <= threshold, else to `right`; leaves have feature -1,
    threshold +inf, left == right == the node itself, and `leaf` = their index into coef/intercept.
    """

    feature: np.ndarray  # (n_nodes,) int
    threshold: np.ndarray  # (n_nodes,) float
    left: np.ndarray  # (n_nodes,) int
    right: np.ndarray  # (n_nodes,) int
    leaf: np.ndarray  # (n_nodes,) int, -1 for internal nodes
    n_samples: np.ndarray  # (n_nodes,) int, training samples that reached the node
    coef: np.ndarray  # (n_leaves, n_features) leaf hyperplanes, smoothing folded in
    intercept: np.ndarray  # (n_leaves,)


def grow_tree(X: np.ndarray, y: np.ndarray, p: GrowParams) -> TreeArrays:
    """Fit the whole M5 tree: grow by SDR, fit node models, prune, smooth, flatten."""
    nodes = _grow(X, y, p)
    if p.node_features == "all":
        tested = np.ones((len(nodes), X.shape[1]), dtype=bool)
    else:
        tested = _features_tested_below(nodes, X.shape[1])
    floor = RESIDUAL_FLOOR * _sd(y)
    for node, used in zip(nodes, tested):
        idx = node["idx"]
        node["model"] = fit_node_model(X[idx], y[idx], used, floor, p.pruning_factor)
    if p.prune:
        _prune(nodes, floor, p.pruning_factor)
    return _flatten(nodes, X.shape[1], p)


def _grow(X: np.ndarray, y: np.ndarray, p: GrowParams) -> list[dict]:
    """Grow depth-first by SDR; each node keeps its samples sorted along every feature (presorting)."""
    Xt = np.ascontiguousarray(X.T)
    order = np.ascontiguousarray(np.argsort(X, axis=0, kind="stable").T)  # (n_features, n_samples)
    root_sd = _sd(y)
    nodes: list[dict] = []
    go_left = np.zeros(len(y), dtype=bool)
    stack = [(order, 0, -1, 0)]  # (sorted sample indices, depth, parent id, side)
    while stack:
        S, depth, parent, side = stack.pop()
        nid = len(nodes)
        node = {"idx": S[0].copy(), "left": -1, "right": -1, "feature": -1, "threshold": np.inf}
        nodes.append(node)
        if parent >= 0:
            nodes[parent]["left" if side == 0 else "right"] = nid
        split = None
        if _may_split(S, y, depth, root_sd, p):
            target = _linear_residuals(X, y, S[0]) if p.split_target == "residual" else y[S[0]]
            split = _best_split(Xt, target, S, p.min_samples_leaf)
        if split is None:
            continue
        feature, k, threshold = split
        node["feature"], node["threshold"] = feature, threshold
        go_left[S[feature, :k]] = True
        keep = go_left[S]
        left_S = S[keep].reshape(S.shape[0], k)
        right_S = S[~keep].reshape(S.shape[0], -1)
        go_left[S[feature, :k]] = False
        stack.append((right_S, depth + 1, nid, 1))  # popped after the left subtree: preorder ids
        stack.append((left_S, depth + 1, nid, 0))
    return nodes


def _may_split(S: np.ndarray, y: np.ndarray, depth: int, root_sd: float, p: GrowParams) -> bool:
    """M5's stopping rule: too few samples, SD below sd_fraction of the root's, or the depth limit."""
    m = S.shape[1]
    if m < 2 * p.min_samples_leaf or (p.max_depth is not None and depth >= p.max_depth):
        return False
    return _sd(y[S[0]]) > p.sd_fraction * root_sd


def _linear_residuals(X: np.ndarray, y: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Residuals of a least-squares plane over all features on the node's samples, in the order of idx.

    Splitting on these instead of on y puts the splits where the node's linear model fails (kinks,
    steps) rather than along trends a leaf's hyperplane fits anyway; normal equations suffice here.
    """
    Xn, yn = X[idx], y[idx]
    Xc = Xn - Xn.sum(axis=0) / len(idx)
    yc = yn - yn.sum() / len(idx)
    norm = np.sqrt(np.einsum("ij,ij->j", Xc, Xc))
    norm[norm == 0] = 1.0
    Z = Xc / norm
    beta = np.linalg.solve(Z.T @ Z + SPLIT_RIDGE * np.eye(Z.shape[1]), Z.T @ yc)
    return yc - Z @ beta


def _best_split(Xt: np.ndarray, target: np.ndarray, S: np.ndarray, min_leaf: int) -> tuple[int, int, float] | None:
    """The (feature, left size, threshold) maximizing SDR of `target` (given in the order of S[0])."""
    m = S.shape[1]
    rank = np.empty(len(Xt[0]), dtype=np.intp)  # position of each sample in S[0]
    rank[S[0]] = np.arange(m)
    Ys = target[rank[S]]
    Ys = Ys - Ys[0].sum() / m  # centring keeps the sums of squares accurate
    Xs = np.take_along_axis(Xt, S, axis=1)
    k = np.arange(min_leaf, m - min_leaf + 1)  # candidate sizes of the left part
    cs = np.cumsum(Ys, axis=1)
    cs2 = np.cumsum(Ys * Ys, axis=1)
    total, total2 = cs[:, -1:], cs2[:, -1:]
    sl, sl2 = cs[:, k - 1], cs2[:, k - 1]
    kl, kr = k.astype(float), (m - k).astype(float)
    var_l = np.maximum(sl2 / kl - (sl / kl) ** 2, 0.0)
    var_r = np.maximum((total2 - sl2) / kr - ((total - sl) / kr) ** 2, 0.0)
    weighted_sd = (kl * np.sqrt(var_l) + kr * np.sqrt(var_r)) / m
    valid = Xs[:, k - 1] < Xs[:, k]  # never split between equal values
    if not valid.any():
        return None
    weighted_sd = np.where(valid, weighted_sd, np.inf)
    best = int(np.argmin(weighted_sd))  # first minimum: lowest feature index, then leftmost split
    feature, pos = divmod(best, len(k))
    sd = _sd(Ys[0])
    if sd - weighted_sd[feature, pos] <= MIN_RELATIVE_SDR * sd:
        return None
    a, b = float(Xs[feature, k[pos] - 1]), float(Xs[feature, k[pos]])
    threshold = a / 2 + b / 2
    if not a <= threshold < b:  # adjacent floats: the midpoint rounds up to b
        threshold = a
    return feature, int(k[pos]), threshold


def _sd(a: np.ndarray) -> float:
    """np.std of a 1-D array by the same operations, without its dispatch (called once or twice per node)."""
    d = a - a.sum() / len(a)
    return math.sqrt((d * d).sum() / len(a))


def _features_tested_below(nodes: list[dict], n_features: int) -> np.ndarray:
    """(n_nodes, n_features) mask: the features tested in each node's subtree (M5 restricts its model to them)."""
    tested = np.zeros((len(nodes), n_features), dtype=bool)
    for nid in range(len(nodes) - 1, -1, -1):  # children have larger preorder ids than their parent
        node = nodes[nid]
        if node["feature"] >= 0:
            tested[nid] = tested[node["left"]] | tested[node["right"]]
            tested[nid, node["feature"]] = True
    return tested


def _prune(nodes: list[dict], floor: float, pruning_factor: float) -> None:
    """Bottom-up: replace a subtree by its node's model where that model's estimated error is no worse.

    As in WEKA's M5P, the subtree is judged as one model on the node's samples whose parameters are
    those of all its leaves' models plus one per split: (n + v) / (n - v) * mean |residual|.
    """
    for nid in range(len(nodes) - 1, -1, -1):  # children have larger preorder ids than their parent
        node = nodes[nid]
        model = node["model"]
        if node["feature"] >= 0:
            left, right = nodes[node["left"]], nodes[node["right"]]
            n_l, n_r = len(left["idx"]), len(right["idx"])
            mae = (n_l * left["subtree_mae"] + n_r * right["subtree_mae"]) / (n_l + n_r)
            v = left["subtree_params"] + right["subtree_params"] + 1
            if model.error <= m5_factor(n_l + n_r, v, pruning_factor) * max(mae, floor):
                node["feature"], node["threshold"], node["left"], node["right"] = -1, np.inf, -1, -1
            else:
                node["subtree_mae"], node["subtree_params"] = mae, v
                continue
        node["subtree_mae"], node["subtree_params"] = model.mae, model.n_params


def _flatten(nodes: list[dict], n_features: int, p: GrowParams) -> TreeArrays:
    """Renumber the reachable nodes in preorder and fold M5 smoothing into each leaf's hyperplane."""
    feature, threshold, left, right, leaf, n_samples, coefs, intercepts = ([] for _ in range(8))
    stack = [(0, -1, 0, None)]  # (old id, new parent id, side, smoothed model of the parent's path)
    path_models: dict[int, list[tuple[np.ndarray, float, int]]] = {}
    while stack:
        old, parent, side, _ = stack.pop()
        node = nodes[old]
        new = len(feature)
        if parent >= 0:
            (left if side == 0 else right)[parent] = new
        model = node["model"]
        chain = (path_models[parent] if parent >= 0 else []) + [(model.coef, model.intercept, len(node["idx"]))]
        n_samples.append(len(node["idx"]))
        if node["feature"] < 0:
            feature.append(-1)
            threshold.append(np.inf)
            left.append(new)
            right.append(new)
            leaf.append(len(coefs))
            c, b = _smoothed(chain, p.smoothing_k) if p.smoothing else (model.coef, model.intercept)
            coefs.append(c)
            intercepts.append(b)
            continue
        feature.append(node["feature"])
        threshold.append(node["threshold"])
        left.append(-1)
        right.append(-1)
        leaf.append(-1)
        path_models[new] = chain
        stack.append((node["right"], new, 1, None))
        stack.append((node["left"], new, 0, None))
    return TreeArrays(
        feature=np.asarray(feature, dtype=np.intp),
        threshold=np.asarray(threshold, dtype=float),
        left=np.asarray(left, dtype=np.intp),
        right=np.asarray(right, dtype=np.intp),
        leaf=np.asarray(leaf, dtype=np.intp),
        n_samples=np.asarray(n_samples, dtype=np.intp),
        coef=np.asarray(coefs, dtype=float).reshape(-1, n_features),
        intercept=np.asarray(intercepts, dtype=float),
    )


def _smoothed(chain: list[tuple[np.ndarray, float, int]], k: float) -> tuple[np.ndarray, float]:
    """M5 smoothing p' = (n p + k q) / (n + k) from the leaf up to the root, on the coefficients."""
    coef, intercept, n_below = chain[-1]
    coef = coef.copy()
    for q_coef, q_intercept, n_node in reversed(chain[:-1]):
        coef = (n_below * coef + k * q_coef) / (n_below + k)
        intercept = (n_below * intercept + k * q_intercept) / (n_below + k)
        n_below = n_node
    return coef, float(intercept)
