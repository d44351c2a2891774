"""Success classifiers (Sec. 4.2.2): does an action reach its goal without failing (e.g. without bumping a
object lying at its goal pose)?

A scikit-learn decision tree on the action's features, made pessimistic by a cost matrix: predicting
success for an episode that collides costs COST_FALSE_SUCCESS times as much as predicting a collision for
one that succeeds. A tree learner takes a cost matrix by reweighting the examples by the cost of
misclassifying them (Witten and Frank, 2005): here `class_weight={fail: cost * n_success / n_fail,
success: 1}`, the cost taken relative to the class balance, so cost 1 is a balanced tree whatever share of
the episodes collide (how often they do depends on the simulator's controllers).
The cost and the leaf size are chosen by stratified cross-validation on the training episodes; the tree is
then evaluated on fresh episodes as a confusion matrix (Table 4.4).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from sklearn.model_selection import StratifiedKFold
from sklearn.tree import DecisionTreeClassifier

from tailor.refinement.models.action_models import CollisionModel
from tailor.refinement.models.decision_tree import DecisionTree
from tailor.errors import DataError
from tailor.refinement.models.features import compute_features, feature_names, first_examples
from tailor.sims.episode import Episode

FAIL, SUCCESS = 0, 1
COSTS = (1.0, 1.5, 2.0, 3.0, 5.0, 8.0, 13.0)  # cost of a false "success" relative to a false "fail"
MIN_SAMPLES_LEAF = (5, 10, 20, 40)
CV_FOLDS = 5
TARGET_FALSE_SUCCESS = 0.015  # cross-validated share of failures predicted to succeed a candidate may have


@dataclass(frozen=True)
class CollisionTraining:
    model: CollisionModel
    report: dict


def labels(episodes: list[Episode]) -> np.ndarray:
    """1 where the episode reached its goal (success), 0 where it failed (any failure outcome)."""
    return np.array([SUCCESS if e.succeeded else FAIL for e in episodes])


def confusion(predicted: np.ndarray, observed: np.ndarray) -> dict:
    """Counts and shares of Table 4.4: rows predicted, columns observed."""
    predicted, observed = np.asarray(predicted, dtype=int), np.asarray(observed, dtype=int)
    n = len(observed)
    counts = {
        f"predicted_{p}_observed_{o}": int(np.sum((predicted == pv) & (observed == ov)))
        for p, pv in (("fail", FAIL), ("success", SUCCESS))
        for o, ov in (("fail", FAIL), ("success", SUCCESS))
    }
    observed_fail = int(np.sum(observed == FAIL))
    return {
        "episodes": n,
        "counts": counts,
        "accuracy": float(np.mean(predicted == observed)) if n else float("nan"),
        "false_success": counts["predicted_success_observed_fail"] / observed_fail if observed_fail else 0.0,
        "predicted_fail": float(np.mean(predicted == FAIL)) if n else float("nan"),
        "observed_fail": observed_fail / n if n else float("nan"),
    }


def make_classifier(cost: float, balance: float, min_samples_leaf: int, seed: int) -> DecisionTreeClassifier:
    """A tree whose failures weigh `cost * balance` (balance = n_success / n_fail) against successes."""
    return DecisionTreeClassifier(class_weight={FAIL: cost * balance, SUCCESS: 1.0},
                                  min_samples_leaf=min_samples_leaf, random_state=seed)


def class_balance(y: np.ndarray) -> float:
    """n_success / n_fail (1 if either class is missing: the tree then has one leaf anyway)."""
    counts = np.bincount(y, minlength=2)
    return float(counts[SUCCESS] / counts[FAIL]) if counts.min() > 0 else 1.0


def choose_hyperparameters(X: np.ndarray, y: np.ndarray, seed: int) -> tuple[float, int, list[dict]]:
    """(cost, min_samples_leaf) with the best cross-validated accuracy among the candidates whose
    false-success share stays within TARGET_FALSE_SUCCESS (the most pessimistic one if none does)."""
    folds = StratifiedKFold(n_splits=min(CV_FOLDS, int(np.bincount(y, minlength=2).min())), shuffle=True,
                            random_state=seed)
    table = []
    for cost in COSTS:
        for leaf in MIN_SAMPLES_LEAF:
            predicted = np.empty_like(y)
            for train, held_out in folds.split(X, y):
                classifier = make_classifier(cost, class_balance(y), leaf, seed).fit(X[train], y[train])
                predicted[held_out] = classifier.predict(X[held_out])
            scores = confusion(predicted, y)
            table.append({"cost": cost, "min_samples_leaf": leaf, "accuracy": scores["accuracy"],
                          "false_success": scores["false_success"]})
    admissible = [row for row in table if row["false_success"] <= TARGET_FALSE_SUCCESS]
    if admissible:
        best = max(admissible, key=lambda row: (row["accuracy"], -row["false_success"], -row["cost"]))
    else:
        best = min(table, key=lambda row: (row["false_success"], -row["accuracy"]))
    return best["cost"], best["min_samples_leaf"], table


def tree_arrays(classifier: DecisionTreeClassifier) -> DecisionTree:
    """The fitted tree as plain arrays; each node's class is the classifier's own (weighted argmax) choice."""
    tree = classifier.tree_
    predicted_class = classifier.classes_[np.argmax(tree.value[:, 0, :], axis=1)]
    return DecisionTree(
        children_left=tree.children_left.astype(np.int64),
        children_right=tree.children_right.astype(np.int64),
        feature=np.where(tree.children_left == -1, -1, tree.feature).astype(np.int64),
        threshold=np.where(tree.children_left == -1, 0.0, tree.threshold).astype(float),
        success=predicted_class == SUCCESS,
        samples=tree.n_node_samples.astype(np.int64),
    )


def train_collision_model(
    action: str,
    episodes: list[Episode],
    fresh: list[Episode],
    seed: int,
    feature_space: str,
    step: Callable[[str], None] = lambda label: None,
) -> CollisionTraining:
    """Learn the pessimistic success tree from `episodes`; evaluate it on the `fresh` ones."""
    y = labels(episodes)
    if not episodes or not fresh:
        raise DataError(f"{action} collision data: {len(episodes)} training and {len(fresh)} fresh episodes")
    X = compute_features(feature_space, first_examples(episodes)[0])
    step("collision: choosing cost and leaf size")
    note = ""
    if np.bincount(y, minlength=2).min() >= CV_FOLDS:
        cost, leaf, table = choose_hyperparameters(X, y, seed)
    else:  # too few of one outcome to cross-validate: the most pessimistic candidate
        cost, leaf, table = max(COSTS), max(MIN_SAMPLES_LEAF), []
        note = f"fewer than {CV_FOLDS} episodes of one outcome: no cross-validation, most pessimistic candidate"
    step("collision: fitting the tree")
    classifier = make_classifier(cost, class_balance(y), leaf, seed).fit(X, y)
    tree = tree_arrays(classifier).simplified()  # same predictions, no split between leaves that agree
    # each node's training episodes and how many of them failed, counted by routing the rows through the final
    # tree (sklearn's `value` is weighted by the class weights): each leaf's failure probability (assertion)
    tree = tree.counted(X, y == FAIL)
    X_fresh = compute_features(feature_space, first_examples(fresh)[0])
    evaluation = confusion(tree.predict(X_fresh), labels(fresh))
    # the same counts from the fresh episodes, which chose no split: a leaf cut around a chance cluster of failed
    # training episodes is not believed on its training episodes alone (CollisionModel.failure_probability)
    held = tree.counted(X_fresh, labels(fresh) == FAIL)
    outcomes, counts = np.unique([e.outcome for e in episodes], return_counts=True)
    report = {
        "action": action,
        "episodes": len(episodes),
        "outcomes": {str(o): int(c) for o, c in zip(outcomes, counts)},
        "cost_false_success": cost,
        "class_weight_fail": cost * class_balance(y),
        "min_samples_leaf": leaf,
        "leaves": tree.n_leaves,
        "fresh_episodes": len(fresh),
        "accuracy": evaluation["accuracy"],
        "false_success": evaluation["false_success"],
        "confusion": evaluation,
        "cross_validation": table,
        "fresh_leaves": {"samples": held.samples.tolist(), "failures": held.failures.tolist()},
        "note": note,
        "seed": seed,
    }
    model = CollisionModel(action, feature_space, feature_names(feature_space), tree, report)
    return CollisionTraining(model, report)
