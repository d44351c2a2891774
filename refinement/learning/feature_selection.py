"""Choosing an action's features automatically (Sec. 4.1.1): generate candidates from its quantities
(models.auto_features), then select a compact set by cross-validated model-tree error.

Selection is forward selection, bounded: each step screens every candidate against the current model's
out-of-fold residuals (how much of their spread its quantile bins explain, a cheap filter that, unlike the
linear correlation the dissertation filters with, also sees non-monotone effects such as an angle's), fits
model trees for the SHORTLIST best-screened ones only, and keeps the one with the lowest K-fold MAE; it stops
when a step gains less than MIN_GAIN or at MAX_FEATURES. Forward, because a compact set is the aim (a model
tree's leaves test few features; fewer features keep the rules readable and the optimizer fast) and each step
costs at most SHORTLIST x FOLDS small fits, so the whole search is bounded whatever the number of candidates; a
backward or exhaustive search would cost fits in proportion to all of them. Everything runs on the first
example of at most SAMPLE_EPISODES learning episodes (never the test quarter), seeded.

The trials of a step are raced (`race`): each is fitted for the first fold only, and only those whose error
there is within RACE_MARGIN of the best trial's (and of the step's bar, MIN_GAIN below the current model's
error on that fold) go on to the other folds. A trial that goes on gets the same K-fold MAE it would get
alone; one left behind is clearly worse on a third of the rows. A step where none goes on gains clearly less
than MIN_GAIN and ends the search. The candidate sets of the end are raced the same way.

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
RACE_MARGIN = 0.12  # a trial more than 12% worse than the best on the first fold is not fitted on the others
# (measured on the bundled actions with racing off: the trial that won by K-fold MAE was at most 9.2% behind the
# best on the first fold, in 51 races of the 8 bundled duration models)
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
    """K-fold MAE of a model tree on X (the median where X has no columns), and the out-of-fold predictions."""
    predicted = np.empty_like(y)
    for fold in folds:
        predicted[fold] = _fold_fit(X, y, fold, leaf)
    return float(np.mean(np.abs(predicted - y))), predicted


def quantile_bins(columns: np.ndarray) -> np.ndarray:
    """Per row and candidate column: the row's bin among the column's BINS quantile bins (what `screen` groups the
    residuals by; computed once, as the columns stay while the residuals change from step to step)."""
    bins = np.empty(columns.shape, dtype=np.intp)
    for k in range(columns.shape[1]):
        edges = np.unique(np.quantile(columns[:, k], np.linspace(0, 1, BINS + 1)[1:-1]))
        bins[:, k] = np.searchsorted(edges, columns[:, k])
    return bins


def screen(bins: np.ndarray, residual: np.ndarray) -> np.ndarray:
    """Per candidate column (its `quantile_bins`): the share of the residual's spread explained by its quantile
    bins' means."""
    total = float(np.sum((residual - residual.mean()) ** 2)) or 1.0
    scores = np.empty(bins.shape[1])
    for k in range(bins.shape[1]):
        counts = np.bincount(bins[:, k])
        sums = np.bincount(bins[:, k], weights=residual)
        explained = float(np.sum(sums[counts > 0] ** 2 / counts[counts > 0])) - residual.sum() ** 2 / len(residual)
        scores[k] = explained / total
    return scores


def _fold_fit(X: np.ndarray, y: np.ndarray, fold: np.ndarray, leaf: int) -> np.ndarray:
    """The predictions on `fold` of a model tree fitted on the other rows (one fold of cv_mae; the other rows'
    median where X has no columns)."""
    rest = np.setdiff1d(np.arange(len(y)), fold)
    if X.shape[1] == 0:
        return np.full(len(fold), np.median(y[rest]))
    with one_thread():
        return ModelTree(min_samples_leaf=leaf).fit(X[rest], y[rest]).predict(X[fold])


@dataclass(frozen=True)
class Race:
    """Raced column sets: K-fold MAE and out-of-fold predictions of those that ran every fold (None for the
    others), and each set's MAE on the first fold."""

    results: list[tuple[float, np.ndarray] | None]
    first_fold: list[float]


def race(sets: list[np.ndarray], y: np.ndarray, folds: list[np.ndarray], leaf: int, jobs: int = 1,
         best: float = np.inf, bar: float | None = None, groups: tuple[tuple[int, ...], ...] = ()) -> Race:
    """Fit every column set for the first fold; for the other folds only those within RACE_MARGIN of the best
    first-fold MAE (theirs, or `best`, a set's raced before) and, with a `bar`, of it; and the best of each of
    `groups` in any case. Those get their cv_mae to the last bit, at a fraction of the fits. The fits run in
    `jobs` workers, results in order (the same for any number of workers)."""
    first = list(ordered_results(_fold_fit, [(X, y, folds[0], leaf) for X in sets], jobs, one_by_one=True))
    errors = [float(np.mean(np.abs(p - y[folds[0]]))) for p in first]
    best = min([best, *errors])
    on = {k for k, e in enumerate(errors) if e <= (1.0 + RACE_MARGIN) * best and
          (bar is None or e < (1.0 + RACE_MARGIN) * bar)}
    on |= {min(group, key=lambda k: (errors[k], k)) for group in groups if group}
    on = sorted(on)
    rest = list(ordered_results(_fold_fit, [(sets[k], y, folds[f], leaf) for k in on for f in range(1, len(folds))],
                                jobs, one_by_one=True))
    results: list[tuple[float, np.ndarray] | None] = [None] * len(sets)
    for j, k in enumerate(on):
        predicted = np.empty_like(y)
        predicted[folds[0]] = first[k]
        for f in range(1, len(folds)):
            predicted[folds[f]] = rest[j * (len(folds) - 1) + f - 1]
        results[k] = (float(np.mean(np.abs(predicted - y))), predicted)
    return Race(results, errors)


def forward_select(candidates: list[Candidate], columns: np.ndarray, bins: np.ndarray, y: np.ndarray,
                   folds: list[np.ndarray], leaf: int, jobs: int = 1) -> tuple[list[int], list[dict], np.ndarray]:
    """Indices of the chosen candidates in order, each step's record, and the chosen set's out-of-fold
    predictions; a step's trials, screened by the columns' `quantile_bins`, are raced (`race`) in `jobs` workers."""
    chosen: list[int] = []
    best, predicted = cv_mae(columns[:, []], y, folds, leaf)
    steps = [{"feature": None, "cv_mae": best}]
    while len(chosen) < min(MAX_FEATURES, len(candidates)):
        scores = screen(bins, y - predicted)
        scores[chosen] = -np.inf
        shortlist = [int(k) for k in np.argsort(-scores, kind="stable")[:SHORTLIST] if np.isfinite(scores[k])]
        if not shortlist:
            break
        current = float(np.mean(np.abs(predicted[folds[0]] - y[folds[0]])))
        raced = race([columns[:, chosen + [k]] for k in shortlist], y, folds, leaf, jobs,
                     bar=(1.0 - MIN_GAIN) * current)
        trials = [(result, k) for result, k in zip(raced.results, shortlist) if result is not None]
        if not trials:  # every trial clearly short of MIN_GAIN on the first fold
            break
        (mae, out_of_fold), k = min(trials, key=lambda t: (t[0][0], t[1]))
        if not mae < (1.0 - MIN_GAIN) * best:
            break
        chosen.append(k)
        best, predicted = mae, out_of_fold
        steps.append({"feature": candidates[k].name, "formula": candidates[k].expression.formula(), "cv_mae": mae,
                      "shortlist": [candidates[j].name for j in shortlist],
                      "raced": len(trials)})
    return chosen, steps, predicted


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
    candidates = generate(spec, entry.quantity, params, y, jobs)
    space_of = lambda chosen: ExpressionSpace(tuple(spec.parameters), tuple(c.name for c in chosen),  # noqa: E731
                                              tuple(c.expression for c in chosen))
    columns = candidate_columns(candidates, tuple(spec.parameters), params)
    order = np.random.default_rng(seed).permutation(len(y))
    folds = np.array_split(order, FOLDS)
    leaf = _leaf(len(y))
    bins = quantile_bins(columns)
    chosen, steps, predicted = forward_select(candidates, columns, bins, y, folds, leaf, jobs)
    known = {}  # the candidate sets whose K-fold MAE is known already: the forward selection's
    if chosen:
        known["forward"] = (steps[-1]["cv_mae"], predicted)
    else:  # nothing beats the median: keep the single best-screened candidate, a model needs one
        chosen = [int(np.argmax(screen(bins, y - np.median(y))))]
    # Table 4.1's generic row, where the structure has one, is a candidate set too, alone and joined to the
    # forward selection's (a step that gains little on the sample may still gain on all the data)
    row = generic_row(spec, entry.quantity) or []
    row_columns = candidate_columns(row, tuple(spec.parameters), params)
    joined = chosen + [len(candidates) + k for k, c in enumerate(row)
                       if not _same_as_any(row_columns[:, k], columns[:, chosen])]
    everything = np.column_stack([columns, row_columns])
    tries = {"forward": chosen, "generic row": list(range(len(candidates), len(candidates) + len(row))),
             "forward and generic row": joined} if row else {"forward": chosen}
    others = brought_spaces(entry, spec) if others is None else others
    # the generated sets and the simulator's, raced together; the best of each finishes (the best brought one
    # is the expert space of Fig. 4.3's comparison where the recipe says "auto")
    tries = {label: keys for label, keys in tries.items() if keys}
    mine = [label for label in tries if label not in known]
    first = min((float(np.mean(np.abs(p[folds[0]] - y[folds[0]]))) for _, p in known.values()), default=np.inf)
    groups = (() if known else tuple(range(len(mine))), tuple(range(len(mine), len(mine) + len(others))))
    raced = race([everything[:, tries[label]] for label in mine] + [space(params) for space in others.values()],
                 y, folds, leaf, jobs, best=first, groups=groups)
    finished = {label: mae for label, (mae, _) in known.items()}
    finished |= {label: r[0] for label, r in zip(mine, raced.results) if r is not None}
    scored = {label: finished[label] for label in tries if label in finished}
    theirs = {name: r[0] for name, r in zip(others, raced.results[len(mine):]) if r is not None}
    dropped = {label: e for label, e, r in zip([*mine, *others], raced.first_fold, raced.results) if r is None}
    label = min(scored, key=scored.get)
    pool = candidates + row
    picked = [pool[k] for k in tries[label]]
    generated = space_of(picked).with_units(_units(spec, entry))
    sets = {"generated": scored[label], **theirs}
    best_other = min((name for name in sets if name != "generated"), key=sets.get, default=None)
    use_other = best_other is not None and sets[best_other] < (1.0 - PREFER_GENERATED) * sets["generated"]
    report = {
        "method": f"forward selection by {FOLDS}-fold model-tree MAE (first example of {len(y)} learning "
                  f"episodes, leaf {leaf}; {SHORTLIST} best-screened candidates tried per step, raced: those more than "
                  f"{RACE_MARGIN:.0%} behind the best on the first fold not fitted on the others)",
        "candidates": len(candidates),
        "generated_sets": scored,
        "steps": steps,
        "selected": generated.describe(),
        "candidate_sets": sets,
        "raced_out": dropped,  # sets left after the first fold (its MAE), clearly worse than the best there
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
