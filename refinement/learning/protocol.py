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
Test sets only ever hold the first example of each episode (Sec. 4.1.2): that is how the model is queried.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from sklearn.base import RegressorMixin
from sklearn.ensemble import HistGradientBoostingRegressor

from tailor.refinement.models.action_models import ActionModel
from tailor.errors import DataError
from tailor.refinement.models.features import compute_features, feature_names, first_examples, intermediate_examples
from tailor.refinement.models.model_tree import ModelTree
from tailor.sims.episode import Episode

N_I_CANDIDATES = (1, 2, 3, 5, 10, 20, 30, 50)  # examples per episode tried (Fig. 4.5)
EPISODE_FRACTIONS = (0.125, 0.25, 0.5, 1.0)  # of the three-quarter training set, for Fig. 4.6
MIN_SAMPLES_LEAF = (5, 10, 20, 40, 80, 160, 320)  # candidate leaf sizes (examples) of the model tree
MAX_LEAVES = 400  # leaves the stored tree may have ("a few hundred")
DEFAULT_MIN_SAMPLES_LEAF = 10  # the leaf size while n_i is chosen
LEAF_TOLERANCE = 0.03  # a larger leaf size is taken if its validation MAE is at most 3% above the best
MIN_EPISODES = 8  # fewer successful episodes cannot be split into train / validation / test

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


def fit_on_episodes(episodes: list[Episode], feature_set: str, n_i: int, regressor: RegressorMixin,
                    observed: tuple[str, ...]) -> RegressorMixin:
    """Fit `regressor` on the first n_i examples of each episode, in the features of `feature_set`; `observed`
    names the action's observed parameters (read from each episode's log for the later examples)."""
    params, targets, _ = intermediate_examples(episodes, n_i, observed)
    return regressor.fit(compute_features(feature_set, params), targets)


def held_out_mae(regressor: RegressorMixin, episodes: list[Episode], feature_set: str) -> float:
    """Mean absolute error (s) on the first example of each episode."""
    params, durations = first_examples(episodes)
    predicted = regressor.predict(compute_features(feature_set, params))
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
    feature_set: str,
    observed: tuple[str, ...],
    n_i_candidates: tuple[int, ...] = N_I_CANDIDATES,
    leaf_candidates: tuple[int, ...] = MIN_SAMPLES_LEAF,
    episode_fractions: tuple[float, ...] = EPISODE_FRACTIONS,
    make_model: RegressorFactory = make_model_tree,
    make_reference: RegressorFactory = make_baseline,
    step: Callable[[str], None] = lambda label: None,
) -> DurationTraining:
    """Run the protocol of Fig. 4.9 on the successful episodes; `step` is called before each fit (progress)."""
    used = [e for e in episodes if e.succeeded]
    if len(used) < MIN_EPISODES:
        raise DataError(f"{action}: {len(used)} successful episodes of {len(episodes)}; need at least {MIN_EPISODES}")
    split = split_episodes(len(used), seed)
    pick = lambda idx: [used[i] for i in idx]  # noqa: E731
    train, validation, test = pick(split.train), pick(split.validation), pick(split.test)
    learn = train + validation

    def validate(n_i: int, leaf: int) -> dict:
        step(f"{action}: n_i={n_i}, leaf={leaf}")
        model = fit_on_episodes(train, feature_set, n_i, make_model(seed, leaf), observed)
        return {"n_i": n_i, "min_samples_leaf": leaf, "examples": count_examples(train, n_i),
                "mae": held_out_mae(model, validation, feature_set), "leaves": _leaves(model)}

    growth = len(used) / len(train)  # leaves grow about in proportion to the episodes (Fig. 4.6 data)
    fitted: dict[tuple[int, int], dict] = {}

    def row_for(n_i: int, leaf: int) -> dict:
        if (n_i, leaf) not in fitted:
            row = validate(n_i, leaf)
            row["projected_leaves"] = None if row["leaves"] is None else round(row["leaves"] * growth)
            fitted[n_i, leaf] = row
        return dict(fitted[n_i, leaf])

    # n_i (Fig. 4.5) at the default leaf size; where that tree outgrows MAX_LEAVES, also with the smallest leaf
    # size that keeps it within (estimated: leaves shrink about in proportion), unless it cannot win anyway
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
    leaf_curve = [row_for(n_i, leaf) for leaf in sorted(set(leaf_candidates) | {DEFAULT_MIN_SAMPLES_LEAF})]
    small = [row for row in leaf_curve if _within_cap(row)] or [max(leaf_curve, key=lambda r: r["min_samples_leaf"])]
    best = min(row["mae"] for row in small)
    leaf = max(row["min_samples_leaf"] for row in small if row["mae"] <= (1.0 + LEAF_TOLERANCE) * best)

    episodes_curve = []
    for fraction in episode_fractions:
        subset = learn[: max(MIN_EPISODES // 2, round(fraction * len(learn)))]
        step(f"{action}: {len(subset)} episodes")
        model = fit_on_episodes(subset, feature_set, n_i, make_model(seed, leaf), observed)
        reference = fit_on_episodes(subset, feature_set, n_i, make_reference(seed, leaf), observed)
        episodes_curve.append({
            "episodes": len(subset),
            "mae": held_out_mae(model, test, feature_set),
            "mae_hgb": held_out_mae(reference, test, feature_set),
            "leaves": _leaves(model),
        })
    evaluated = episodes_curve[-1] if len(episodes_curve) and episodes_curve[-1]["episodes"] == len(learn) else None
    if evaluated is None:  # the curve did not end with the full three quarters: evaluate them here
        step(f"{action}: {len(learn)} episodes")
        model = fit_on_episodes(learn, feature_set, n_i, make_model(seed, leaf), observed)
        reference = fit_on_episodes(learn, feature_set, n_i, make_reference(seed, leaf), observed)
        evaluated = {"mae": held_out_mae(model, test, feature_set), "mae_hgb": held_out_mae(reference, test, feature_set),
                     "leaves": _leaves(model)}

    # the floor any model must beat: the median duration of the learning episodes, predicted for every test one
    constant = float(np.median([e.duration for e in learn]))
    mae_constant = float(np.mean(np.abs(first_examples(test)[1] - constant)))

    step(f"{action}: final model")
    final = fit_on_episodes(used, feature_set, n_i, make_model(seed, leaf), observed)
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
    model = ActionModel(action, feature_set, feature_names(feature_set), final, n_i, report)
    return DurationTraining(model, report)


def _within_cap(row: dict) -> bool:
    """Whether the stored tree of a validation row's (n_i, leaf size) would have at most MAX_LEAVES leaves."""
    return row["projected_leaves"] is None or row["projected_leaves"] <= MAX_LEAVES


def _leaves(model: RegressorMixin) -> int | None:
    leaves = getattr(model, "n_leaves_", None)
    return int(leaves) if leaves is not None else None


def _outcome_counts(episodes: list[Episode]) -> dict[str, int]:
    outcomes, counts = np.unique([e.outcome for e in episodes], return_counts=True)
    return {str(o): int(c) for o, c in zip(outcomes, counts)}
