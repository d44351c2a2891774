"""Fig. 5.16: the meta action model's decision tree, and its regions in the plane of the two features it relies
on most (the other features at their training medians) with the fresh episodes marked by what really happened."""

from __future__ import annotations

from pathlib import Path

import numpy as np

COLORS = {"better": "#2ca02c", "equal": "#7f7f7f", "worse": "#d62728"}
MARKERS = {"better": "o", "equal": "s", "worse": "x"}
GRID = 200


def _top_features(estimator, n: int = 2) -> list[int]:
    importance = np.asarray(estimator.feature_importances_, dtype=float)
    order = [int(i) for i in np.argsort(-importance, kind="stable")]
    return order[:n]


def _draw_rules(ax, model, classes: list[str]) -> None:
    """The stored tree's rules as text, each leaf coloured by the class it predicts."""
    lines = model.rules_text().splitlines()
    ax.axis("off")
    size = max(5.0, min(9.0, 300.0 / max(len(lines), 1)))
    step = 1.0 / (max(len(lines), 1) + 1)
    for k, line in enumerate(lines):
        leaf = next((c for c in classes if f": {c} (" in line), None)
        ax.text(0.0, 1.0 - (k + 1) * step, line, family="monospace", fontsize=size, va="center",
                color=COLORS[leaf] if leaf else "black", transform=ax.transAxes)
    ax.set_title(f"Meta action model: does refinement (h={model.horizon}) make execution better, equal or worse "
                 f"than greedy?\n{model.tree.n_leaves} leaves; training episodes per leaf: better/equal/worse",
                 fontsize=9, loc="left")


def draw_meta_model(path: Path, training, fresh_rows: list[dict]) -> Path:
    """The tree (left) and its predictions over its two most important features (right)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    from tailor.refinement.learning.meta_learning import episode_label
    from tailor.refinement.refine_plots import _save

    model, estimator = training.model, training.estimator
    classes = list(model.tree.classes)
    fig, (left, right) = plt.subplots(1, 2, figsize=(16, 7.5), gridspec_kw={"width_ratios": [1.25, 1]})
    _draw_rules(left, model, classes)
    top = _top_features(estimator)
    if len(top) < 2:
        top = (top + [0, 1])[:2]
    i, j = top
    X = training.X
    shown = [r for r in fresh_rows if tuple(tuple(s) for s in r["signature"]) == model.window]
    every = np.vstack([X] + [np.array([r["features"] for r in shown], dtype=float).reshape(-1, X.shape[1])])
    xs = np.linspace(every[:, i].min(), every[:, i].max(), GRID)
    ys = np.linspace(every[:, j].min(), every[:, j].max(), GRID)
    gx, gy = np.meshgrid(xs, ys)
    points = np.repeat(np.median(X, axis=0)[None, :], gx.size, axis=0)
    points[:, i], points[:, j] = gx.ravel(), gy.ravel()
    label = model.tree.label[model.tree.apply(points)].reshape(gx.shape)
    cmap = ListedColormap([COLORS[c] for c in classes])
    right.pcolormesh(gx, gy, label, cmap=cmap, vmin=-0.5, vmax=len(classes) - 0.5, alpha=0.25, shading="auto")
    for k, name in enumerate(classes):
        pts = np.array([r["features"] for r in shown if episode_label(r, model.equal_band) == k]).reshape(-1, X.shape[1])
        right.scatter(pts[:, i], pts[:, j], s=10, c=COLORS[name], marker=MARKERS[name],
                      label=f"fresh episode: {name} ({len(pts)})", linewidths=0.8)
    right.set_xlabel(model.feature_names[i])
    right.set_ylabel(model.feature_names[j])
    right.set_title("predicted regions (shaded; other features at their training medians)\n"
                    "and what refinement did on fresh episodes", fontsize=9)
    right.legend(loc="best", fontsize=7)
    fig.tight_layout()
    _save(fig, Path(path))
    plt.close(fig)
    return Path(path)
