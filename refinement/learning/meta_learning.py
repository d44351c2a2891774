"""Learning the meta action model (Sec. 5.5.4) from evaluated episodes: a decision tree predicting whether
refinement makes a situation's execution better, equal or worse than greedy execution (Table 5.5).

Each episode is labelled by its simulated gain 1 - t_refined / t_greedy: better above +1%, worse below -1%,
equal between (the tolerance `tailor evaluate` counts with); a refined execution that failed where greedy
succeeded is worse, the other way round better; where both failed the episode teaches nothing. The features
are those of the first refinement window at the greedy parameterization and refinement's predicted gain
(tailor.refinement.meta_filter.meta_features).

The tree is a scikit-learn DecisionTreeClassifier with a cost matrix, as the success classifier's: a "worse"
episode weighs `cost` times as much as the others, so the tree is pessimistic where refinement has hurt. The
cost and the leaf size are chosen by stratified cross-validation on the training episodes for what the filter
is for: among the candidates whose filtered mean improvement (refine only where "better" is predicted, keep
greedy elsewhere) is not below refining everything, the one leaving the fewest worse episodes; if there is none,
the one with the highest filtered mean improvement.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np

from tailor.errors import DataError
from tailor.refinement.models.decision_tree import LabelTree
from tailor.refinement.models.meta_model import EQUAL_BAND, MetaModel

CLASSES = ("better", "equal", "worse")  # Table 5.4's +, 0, -
BETTER, EQUAL, WORSE = range(3)
COSTS = (1.0, 2.0, 3.0, 5.0)  # weight of a "worse" episode relative to the others
MIN_SAMPLES_LEAF = (5, 10, 20, 40, 80)
CV_FOLDS = 5
MIN_EPISODES = 20  # fewer labelled episodes of one window cannot be split for cross-validation


@dataclass(frozen=True)
class MetaTraining:
    model: MetaModel
    estimator: object  # the fitted scikit-learn tree (for drawing it)
    X: np.ndarray
    y: np.ndarray  # class indices
    report: dict


def episode_label(row: dict, band: float = EQUAL_BAND) -> int | None:
    """The class index of an evaluated episode (see the module docstring), None where both executions failed."""
    if row["greedy_ok"] and row["refined_ok"]:
        gain = 1.0 - row["refined"] / row["greedy"]
        return BETTER if gain > band else WORSE if gain < -band else EQUAL
    if row["greedy_ok"]:
        return WORSE
    if row["refined_ok"]:
        return BETTER
    return None


def filtered_gain(rows_gain: np.ndarray, refine: np.ndarray) -> np.ndarray:
    """Per episode, the gain of the filtered execution: the refined one's where refined, else 0 (greedy)."""
    return np.where(refine, rows_gain, 0.0)


def _gain(row: dict) -> float:
    """The relative gain used to score filters during training: a failed execution counts as a 100% loss."""
    if row["greedy_ok"] and row["refined_ok"]:
        return 1.0 - row["refined"] / row["greedy"]
    return -1.0 if row["greedy_ok"] else 1.0


def training_set(rows: list[dict]) -> tuple[tuple[tuple[str, str], ...], tuple[str, ...], np.ndarray, np.ndarray,
                                            np.ndarray]:
    """(window, feature names, X, y, gain) of the labelled episodes of the most common first window."""
    labelled = [r for r in rows if episode_label(r) is not None]
    windows = Counter(tuple(tuple(s) for s in r["signature"]) for r in labelled)
    if not windows:
        raise DataError("no evaluated episode to learn the meta model from (every execution failed)")
    window = windows.most_common(1)[0][0]
    use = [r for r in labelled if tuple(tuple(s) for s in r["signature"]) == window]
    if len(use) < MIN_EPISODES:
        raise DataError(f"only {len(use)} labelled episodes to learn the meta model from (at least {MIN_EPISODES})")
    names = tuple(use[0]["feature_names"])
    X = np.array([r["features"] for r in use], dtype=float)
    y = np.array([episode_label(r) for r in use])
    gain = np.array([_gain(r) for r in use])
    return window, names, X, y, gain


def _classifier(cost: float, leaf: int, seed: int):
    from sklearn.tree import DecisionTreeClassifier

    return DecisionTreeClassifier(class_weight={BETTER: 1.0, EQUAL: 1.0, WORSE: cost}, min_samples_leaf=leaf,
                                  random_state=seed)


def choose_hyperparameters(X: np.ndarray, y: np.ndarray, gain: np.ndarray, seed: int,
                           costs: tuple[float, ...] = COSTS) -> tuple[float, int, list]:
    """(cost, min_samples_leaf) by stratified cross-validation (see the module docstring), and every
    candidate's cross-validated filtered mean improvement, worse share and accuracy."""
    from sklearn.model_selection import KFold, StratifiedKFold

    folds = CV_FOLDS if np.bincount(y, minlength=3)[np.bincount(y, minlength=3) > 0].min() >= CV_FOLDS else None
    splitter = (StratifiedKFold(folds, shuffle=True, random_state=seed) if folds
                else KFold(CV_FOLDS, shuffle=True, random_state=seed))
    splits = list(splitter.split(X, y))
    unfiltered = float(gain.mean())
    candidates = []
    for cost in costs:
        for leaf in MIN_SAMPLES_LEAF:
            predicted = np.zeros(len(y), dtype=int)
            for train, test in splits:
                tree = _classifier(cost, leaf, seed).fit(X[train], y[train])
                predicted[test] = tree.predict(X[test])
            refine = predicted == BETTER
            filtered = filtered_gain(gain, refine)
            worse = float(np.mean(refine & (y == WORSE)))
            candidates.append({"cost": cost, "min_samples_leaf": leaf, "improvement": float(filtered.mean()),
                               "worse_share": worse, "refined_share": float(refine.mean()),
                               "accuracy": float(np.mean(predicted == y))})
    keeping = [c for c in candidates if c["improvement"] >= unfiltered]
    best = (min(keeping, key=lambda c: (c["worse_share"], -c["improvement"])) if keeping
            else max(candidates, key=lambda c: (c["improvement"], -c["worse_share"])))
    return best["cost"], best["min_samples_leaf"], candidates


def label_tree(estimator, X: np.ndarray, y: np.ndarray) -> LabelTree:
    """A fitted tree as a LabelTree over CLASSES, with the unweighted training examples per class and node."""
    t = estimator.tree_
    path = estimator.decision_path(X)  # (examples, nodes) sparse: the nodes each example passes
    onehot = np.eye(len(CLASSES), dtype=np.int64)[y]
    counts = np.asarray(path.T @ onehot, dtype=np.int64)
    classes = np.asarray(estimator.classes_, dtype=np.int64)
    label = classes[np.argmax(t.value[:, 0, :], axis=1)]
    return LabelTree(children_left=t.children_left.astype(np.int64), children_right=t.children_right.astype(np.int64),
                     feature=np.where(t.children_left == -1, -1, t.feature).astype(np.int64),
                     threshold=np.where(t.children_left == -1, 0.0, t.threshold).astype(float),
                     label=label.astype(np.int64), counts=counts, classes=CLASSES)


def confusion(actual: np.ndarray, predicted: np.ndarray) -> dict:
    """Table 5.5: counts and shares of all episodes, rows actual, columns predicted, with the totals and the
    share predicted correctly."""
    actual, predicted = np.asarray(actual), np.asarray(predicted)
    n = len(actual)
    counts = [[int(np.sum((actual == a) & (predicted == p))) for p in range(len(CLASSES))]
              for a in range(len(CLASSES))]
    share = (lambda k: k / n) if n else (lambda k: None)
    return {"classes": list(CLASSES), "rows": "actual", "columns": "predicted", "episodes": n, "counts": counts,
            "shares": [[share(k) for k in row] for row in counts],
            "actual_totals": [share(sum(row)) for row in counts],
            "predicted_totals": [share(sum(row[p] for row in counts)) for p in range(len(CLASSES))],
            "correct": share(sum(counts[k][k] for k in range(len(CLASSES))))}


def learn_meta_model(rows: list[dict], horizon: int, seed: int = 0, cost: float | None = None) -> MetaTraining:
    """The meta model of the episodes `rows` (meta_episodes.meta_episode), its hyperparameters chosen by
    cross-validation (`cost`: the weight of a worse episode fixed, only the leaf size chosen) and its tree
    fitted on all of them (subtrees predicting one class merged into one leaf)."""
    window, names, X, y, gain = training_set(rows)
    cost, leaf, candidates = choose_hyperparameters(X, y, gain, seed, COSTS if cost is None else (float(cost),))
    estimator = _classifier(cost, leaf, seed).fit(X, y)
    tree = label_tree(estimator, X, y).simplified()
    report = {"episodes": int(len(y)), "labels": {c: int(np.sum(y == k)) for k, c in enumerate(CLASSES)},
              "equal_band": EQUAL_BAND, "cost": cost, "min_samples_leaf": leaf, "leaves": tree.n_leaves,
              "unfiltered_improvement": float(gain.mean()), "candidates": candidates,
              "training_confusion": confusion(y, np.array([CLASSES.index(p) for p in tree.predict(X)]))}
    model = MetaModel(window, names, tree, horizon, EQUAL_BAND, report)
    return MetaTraining(model, estimator, X, y, report)
