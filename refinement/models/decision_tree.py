"""A learned decision tree held as plain arrays (App. C.1): predicts without scikit-learn, saves as JSON.

The arrays are those of a fitted `sklearn.tree.DecisionTreeClassifier.tree_` (node i tests
`x[feature[i]] <= threshold[i]`, going to children_left[i] if true); leaves have children -1 and carry
the predicted class. Each leaf is also a box lower < x <= upper, the form subgoal assertion needs.
`DecisionTree` predicts success or failure (a success classifier); `LabelTree` one of several named classes
(the meta action model's better / equal / worse, Sec. 5.5.4).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from tailor.refinement.models.rules import leaf_boxes

LEAF = -1


def route(left: np.ndarray, right: np.ndarray, feature: np.ndarray, threshold: np.ndarray, X: np.ndarray
          ) -> np.ndarray:
    """The leaf index each row of X (n, f) reaches in a tree of `x <= threshold` tests."""
    # scikit-learn compares features as float32 against float64 thresholds; do the same for equal answers
    X = np.atleast_2d(np.asarray(X, dtype=float)).astype(np.float32).astype(np.float64)
    node = np.zeros(len(X), dtype=np.int64)
    active = left[node] != LEAF
    while np.any(active):
        rows = np.flatnonzero(active)
        at = node[rows]
        go_left = X[rows, feature[at]] <= threshold[at]
        node[rows] = np.where(go_left, left[at], right[at])
        active[rows] = left[node[rows]] != LEAF
    return node


def check_structure(left: np.ndarray, right: np.ndarray, arrays: dict[str, np.ndarray]) -> None:
    """ValueError unless the arrays describe one binary tree: equal lengths, leaves marked in both children,
    every other node referenced once as a child."""
    n = len(left)
    for name, array in {"children_right": right, **arrays}.items():
        if np.shape(array) != (n,):
            raise ValueError(f"{name} must have shape ({n},), got {np.shape(array)}")
    if n == 0:
        raise ValueError("a tree needs at least one node")
    inner = left != LEAF
    if np.any((right == LEAF) != ~inner):
        raise ValueError("a node has exactly one child")
    children = np.concatenate([left[inner], right[inner]])
    if np.any((children < 1) | (children >= n)) or len(np.unique(children)) != len(children):
        raise ValueError("children must be distinct node indices in 1..nodes-1")


@dataclass(frozen=True, eq=False)
class LeafBox:
    """The region of one leaf: lower < x <= upper per feature (bounds may be infinite)."""

    lower: np.ndarray
    upper: np.ndarray
    success: bool
    samples: int

    def contains(self, X: np.ndarray) -> np.ndarray:
        X = np.atleast_2d(X)
        return np.all((X > self.lower) & (X <= self.upper), axis=1)


class _Routed:
    """What every tree stored as arrays (children_left, children_right, feature, threshold) does alike."""

    @property
    def n_leaves(self) -> int:
        return int(np.sum(self.children_left == LEAF))

    def apply(self, X: np.ndarray) -> np.ndarray:
        """The leaf index reached by each row of X (n, f)."""
        return route(self.children_left, self.children_right, self.feature, self.threshold, X)


@dataclass(frozen=True, eq=False)
class DecisionTree(_Routed):
    """A binary decision tree predicting success (True) or failure (False) per leaf."""

    children_left: np.ndarray  # (nodes,) int, -1 at leaves
    children_right: np.ndarray  # (nodes,) int, -1 at leaves
    feature: np.ndarray  # (nodes,) int, tested feature (ignored at leaves)
    threshold: np.ndarray  # (nodes,) float, go left if x <= threshold
    success: np.ndarray  # (nodes,) bool, the class predicted at the node
    samples: np.ndarray  # (nodes,) int, training episodes reaching the node
    # (nodes,) int, how many of those failed (None: not recorded, as in trees written before they were)
    failures: np.ndarray | None = None

    def __post_init__(self) -> None:
        check_structure(self.children_left, self.children_right,
                        {name: getattr(self, name) for name in ("feature", "threshold", "success", "samples")})
        if self.failures is not None:
            check_failures(self.failures, self.samples)

    def predict(self, X: np.ndarray) -> np.ndarray:
        return self.success[self.apply(X)]

    def simplified(self) -> DecisionTree:
        """The same predictions with every subtree whose leaves all agree replaced by one leaf (fewer rules)."""
        keep, verdict, structure = collapse_uniform(self, lambda node: bool(self.success[node]))
        return DecisionTree(
            **structure,
            success=np.array([bool(self.success[k]) if verdict[k] is None else verdict[k] for k in keep]),
            samples=np.array([int(self.samples[k]) for k in keep]),
            failures=None if self.failures is None else np.array([int(self.failures[k]) for k in keep]),
        )

    def counted(self, X: np.ndarray, failed: np.ndarray) -> DecisionTree:
        """The same tree with `samples` and `failures` counted by routing the rows of X (n, f) through it, `failed`
        (n,) marking the rows that failed: unweighted counts, whatever class weights the learner used."""
        none = np.zeros(len(self.children_left), dtype=np.int64)
        return replace(self, samples=none, failures=none).counted_more(self.apply(X), failed)

    def counted_more(self, leaves: np.ndarray, failed: np.ndarray) -> DecisionTree:
        """The same tree with rows that reached `leaves` (n,) counted into `samples` and `failures` too (`failed`
        (n,) marking those that failed), every node on their way included."""
        n = len(self.children_left)
        samples = self.samples + np.bincount(leaves, minlength=n).astype(np.int64)
        failures = (self.failures if self.failures is not None else np.zeros(n, np.int64)) + np.bincount(
            leaves, weights=np.asarray(failed, dtype=bool), minlength=n).astype(np.int64)
        for node in reversed(preorder(self.children_left, self.children_right)):  # inner nodes: sum of children
            if self.children_left[node] != LEAF:
                for counts in (samples, failures):
                    counts[node] = counts[self.children_left[node]] + counts[self.children_right[node]]
        return replace(self, samples=samples, failures=failures)

    def failure_probability(self, nodes: np.ndarray) -> np.ndarray | None:
        """The Laplace estimate (failed + 1) / (samples + 2) of failing at each of `nodes` from the training episodes
        that reached it (None where the failures were not recorded)."""
        if self.failures is None:
            return None
        nodes = np.asarray(nodes, dtype=np.int64)
        return (self.failures[nodes] + 1.0) / (self.samples[nodes] + 2.0)

    def leaf_boxes(self, n_features: int) -> list[LeafBox]:
        """Every leaf as a box in feature space, in depth-first order (left before right)."""
        return [LeafBox(lower, upper, bool(self.success[node]), int(self.samples[node]))
                for node, lower, upper in leaf_boxes(self.children_left, self.children_right, self.feature,
                                                     self.threshold, lambda k: self.children_left[k] == LEAF,
                                                     n_features)]

    def success_boxes(self, n_features: int) -> list[LeafBox]:
        """The leaves predicting success, each box shrunk to where `predict` (which compares features as float32)
        surely reaches it: every point inside is predicted to succeed, also next to a split (for optimizers that
        place values on box bounds)."""
        out = []
        for box in self.leaf_boxes(n_features):
            if not box.success:
                continue
            with np.errstate(over="ignore"):
                low32, high32 = box.lower.astype(np.float32), box.upper.astype(np.float32)
            # x > lower is safe once x >= the first float32 above lower; x <= upper once x <= the last below it
            low = np.where(low32 <= box.lower, np.nextafter(low32, np.float32(np.inf)), low32).astype(float)
            high = np.where(high32 > box.upper, np.nextafter(high32, np.float32(-np.inf)), high32).astype(float)
            low = np.where(np.isfinite(box.lower), low, -np.inf)
            high = np.where(np.isfinite(box.upper), high, np.inf)
            out.append(LeafBox(low, high, True, box.samples))
        return out

    def export_text(self, feature_names: tuple[str, ...], labels: tuple[str, str] = ("Fail", "Success")) -> str:
        """Readable rules, one test per line, indented by depth (like WEKA's J48 output, Fig. 4.8)."""
        lines: list[str] = []

        def visit(node: int, depth: int) -> None:
            if self.children_left[node] == LEAF:
                return
            name, t = feature_names[self.feature[node]], self.threshold[node]
            for child, op in ((self.children_left[node], "<="), (self.children_right[node], ">")):
                text = f"{'|   ' * depth}{name} {op} {t:.3f}"
                if self.children_left[child] == LEAF:
                    text += f": {labels[int(self.success[child])]} ({self.samples[child]})"
                lines.append(text)
                visit(child, depth + 1)

        if self.children_left[0] == LEAF:
            lines.append(f": {labels[int(self.success[0])]} ({self.samples[0]})")
        visit(0, 0)
        return "\n".join(lines)

    def to_json(self) -> dict:
        return {
            "children_left": self.children_left.tolist(),
            "children_right": self.children_right.tolist(),
            "feature": self.feature.tolist(),
            "threshold": self.threshold.tolist(),
            "success": self.success.tolist(),
            "samples": self.samples.tolist(),
            **({} if self.failures is None else {"failures": self.failures.tolist()}),
        }

    @classmethod
    def from_json(cls, data: dict) -> DecisionTree:
        """Raises ValueError/KeyError/TypeError on malformed data (the loader names the file). `failures` is
        optional (trees written before it was recorded load without it)."""
        failures = data.get("failures")
        if failures is not None and (not isinstance(failures, list) or not all(
                isinstance(f, int) and not isinstance(f, bool) for f in failures)):
            raise ValueError("failures must be a list of integers, one per node")
        return cls(
            children_left=np.asarray(data["children_left"], dtype=np.int64),
            children_right=np.asarray(data["children_right"], dtype=np.int64),
            feature=np.asarray(data["feature"], dtype=np.int64),
            threshold=np.asarray(data["threshold"], dtype=float),
            success=np.asarray(data["success"], dtype=bool),
            samples=np.asarray(data["samples"], dtype=np.int64),
            failures=None if failures is None else np.asarray(failures, dtype=np.int64),
        )


def check_failures(failures: np.ndarray, samples: np.ndarray) -> None:
    """ValueError unless `failures` holds one count per node, each between 0 and the node's samples."""
    if np.shape(failures) != np.shape(samples):
        raise ValueError(f"failures must have one count per node ({len(samples)}), got shape {np.shape(failures)}")
    if not np.issubdtype(np.asarray(failures).dtype, np.integer):
        raise ValueError("failures must be integers")
    if np.any(failures < 0) or np.any(failures > samples):
        node = int(np.flatnonzero((failures < 0) | (failures > samples))[0])
        raise ValueError(f"failures at node {node} ({int(failures[node])}) must lie in 0..samples "
                         f"({int(samples[node])})")


def preorder(left: np.ndarray, right: np.ndarray) -> list[int]:
    """The nodes of a tree in preorder (every parent before its children)."""
    order, stack = [], [0]
    while stack:
        node = stack.pop()
        order.append(node)
        if left[node] != LEAF:
            stack += [int(right[node]), int(left[node])]
    return order



@dataclass(frozen=True, eq=False)
class LabelTree(_Routed):
    """A binary decision tree predicting one of the named `classes` per leaf (`label`: the class index), with
    the training examples of each class that reached every node (`counts`, (nodes, classes))."""

    children_left: np.ndarray  # (nodes,) int, -1 at leaves
    children_right: np.ndarray  # (nodes,) int, -1 at leaves
    feature: np.ndarray  # (nodes,) int, tested feature (ignored at leaves)
    threshold: np.ndarray  # (nodes,) float, go left if x <= threshold
    label: np.ndarray  # (nodes,) int, index into classes of the class predicted at the node
    counts: np.ndarray  # (nodes, classes) int, training examples of each class reaching the node
    classes: tuple[str, ...]

    def __post_init__(self) -> None:
        check_structure(self.children_left, self.children_right,
                        {"feature": self.feature, "threshold": self.threshold, "label": self.label})
        if len(self.classes) < 2 or len(set(self.classes)) != len(self.classes):
            raise ValueError(f"classes must be at least two distinct names, got {list(self.classes)}")
        if np.shape(self.counts) != (len(self.children_left), len(self.classes)):
            raise ValueError(f"counts must have shape ({len(self.children_left)}, {len(self.classes)}), "
                             f"got {np.shape(self.counts)}")
        if np.any((self.label < 0) | (self.label >= len(self.classes))):
            raise ValueError(f"a label lies outside 0..{len(self.classes) - 1}")
        if np.any(self.counts < 0):
            raise ValueError("counts must not be negative")
        if not np.all(np.isfinite(self.threshold)):
            raise ValueError("thresholds must be finite numbers")

    def predict(self, X: np.ndarray) -> np.ndarray:
        """The class name predicted for each row of X (n, f)."""
        return np.array(self.classes, dtype=object)[self.label[self.apply(X)]]

    def simplified(self) -> LabelTree:
        """The same predictions with every subtree whose leaves all predict one class replaced by one leaf (its
        counts those of the subtree's root): fewer, readable rules."""
        keep, verdict, structure = collapse_uniform(self, lambda node: int(self.label[node]))
        return LabelTree(
            **structure,
            label=np.array([int(self.label[k]) if verdict[k] is None else verdict[k] for k in keep]),
            counts=np.array([self.counts[k] for k in keep], dtype=np.int64).reshape(len(keep), len(self.classes)),
            classes=self.classes,
        )

    def export_text(self, feature_names: tuple[str, ...]) -> str:
        """Readable rules like WEKA's J48 output: one test per line, indented by depth, each leaf with its class
        and its training examples per class."""
        lines: list[str] = []

        def leaf_text(node: int) -> str:
            counts = "/".join(str(int(c)) for c in self.counts[node])
            return f": {self.classes[self.label[node]]} ({counts})"

        def visit(node: int, depth: int) -> None:
            if self.children_left[node] == LEAF:
                return
            name, t = feature_names[self.feature[node]], self.threshold[node]
            for child, op in ((self.children_left[node], "<="), (self.children_right[node], ">")):
                text = f"{'|   ' * depth}{name} {op} {t:.3f}"
                if self.children_left[child] == LEAF:
                    text += leaf_text(child)
                lines.append(text)
                visit(child, depth + 1)

        if self.children_left[0] == LEAF:
            lines.append(leaf_text(0))
        visit(0, 0)
        return "\n".join(lines)

    def to_json(self) -> dict:
        return {
            "classes": list(self.classes),
            "children_left": self.children_left.tolist(),
            "children_right": self.children_right.tolist(),
            "feature": self.feature.tolist(),
            "threshold": self.threshold.tolist(),
            "label": self.label.tolist(),
            "counts": self.counts.tolist(),
        }

    @classmethod
    def from_json(cls, data: dict) -> LabelTree:
        """Raises ValueError/KeyError/TypeError on malformed data (the loader names the file)."""
        classes = data["classes"]
        if not isinstance(classes, list) or not all(isinstance(c, str) for c in classes):
            raise ValueError("classes must be a list of names")
        counts = np.asarray(data["counts"], dtype=np.int64)
        return cls(
            children_left=np.asarray(data["children_left"], dtype=np.int64),
            children_right=np.asarray(data["children_right"], dtype=np.int64),
            feature=np.asarray(data["feature"], dtype=np.int64),
            threshold=np.asarray(data["threshold"], dtype=float),
            label=np.asarray(data["label"], dtype=np.int64),
            counts=counts,
            classes=tuple(classes),
        )


def collapse_uniform(tree, leaf_class) -> tuple[list[int], dict[int, object], dict[str, np.ndarray]]:
    """The nodes kept when every subtree whose leaves all predict one class (`leaf_class(node)` at a leaf) becomes
    one leaf: the kept nodes in preorder, the class each node's subtree predicts (None: mixed), and the kept
    tree's structure arrays (children_left, children_right, feature, threshold)."""
    verdict: dict[int, object] = {}

    def visit(node: int):
        if tree.children_left[node] == LEAF:
            verdict[node] = leaf_class(node)
        else:
            left, right = visit(tree.children_left[node]), visit(tree.children_right[node])
            verdict[node] = left if left is not None and left == right else None
        return verdict[node]

    visit(0)
    keep: list[int] = []
    new_index: dict[int, int] = {}
    stack = [0]
    while stack:  # preorder walk that stops at uniform subtrees
        node = stack.pop()
        new_index[node] = len(keep)
        keep.append(node)
        if verdict[node] is None:
            stack += [int(tree.children_right[node]), int(tree.children_left[node])]
    leaf = [verdict[k] is not None for k in keep]
    structure = {
        "children_left": np.array([LEAF if lf else new_index[int(tree.children_left[k])] for k, lf in zip(keep, leaf)]),
        "children_right": np.array([LEAF if lf else new_index[int(tree.children_right[k])]
                                    for k, lf in zip(keep, leaf)]),
        "feature": np.array([LEAF if lf else int(tree.feature[k]) for k, lf in zip(keep, leaf)]),
        "threshold": np.array([0.0 if lf else float(tree.threshold[k]) for k, lf in zip(keep, leaf)]),
    }
    return keep, verdict, structure
