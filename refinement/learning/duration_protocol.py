"""The training protocol of duration models (Sec. 4.3, Fig. 4.9).

Episodes are shuffled (seeded) and split: half train, a quarter validation, a quarter test.
1. n_i is chosen from candidates by the validation MAE of models trained on the half (Fig. 4.5), then the
   model tree's leaf size: the most accurate on validation (the largest within LEAF_TOLERANCE of that) among
   those whose stored tree is projected to stay within MAX_LEAVES. Intermediate examples of one episode are
   near duplicates, so M5's pruning, which counts them as independent, keeps leaves in proportion to the
   data; the leaf size is what keeps the tree readable (and quick to minimize over) as data grows.
2. A model trained on train + validation (three quarters) with that n_i is tested on the last quarter: its
   MAE is the reported accuracy, beside the MAE of a gradient-boosting ensemble trained on the same examples.
3. The stored model is trained on all episodes.
4. Its uncertainty (models.uncertainty): each episode predicted by a tree of the same n_i and leaf size fitted
   on the other folds (K-fold cross-fitting), the held-out errors averaged per leaf of the stored tree.
Test sets only ever hold the first example of each episode (Sec. 4.1.2): that is how the model is queried.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from sklearn.base import RegressorMixin
from sklearn.ensemble import HistGradientBoostingRegressor

from tailor.refinement.learning.threads import one_thread
from tailor.refinement.models.action_models import ActionModel
from tailor.errors import DataError
from tailor.refinement.models.expression_space import ExpressionSpace
from tailor.refinement.models.features import compute_features, first_examples, intermediate_examples, resolve
from tailor.sims.protocol import FeatureSpace
from tailor.refinement.models.model_tree import ModelTree
from tailor.refinement.models.uncertainty import FOLDS, LeafUncertainty
from tailor.sims.episode import Episode

N_I_CANDIDATES = (1, 2, 3, 5, 10, 20, 30, 50)  # examples per episode tried (Fig. 4.5)
EPISODE_FRACTIONS = (0.125, 0.25, 0.5, 1.0)  # of the three-quarter training set, for Fig. 4.6
MIN_SAMPLES_LEAF = (5, 10, 20, 40, 80, 160, 320)  # candidate leaf sizes (examples) of the model tree
MAX_LEAVES = 400  # leaves the stored tree may have ("a few hundred")
DEFAULT_MIN_SAMPLES_LEAF = 10  # the leaf size while n_i is chosen
LEAF_TOLERANCE = 0.03  # a larger leaf size is taken if its validation MAE is at most 3% above the best
MIN_EPISODES = 8  # fewer successful episodes cannot be split into train / validation / test

# Each fit runs on one thread (OpenMP, BLAS): the cores are used by fitting in --jobs workers. Left to itself,
RegressorFactory = Callable[[int, int], RegressorMixin]  # (seed, min_samples_leaf) -> unfitted regressor


def make_model_tree(seed: int, min_samples_leaf: int) -> RegressorMixin:
    """The duration model: an M5-style model tree (App. C.2); the seed is unused (the tree is deterministic)."""
    return ModelTree(min_samples_leaf=min_samples_leaf)


def make_baseline(seed: int, min_samples_leaf: int) -> RegressorMixin:
    """The comparison of Table 4.3's MAE: scikit-learn's histogram gradient boosting, seeded."""
    return HistGradientBoostingRegressor(random_state=seed)


@dataclass(frozen=True)
class Split:
    """Episode indices of the three parts of Fig. 4.9; disjoint, together all episodes."""

    train: np.ndarray
    validation: np.ndarray
    test: np.ndarray


def split_episodes(n: int, seed: int) -> Split:
    """Seeded shuffle of n episodes into half train, a quarter validation, a quarter test."""
    order = np.random.default_rng(seed).permutation(n)
    half, three_quarters = n // 2, (3 * n) // 4
    return Split(order[:half], order[half:three_quarters], order[three_quarters:])


def fit_on_episodes(episodes: list[Episode], feature_space: str | FeatureSpace, n_i: int, regressor: RegressorMixin,
                    observed: tuple[str, ...]) -> RegressorMixin:
    """Fit `regressor` on the first n_i examples of each episode, in the features of `feature_space`; `observed`
    names the action's observed parameters (read from each episode's log for the later examples)."""
    params, targets, _ = intermediate_examples(episodes, n_i, observed)
    return regressor.fit(compute_features(feature_space, params), targets)


def held_out_mae(regressor: RegressorMixin, episodes: list[Episode], feature_space: str | FeatureSpace) -> float:
    """Mean absolute error (s) on the first example of each episode."""
    params, durations = first_examples(episodes)
    predicted = regressor.predict(compute_features(feature_space, params))
    return float(np.mean(np.abs(predicted - durations)))


def count_examples(episodes: list[Episode], n_i: int) -> int:
    return int(sum(min(n_i, len(e.t)) for e in episodes))


@dataclass(frozen=True)
class DurationTraining:
    model: ActionModel
    report: dict


def train_duration_model(
    action: str,
    episodes: list[Episode],
    seed: int,
    feature_space: str | FeatureSpace | ExpressionSpace,
    observed: tuple[str, ...],
    n_i_candidates: tuple[int, ...] = N_I_CANDIDATES,
    leaf_candidates: tuple[int, ...] = MIN_SAMPLES_LEAF,
    episode_fractions: tuple[float, ...] = EPISODE_FRACTIONS,
    make_model: RegressorFactory = make_model_tree,
    make_reference: RegressorFactory = make_baseline,
    step: Callable[[str], None] = lambda label: None,
    jobs: int = 1,
) -> DurationTraining:
    """Run the protocol of Fig. 4.9 on the successful episodes; `step` is called as each fit is done (progress).

    Fits that do not depend on one another (the n_i candidates, the leaf sizes, the points of the learning
    curve) run in `jobs` workers of the backend in force (tailor.sims.parallel), with the serial result: each
    fit is deterministic and the results are taken in order. The factories must then be picklable.
    `feature_space`: a registered space's name, a FeatureSpace, or generated expressions (stored in the model)."""
    expressions = feature_space if isinstance(feature_space, ExpressionSpace) else None
    feature_space = expressions.feature_space() if expressions is not None else resolve(feature_space)
    used = [e for e in episodes if e.succeeded]
    if len(used) < MIN_EPISODES:
        raise DataError(f"{action}: {len(used)} successful episodes of {len(episodes)}; need at least {MIN_EPISODES}")
    split = split_episodes(len(used), seed)
    pick = lambda idx: [used[i] for i in idx]  # noqa: E731
    train, validation, test = pick(split.train), pick(split.validation), pick(split.test)
    learn = train + validation

    train_examples: dict[int, tuple[np.ndarray, np.ndarray]] = {}  # n_i -> features and targets of `train`

    def examples(n_i: int) -> tuple[np.ndarray, np.ndarray]:
        if n_i not in train_examples:
            params, targets, _ = intermediate_examples(train, n_i, observed)
            train_examples[n_i] = compute_features(feature_space, params), targets
        return train_examples[n_i]

    validation_set = _first_example_features(validation, feature_space)
    growth = len(used) / len(train)  # leaves grow about in proportion to the episodes (Fig. 4.6 data)
    fitted: dict[tuple[int, int], dict] = {}

    def fit_rows(pairs) -> None:
        """Fit the (n_i, leaf size) pairs not fitted yet, in the workers (independent fits, results in order)."""
        todo = [pair for pair in dict.fromkeys(pairs) if pair not in fitted]
        if not todo:
            return
        calls = [(make_model, seed, leaf, *examples(n_i), *validation_set) for n_i, leaf in todo]
        for (n_i, leaf), (mae, leaves) in zip(todo, _results(_fit_and_test, calls, jobs)):
            step(f"{action}: n_i={n_i}, leaf={leaf}")
            fitted[n_i, leaf] = {"n_i": n_i, "min_samples_leaf": leaf, "examples": count_examples(train, n_i),
                                 "mae": mae, "leaves": leaves,
                                 "projected_leaves": None if leaves is None else round(leaves * growth)}

    def row_for(n_i: int, leaf: int) -> dict:
        fit_rows([(n_i, leaf)])
        return dict(fitted[n_i, leaf])

    # n_i (Fig. 4.5) at the default leaf size; where that tree outgrows MAX_LEAVES, also with the smallest leaf
    # size that keeps it within (estimated: leaves shrink about in proportion), unless it cannot win anyway
    fit_rows([(n_i, DEFAULT_MIN_SAMPLES_LEAF) for n_i in n_i_candidates])
    n_i_curve = [row_for(n_i, DEFAULT_MIN_SAMPLES_LEAF) for n_i in n_i_candidates]
    small = [row for row in n_i_curve if _within_cap(row)]
    for row in sorted(n_i_curve, key=lambda row: row["mae"]):
        if _within_cap(row) or (small and row["mae"] >= min(r["mae"] for r in small)):
            continue
        needed = row["projected_leaves"] * DEFAULT_MIN_SAMPLES_LEAF / MAX_LEAVES
        larger = [leaf for leaf in leaf_candidates if leaf >= needed]
        if larger:
            capped = row_for(row["n_i"], min(larger))
            small += [capped] if _within_cap(capped) else []
    n_i = min(small or n_i_curve, key=lambda row: (row["mae"], row["n_i"]))["n_i"]

    # the leaf size for that n_i: the largest within LEAF_TOLERANCE of the best that keeps the tree small
    leaf_sizes = sorted(set(leaf_candidates) | {DEFAULT_MIN_SAMPLES_LEAF})
    fit_rows([(n_i, leaf) for leaf in leaf_sizes])
    leaf_curve = [row_for(n_i, leaf) for leaf in leaf_sizes]
    small = [row for row in leaf_curve if _within_cap(row)] or [max(leaf_curve, key=lambda r: r["min_samples_leaf"])]
    best = min(row["mae"] for row in small)
    leaf = max(row["min_samples_leaf"] for row in small if row["mae"] <= (1.0 + LEAF_TOLERANCE) * best)

    # the learning curve (Fig. 4.6) and the test of the three quarters: model tree and reference, fitted at once
    subsets = [learn[: max(MIN_EPISODES // 2, round(fraction * len(learn)))] for fraction in episode_fractions]
    if not subsets or len(subsets[-1]) != len(learn):  # the curve does not end with the full three quarters
        subsets.append(learn)
    test_set = _first_example_features(test, feature_space)
    calls = []
    for subset in subsets:
        params, targets, _ = intermediate_examples(subset, n_i, observed)
        features = compute_features(feature_space, params)
        calls += [(factory, seed, leaf, features, targets, *test_set) for factory in (make_model, make_reference)]
    results = []
    for k, result in enumerate(_results(_fit_and_test, calls, jobs)):
        if k % 2 == 0:
            step(f"{action}: {len(subsets[k // 2])} episodes")
        results.append(result)
    points = [{"episodes": len(subset), "mae": results[2 * k][0], "mae_hgb": results[2 * k + 1][0],
               "leaves": results[2 * k][1]} for k, subset in enumerate(subsets)]
    episodes_curve = points[:len(episode_fractions)]
    evaluated = points[-1]

    # the floor any model must beat: the median duration of the learning episodes, predicted for every test one
    constant = float(np.median([e.duration for e in learn]))
    mae_constant = float(np.mean(np.abs(first_examples(test)[1] - constant)))

    step(f"{action}: final model")
    with one_thread():
        final = fit_on_episodes(used, feature_space, n_i, make_model(seed, leaf), observed)
    uncertainty = _leaf_uncertainty(final, used, seed, leaf, n_i, feature_space, observed, make_model, step, action,
                                    jobs)
    durations = np.array([e.duration for e in used])
    report = {
        "action": action,
        "episodes": len(used),
        "episodes_gathered": len(episodes),
        "outcomes": _outcome_counts(episodes),
        "mean_duration": float(durations.mean()),
        "duration_range": [float(durations.min()), float(durations.max())],  # predictions are checked against it
        "simulated_hours": float(sum(e.duration for e in episodes) / 3600.0),
        "n_i": n_i,
        "min_samples_leaf": leaf,
        "examples": count_examples(used, n_i),
        "test_episodes": len(test),
        "mae": evaluated["mae"],
        "mae_hgb": evaluated["mae_hgb"],
        "mae_constant": mae_constant,  # predicting the median duration of the learning episodes
        "mae_relative": evaluated["mae"] / float(durations.mean()),
        "mae_over_hgb": evaluated["mae"] / evaluated["mae_hgb"] if evaluated["mae_hgb"] > 0 else None,
        "leaves_evaluated": evaluated["leaves"],
        "leaves": _leaves(final),
        "n_i_curve": n_i_curve,
        "leaf_curve": leaf_curve,
        "episodes_curve": episodes_curve,
        "seed": seed,
    }
    if uncertainty is not None:
        report["uncertainty_overall"] = uncertainty.overall  # the cross-fitted held-out MAE of all episodes
    model = ActionModel(action, feature_space.name, feature_space.names, final, n_i, report, uncertainty=uncertainty,
                        expressions=expressions)
    return DurationTraining(model, report)


def _leaf_uncertainty(final: RegressorMixin, used: list[Episode], seed: int, leaf: int, n_i: int,
                      feature_space: str | FeatureSpace,
                      observed: tuple[str, ...], make_model: RegressorFactory, step: Callable[[str], None],
                      action: str, jobs: int) -> LeafUncertainty | None:
    """Cross-fitted held-out errors of every episode, averaged per leaf of `final` (None if it has no leaves)."""
    if not hasattr(final, "apply") or not hasattr(final, "n_leaves_"):
        return None
    order = np.random.default_rng(seed).permutation(len(used))
    folds = np.array_split(order, FOLDS)
    calls = []
    for k, fold in enumerate(folds):
        rest = np.concatenate([f for j, f in enumerate(folds) if j != k])
        params, targets, _ = intermediate_examples([used[i] for i in rest], n_i, observed)
        calls.append((make_model, seed, leaf, compute_features(feature_space, params), targets,
                      *_first_example_features([used[i] for i in fold], feature_space)))
    residual = np.empty(len(used))
    for fold, errors in zip(folds, _results(_fit_and_residuals, calls, jobs)):
        step(f"{action}: uncertainty fold")
        residual[fold] = errors
    features, _ = _first_example_features(used, feature_space)
    return LeafUncertainty.from_residuals(final.apply(features), residual, int(final.n_leaves_))


def _fit_and_residuals(factory: RegressorFactory, seed: int, leaf: int, features: np.ndarray, targets: np.ndarray,
                       test_features: np.ndarray, test_durations: np.ndarray) -> np.ndarray:
    """Observed minus predicted duration of each held-out example, by a regressor fitted on the others."""
    with one_thread():
        regressor = factory(seed, leaf).fit(features, targets)
        return test_durations - regressor.predict(test_features)


def _first_example_features(episodes: list[Episode], feature_space: str | FeatureSpace
                            ) -> tuple[np.ndarray, np.ndarray]:
    """Features and durations of the first example of each episode (the held-out examples)."""
    params, durations = first_examples(episodes)
    return compute_features(feature_space, params), durations


def _fit_and_test(factory: RegressorFactory, seed: int, leaf: int, features: np.ndarray, targets: np.ndarray,
                  test_features: np.ndarray, test_durations: np.ndarray) -> tuple[float, int | None]:
    """(held-out MAE, leaves) of a regressor of `factory` fitted on the examples: one fit, run in a worker."""
    with one_thread():  # the parallelism is the workers' (learning.threads)
        regressor = factory(seed, leaf).fit(features, targets)
        return float(np.mean(np.abs(regressor.predict(test_features) - test_durations))), _leaves(regressor)


def _results(function: Callable, calls: list[tuple], jobs: int):
    from tailor.sims.parallel import ordered_results

    return ordered_results(function, calls, jobs)


def _within_cap(row: dict) -> bool:
    """Whether the stored tree of a validation row's (n_i, leaf size) would have at most MAX_LEAVES leaves."""
    return row["projected_leaves"] is None or row["projected_leaves"] <= MAX_LEAVES


def _leaves(model: RegressorMixin) -> int | None:
    leaves = getattr(model, "n_leaves_", None)
    return int(leaves) if leaves is not None else None


def _outcome_counts(episodes: list[Episode]) -> dict[str, int]:
    outcomes, counts = np.unique([e.outcome for e in episodes], return_counts=True)
    return {str(o): int(c) for o, c in zip(outcomes, counts)}
