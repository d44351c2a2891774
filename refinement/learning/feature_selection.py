"""Choosing an action's features automatically (Sec. 4.1.1): generate candidates from its quantities
(models.auto_features), then select a compact set by cross-validated model-tree error.

Selection is forward selection, bounded: each step screens every candidate against the current model's
out-of-fold residuals (how much of their spread its quantile bins explain, a cheap filter that, unlike the
linear correlation the dissertation filters with, also sees non-monotone effects such as an angle's), fits
model trees for the SHORTLIST best-screened ones only, and keeps the one with the lowest K-fold MAE; it stops
when a step gains less than MIN_GAIN or at MAX_FEATURES. Forward, because a compact set is the aim (a model
tree's leaves test few features; fewer features keep the rules readable and the optimizer fast) and each step
costs SHORTLIST x FOLDS small fits, so the whole search is bounded whatever the number of candidates; a
backward or exhaustive search would cost fits in proportion to all of them. Everything runs on the first
example of at most SAMPLE_EPISODES learning episodes (never the test quarter), seeded.

A simulator's own feature spaces that read the action's parameters are candidate sets beside the generated
one: the set with the lowest cross-validated MAE wins, the generated one unless another is better by more
than PREFER_GENERATED (it needs no robot code, and it bounds itself exactly for the certified optimizer).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from tailor.refinement.learning.threads import one_thread
from tailor.refinement.models.auto_features import Candidate, candidate_columns, generate, generic_row
from tailor.refinement.models.expression_space import AUTO, ExpressionSpace
from tailor.refinement.models.features import first_examples
from tailor.refinement.models.model_tree import ModelTree
from tailor.sims.episode import Episode
from tailor.sims.parallel import ordered_results
from tailor.sims.protocol import ActionSpec, FeatureSpace, SimulatorEntry

SAMPLE_EPISODES = 4000
FOLDS = 3
SHORTLIST = 8
MAX_FEATURES = 8
MIN_GAIN = 0.005  # a step must lower the cross-validated MAE by at least 0.5%
BINS = 16
PREFER_GENERATED = 0.02
MIN_LEAF = 10


@dataclass(frozen=True)
class Selection:
    """What feature selection chose for an action: a generated space, or the name of a space the simulator
    brings; and the record of how (for the report)."""

    space: ExpressionSpace | None
    named: str | None
    report: dict = field(default_factory=dict)
    generated: ExpressionSpace | None = None  # the generated set, also where another set won

    @property
    def feature_space(self) -> FeatureSpace | str:
        return self.space.feature_space() if self.space is not None else self.named


def _leaf(rows: int) -> int:
    return max(MIN_LEAF, rows // 200)


def cv_mae(X: np.ndarray, y: np.ndarray, folds: list[np.ndarray], leaf: int) -> tuple[float, np.ndarray]:
    """K-fold MAE of a model tree on X, and the out-of-fold predictions."""
    predicted = np.empty_like(y)
    if X.shape[1] == 0:
        for fold in folds:
            rest = np.setdiff1d(np.arange(len(y)), fold)
            predicted[fold] = np.median(y[rest])
    else:
        with one_thread():
            for fold in folds:
                rest = np.setdiff1d(np.arange(len(y)), fold)
                predicted[fold] = ModelTree(min_samples_leaf=leaf).fit(X[rest], y[rest]).predict(X[fold])
    return float(np.mean(np.abs(predicted - y))), predicted


def screen(columns: np.ndarray, residual: np.ndarray) -> np.ndarray:
    """Per candidate column: the share of the residual's spread explained by its quantile bins' means."""
    total = float(np.sum((residual - residual.mean()) ** 2)) or 1.0
    scores = np.empty(columns.shape[1])
    for k in range(columns.shape[1]):
        edges = np.unique(np.quantile(columns[:, k], np.linspace(0, 1, BINS + 1)[1:-1]))
        bins = np.searchsorted(edges, columns[:, k])
        counts = np.bincount(bins)
        sums = np.bincount(bins, weights=residual)
        explained = float(np.sum(sums[counts > 0] ** 2 / counts[counts > 0])) - residual.sum() ** 2 / len(residual)
        scores[k] = explained / total
    return scores


def _trial(X: np.ndarray, y: np.ndarray, folds: list[np.ndarray], leaf: int) -> tuple[float, np.ndarray]:
    return cv_mae(X, y, folds, leaf)


def forward_select(candidates: list[Candidate], columns: np.ndarray, y: np.ndarray, folds: list[np.ndarray],
                   leaf: int, jobs: int = 1) -> tuple[list[int], list[dict]]:
    """Indices of the chosen candidates in order, and each step's record; a step's trials run in `jobs` workers
    (independent fits, results in order: the same choice for any number of workers)."""
    chosen: list[int] = []
    best, predicted = cv_mae(columns[:, []], y, folds, leaf)
    steps = [{"feature": None, "cv_mae": best}]
    while len(chosen) < min(MAX_FEATURES, len(candidates)):
        scores = screen(columns, y - predicted)
        scores[chosen] = -np.inf
        shortlist = [int(k) for k in np.argsort(-scores, kind="stable")[:SHORTLIST] if np.isfinite(scores[k])]
        calls = [(columns[:, chosen + [k]], y, folds, leaf) for k in shortlist]
        trials = list(zip(ordered_results(_trial, calls, jobs), shortlist))
        if not trials:
            break
        (mae, out_of_fold), k = min(trials, key=lambda t: (t[0][0], t[1]))
        if not mae < (1.0 - MIN_GAIN) * best:
            break
        chosen.append(k)
        best, predicted = mae, out_of_fold
        steps.append({"feature": candidates[k].name, "formula": candidates[k].expression.formula(), "cv_mae": mae,
                      "shortlist": [candidates[j].name for j in shortlist]})
    return chosen, steps


def _same_as_any(column: np.ndarray, others: np.ndarray) -> bool:
    return any(np.allclose(column, others[:, k]) for k in range(others.shape[1]))


def _sample(episodes: list[Episode], seed: int) -> list[Episode]:
    if len(episodes) <= SAMPLE_EPISODES:
        return list(episodes)
    keep = np.sort(np.random.default_rng(seed).choice(len(episodes), SAMPLE_EPISODES, replace=False))
    return [episodes[i] for i in keep]


def brought_spaces(entry: SimulatorEntry, spec: ActionSpec) -> dict[str, FeatureSpace]:
    """The simulator's own feature spaces that read exactly the action's parameters."""
    return {s.name: s for s in entry.feature_spaces if tuple(s.parameters) == tuple(spec.parameters)}


def select_features(spec: ActionSpec, entry: SimulatorEntry, episodes: list[Episode], seed: int,
                    others: dict[str, FeatureSpace] | None = None, jobs: int = 1) -> Selection:
    """Generate candidates for `spec`'s action and select a compact set on `episodes` (the learning ones), then
    compare it with the candidate sets `others` (default: the simulator's own spaces for this action)."""
    started = time.perf_counter()
    sample = [e for e in _sample(episodes, seed) if e.succeeded]
    params, y = first_examples(sample)
    candidates = generate(spec, entry.quantity, params, y)
    space_of = lambda chosen: ExpressionSpace(tuple(spec.parameters), tuple(c.name for c in chosen),  # noqa: E731
                                              tuple(c.expression for c in chosen))
    columns = candidate_columns(candidates, tuple(spec.parameters), params)
    order = np.random.default_rng(seed).permutation(len(y))
    folds = np.array_split(order, FOLDS)
    leaf = _leaf(len(y))
    chosen, steps = forward_select(candidates, columns, y, folds, leaf, jobs)
    if not chosen:  # nothing beats the median: keep the single best-screened candidate, a model needs one
        chosen = [int(np.argmax(screen(columns, y - np.median(y))))]
    # Table 4.1's generic row, where the structure has one, is a candidate set too, alone and joined to the
    # forward selection's (a step that gains little on the sample may still gain on all the data)
    row = generic_row(spec, entry.quantity) or []
    names = {c.name: k for k, c in enumerate(candidates)}
    row_columns = candidate_columns(row, tuple(spec.parameters), params)
    joined = chosen + [len(candidates) + k for k, c in enumerate(row)
                       if not _same_as_any(row_columns[:, k], columns[:, chosen])]
    everything = np.column_stack([columns, row_columns])
    tries = {"forward": chosen, "generic row": list(range(len(candidates), len(candidates) + len(row))),
             "forward and generic row": joined} if row else {"forward": chosen}
    scored = {label: cv_mae(everything[:, keys], y, folds, leaf)[0] for label, keys in tries.items() if keys}
    label = min(scored, key=scored.get)
    pool = candidates + row
    picked = [pool[k] for k in tries[label]]
    del names
    generated = space_of(picked).with_units(_units(spec, entry))
    sets = {"generated": scored[label]}
    others = brought_spaces(entry, spec) if others is None else others
    for name, space in others.items():
        sets[name] = cv_mae(space(params), y, folds, leaf)[0]
    best_other = min((name for name in sets if name != "generated"), key=sets.get, default=None)
    use_other = best_other is not None and sets[best_other] < (1.0 - PREFER_GENERATED) * sets["generated"]
    report = {
        "method": f"forward selection by {FOLDS}-fold model-tree MAE (first example of {len(y)} learning "
                  f"episodes, leaf {leaf}; {SHORTLIST} best-screened candidates tried per step)",
        "candidates": len(candidates),
        "generated_sets": scored,
        "steps": steps,
        "selected": generated.describe(),
        "candidate_sets": sets,
        "chosen": best_other if use_other else AUTO,
        "seconds": time.perf_counter() - started,
    }
    if use_other:
        return Selection(None, best_other, report, generated)
    return Selection(generated, None, report, generated)


def _units(spec: ActionSpec, entry: SimulatorEntry) -> dict[str, str]:
    quantities = dict(zip(spec.parameters, spec.observed_quantities + spec.internal_quantities))
    return {name: entry.quantity(q).unit for name, q in quantities.items()}


def generic_space(spec: ActionSpec, entry: SimulatorEntry) -> ExpressionSpace | None:
    """Table 4.1's generic row the action's structure matches, as a space (None where none does)."""
    row = generic_row(spec, entry.quantity)
    if not row:
        return None
    return ExpressionSpace(tuple(spec.parameters), tuple(c.name for c in row),
                           tuple(c.expression for c in row)).with_units(_units(spec, entry))
