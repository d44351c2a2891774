"""The linear model of one M5 node: least squares on the features tested below it, simplified greedily.

M5 (Quinlan 1992) restricts a node's model to the attributes tested in its subtree, then drops attributes
one at a time while that lowers the estimated error (n + v) / (n - v) * mean |residual|: fewer parameters
shrink the factor even when the residuals grow. Without that step small nodes keep noisy slopes and
pruning keeps far too many leaves.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

# Singular values below this share of the largest are dropped in the final least squares (min-norm fit).
LSTSQ_RCOND = 1e-10
# Ridge on the unit-diagonal Gram matrix used only to rank attributes for elimination (keeps it solvable).
SELECTION_RIDGE = 1e-10
# M5's error factor when a node has no more samples than its model has parameters (as in WEKA's M5P).
SMALL_NODE_FACTOR = 10.0


@dataclass(frozen=True, eq=False)
class NodeModel:
    coef: np.ndarray  # (n_features,), zero for features not in the model
    intercept: float
    mae: float  # mean absolute residual on the node's samples (at least the floor)
    n_params: int  # v: features in the model + 1
    error: float  # M5's estimated error m5_factor(n, v) * mae


def m5_factor(n: int, v: int, pruning_factor: float) -> float:
    """M5's pessimistic correction (n + v) / (n - v) of a model with v parameters fitted to n samples."""
    if n <= v:
        return SMALL_NODE_FACTOR
    return (n + pruning_factor * v) / (n - v)


def fit_node_model(X: np.ndarray, y: np.ndarray, used: np.ndarray, floor: float, pruning_factor: float) -> NodeModel:
    """The node's model: `used` features minus greedily eliminated ones, refitted by least squares.

    Mean absolute residuals below `floor` count as `floor`, so that on noise-free data ties between
    perfect fits go to the simpler model instead of to rounding noise.
    """
    n = len(y)
    if not used.any():  # the node's mean (what the general path below gives without features, done cheaply)
        mu_y = float(y.sum() / n)
        mae = max(float(np.abs(y - mu_y).sum() / n), floor)
        return NodeModel(np.zeros(X.shape[1]), mu_y, mae, 1, m5_factor(n, 1, pruning_factor) * mae)
    mu_x, mu_y = X.sum(axis=0) / n, float(y.sum() / n)  # np.mean's operations, without its overhead
    Xc, yc = X - mu_x, y - mu_y
    norm = np.sqrt(np.einsum("ij,ij->j", Xc, Xc))
    # A feature constant in the node (up to rounding) cannot be fitted; it is not a parameter either.
    keep = np.flatnonzero(used & (norm > 1e-12 * np.maximum(np.abs(mu_x), 1.0) * np.sqrt(n)))
    Z = Xc[:, keep] / norm[keep]

    def error(mae: np.ndarray | float, n_params: int) -> np.ndarray | float:
        return m5_factor(n, n_params, pruning_factor) * np.maximum(mae, floor)

    if len(keep):
        keep = _eliminate(Z, yc, keep, error)
    coef = np.zeros(X.shape[1])
    if len(keep):
        beta = np.linalg.lstsq(Xc[:, keep] / norm[keep], yc, rcond=LSTSQ_RCOND)[0]
        coef[keep] = beta / norm[keep]
    mae = max(float(np.abs(yc - Xc[:, keep] @ coef[keep]).sum() / n), floor)
    v = len(keep) + 1
    return NodeModel(coef, mu_y - float(mu_x @ coef), mae, v, m5_factor(n, v, pruning_factor) * mae)


def _eliminate(Z: np.ndarray, yc: np.ndarray, keep: np.ndarray, error) -> np.ndarray:
    """Greedy backward elimination on unit-norm centred columns Z; returns the features kept."""
    cols = np.arange(len(keep))
    G = Z.T @ Z + SELECTION_RIDGE * np.eye(len(keep))
    r = Z.T @ yc
    full = np.linalg.solve(G, r)
    n = len(yc)
    best = float(error(float(np.abs(yc - Z @ full).sum() / n), len(cols) + 1))
    while len(cols):
        k = len(cols)
        # Candidate j drops column j: its Gram row/column become the unit vector and its right side 0,
        # so one batched solve gives all k reduced fits (coefficient j comes out exactly 0).
        keep_j, unit_j, others = _drop_masks(k)
        Gs = G.take(cols, 0).take(cols, 1) * keep_j + unit_j
        rs = r[cols] * others
        B = np.linalg.solve(Gs, rs[..., None])[..., 0]  # (k candidates, k coefficients)
        mae = np.abs(yc[:, None] - Z[:, cols] @ B.T).sum(axis=0) / n
        errors = error(mae, k)  # k - 1 features + intercept
        j = int(np.argmin(errors))
        if errors[j] > best:
            break
        best = float(errors[j])
        cols = np.concatenate([cols[:j], cols[j + 1:]])
    return keep[cols]


@functools.cache
def _drop_masks(k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Masks for dropping each of k columns: candidate j's Gram matrix is G * keep[j] + unit[j] (row and column j
    zero, 1 at j, j), its right side r * others[j] (0 at j)."""
    keep = np.ones((k, k, k))
    diag = np.arange(k)
    keep[diag, diag, :] = 0.0
    keep[diag, :, diag] = 0.0
    unit = np.zeros((k, k, k))
    unit[diag, diag, diag] = 1.0
    others = 1.0 - np.eye(k)
    for mask in (keep, unit, others):
        mask.flags.writeable = False
    return keep, unit, others
