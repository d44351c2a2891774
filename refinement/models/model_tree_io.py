"""The model tree as text (WEKA's M5 layout, App. C.3.1) and as JSON (schema tailor.model_tree/1).

JSON floats are written by Python's json module as repr (shortest round-tripping) strings, so a saved tree
predicts bit-identically after loading. Loading checks the schema, every type and the tree's shape, and
reports the first problem as one line naming the file.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from tailor.errors import ModelFileError
from tailor.refinement.models.model_tree_grow import TreeArrays

SCHEMA = "tailor.model_tree/1"
THRESHOLD_DIGITS = 6  # significant digits of split thresholds in export_text
COEF_DIGITS = 4  # significant digits of linear-model terms in export_text


# -- text ------------------------------------------------------------------------------------------------


def export_text(tree: TreeArrays, names: Sequence[str]) -> str:
    """Nested `name <= t :` / `name > t :` lines with `LMi (n)` at the leaves, then each `LMi: formula`."""
    lines: list[str] = []

    def walk(node: int, depth: int) -> None:
        for child, op in ((tree.left[node], "<="), (tree.right[node], ">")):
            test = "|   " * depth + f"{names[tree.feature[node]]} {op} {tree.threshold[node]:.{THRESHOLD_DIGITS}g} :"
            if tree.leaf[child] >= 0:
                lines.append(f"{test} LM{tree.leaf[child] + 1} ({tree.n_samples[child]})")
            else:
                lines.append(test)
                walk(child, depth + 1)

    if tree.leaf[0] >= 0:
        lines.append(f"LM1 ({tree.n_samples[0]})")
    else:
        walk(0, 0)
    lines.append("")
    for i, (coef, intercept) in enumerate(zip(tree.coef, tree.intercept)):
        lines.append(f"LM{i + 1}: {format_linear_model(coef, float(intercept), names)}")
    lines.append("")
    lines.append(f"Number of rules: {len(tree.intercept)}")
    return "\n".join(lines) + "\n"


def format_linear_model(coef: np.ndarray, intercept: float, names: Sequence[str]) -> str:
    """`1.35*dist + 0.22*angle + 0.13`; features with coefficient 0 are left out."""
    terms = [(float(c), f"*{name}") for c, name in zip(coef, names) if c != 0.0] + [(intercept, "")]
    text = ""
    for i, (value, suffix) in enumerate(terms):
        magnitude = f"{abs(value):.{COEF_DIGITS}g}{suffix}"
        if i == 0:
            text = ("-" if value < 0 else "") + magnitude
        else:
            text += (" - " if value < 0 else " + ") + magnitude
    return text


# -- JSON ------------------------------------------------------------------------------------------------


def tree_to_json(
    tree: TreeArrays, hyperparameters: dict[str, Any], n_features: int, feature_names: list[str] | None
) -> dict:
    nodes: list[dict] = []
    for i in range(len(tree.feature)):
        if tree.leaf[i] >= 0:
            nodes.append({"leaf": int(tree.leaf[i]), "n_samples": int(tree.n_samples[i])})
        else:
            nodes.append({
                "feature": int(tree.feature[i]),
                "threshold": float(tree.threshold[i]),
                "left": int(tree.left[i]),
                "right": int(tree.right[i]),
                "n_samples": int(tree.n_samples[i]),
            })
    data: dict[str, Any] = {"schema": SCHEMA, "hyperparameters": dict(hyperparameters), "n_features_in_": n_features}
    if feature_names is not None:
        data["feature_names_in_"] = list(feature_names)
    data["nodes"] = nodes
    data["leaves"] = [
        {"coef": [float(c) for c in coef], "intercept": float(b)} for coef, b in zip(tree.coef, tree.intercept)
    ]
    return data


def tree_from_json(
    data: Any, source: str, hyperparameter_names: Sequence[str]
) -> tuple[TreeArrays, dict[str, Any], int, list[str] | None]:
    """Check a to_json dict thoroughly and rebuild the tree; any problem raises ModelFileError."""

    def fail(message: str) -> ModelFileError:
        return ModelFileError(message, file=source)

    if not isinstance(data, dict):
        raise fail(f"a model tree must be a JSON object, got {type(data).__name__}")
    if data.get("schema") != SCHEMA:
        raise fail(f"schema is {data.get('schema')!r}, expected {SCHEMA!r}")
    missing = [k for k in ("hyperparameters", "n_features_in_", "nodes", "leaves") if k not in data]
    if missing:
        raise fail(f"missing key {missing[0]!r}")
    hyper = data["hyperparameters"]
    if not isinstance(hyper, dict) or set(hyper) != set(hyperparameter_names):
        raise fail(f"hyperparameters must be an object with exactly the keys {', '.join(hyperparameter_names)}")
    d = data["n_features_in_"]
    if not _is_int(d) or d < 1:
        raise fail(f"n_features_in_ must be an integer >= 1, got {d!r}")
    names = data.get("feature_names_in_")
    if names is not None and (
        not isinstance(names, list) or len(names) != d or not all(isinstance(n, str) for n in names)
    ):
        raise fail(f"feature_names_in_ must be a list of {d} strings")
    leaves = _list_of_objects(data["leaves"], "leaves", fail)
    coef = np.empty((len(leaves), d))
    intercept = np.empty(len(leaves))
    for i, leaf in enumerate(leaves):
        c = leaf.get("coef")
        if not isinstance(c, list) or len(c) != d or not all(_is_number(v) for v in c):
            raise fail(f"leaves[{i}].coef must be a list of {d} finite numbers")
        if not _is_number(leaf.get("intercept")):
            raise fail(f"leaves[{i}].intercept must be a finite number")
        coef[i], intercept[i] = c, leaf["intercept"]
    nodes = _list_of_objects(data["nodes"], "nodes", fail)
    tree = _nodes_to_arrays(nodes, d, len(leaves), fail)
    return TreeArrays(**tree, coef=coef, intercept=intercept), dict(hyper), int(d), names


def _nodes_to_arrays(nodes: list[dict], d: int, n_leaves: int, fail) -> dict[str, np.ndarray]:
    """Node arrays, checking that the nodes form one binary tree in preorder with leaves numbered in order."""
    n = len(nodes)
    feature, threshold = np.full(n, -1, dtype=np.intp), np.full(n, np.inf)
    left, right = np.arange(n, dtype=np.intp), np.arange(n, dtype=np.intp)
    leaf, n_samples = np.full(n, -1, dtype=np.intp), np.zeros(n, dtype=np.intp)
    for i, node in enumerate(nodes):
        if not _is_int(node.get("n_samples")) or node["n_samples"] < 0:
            raise fail(f"nodes[{i}].n_samples must be an integer >= 0")
        n_samples[i] = node["n_samples"]
        if "leaf" in node:
            if set(node) != {"leaf", "n_samples"} or not _is_int(node["leaf"]):
                raise fail(f"nodes[{i}] must be {{leaf, n_samples}} with an integer leaf")
            leaf[i] = node["leaf"]
            continue
        if set(node) != {"feature", "threshold", "left", "right", "n_samples"}:
            raise fail(f"nodes[{i}] must have the keys feature, threshold, left, right, n_samples (or leaf)")
        if not _is_int(node["feature"]) or not 0 <= node["feature"] < d:
            raise fail(f"nodes[{i}].feature must be an integer in 0..{d - 1}")
        if not _is_number(node["threshold"]):
            raise fail(f"nodes[{i}].threshold must be a finite number")
        if not all(_is_int(node[k]) and 0 <= node[k] < n for k in ("left", "right")):
            raise fail(f"nodes[{i}].left and .right must be node indices in 0..{n - 1}")
        feature[i], threshold[i], left[i], right[i] = node["feature"], node["threshold"], node["left"], node["right"]
    # Walk from the root in preorder: every node must be reached exactly once, at its own index.
    expected, leaves_seen, stack = 0, 0, [0]
    while stack:
        node = stack.pop()
        if node != expected:
            raise fail(f"nodes are not one binary tree in preorder (expected node {expected}, found {node})")
        expected += 1
        if leaf[node] >= 0:
            if leaf[node] != leaves_seen:
                raise fail(f"nodes[{node}].leaf is {leaf[node]}, expected {leaves_seen} (leaves in preorder)")
            leaves_seen += 1
        else:
            stack += [int(right[node]), int(left[node])]
            if len(stack) > n:
                raise fail("nodes are not one binary tree in preorder (a cycle)")
    if expected != n:
        raise fail(f"nodes are not one binary tree: {n - expected} of {n} nodes are unreachable")
    if leaves_seen != n_leaves:
        raise fail(f"the tree has {leaves_seen} leaf nodes but 'leaves' lists {n_leaves}")
    return dict(feature=feature, threshold=threshold, left=left, right=right, leaf=leaf, n_samples=n_samples)


def _list_of_objects(value: Any, key: str, fail) -> list[dict]:
    if not isinstance(value, list) or not value or not all(isinstance(v, dict) for v in value):
        raise fail(f"{key} must be a non-empty list of objects")
    return value


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
