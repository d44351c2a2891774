"""Fig. 4.3 for every action: the held-out MAE of the model tree on several feature spaces of the same
episodes, beside gradient boosting on the raw parameters.

The spaces: the raw parameters; Table 4.1's generic row where the action's structure matches one; the
simulator's expert space where it brings one (the binding's, or the best it brings for these parameters); and the
automatically generated one (Sec. 4.1.1). Each is fitted as the duration model is (Fig. 4.9's split, the
action model's n_i): its leaf size chosen on the validation quarter, then trained on three quarters and tested on
the first example of each episode of the last quarter, the same test episodes for every space.
"""

from __future__ import annotations

import time

import numpy as np

from tailor.refinement.learning.duration_protocol import (_first_example_features, _fit_and_test, _results,
                                                          make_baseline, make_model_tree, split_episodes)
from tailor.refinement.models.features import intermediate_examples, raw_space
from tailor.sims.episode import Episode
from tailor.sims.protocol import FeatureSpace

LEAVES = (5, 10, 20, 40, 80, 160)  # leaf sizes tried per space on the validation quarter
ORDER = ("raw", "generic", "expert", "auto")


def learning_episodes(episodes: list[Episode], seed: int) -> list[Episode]:
    """The successful episodes the duration protocol learns from (train and validation), never its test ones."""
    used = [e for e in episodes if e.succeeded]
    split = split_episodes(len(used), seed)
    return [used[i] for i in np.concatenate([split.train, split.validation])]


def compare_spaces(episodes: list[Episode], seed: int, observed: tuple[str, ...], n_i: int,
                   spaces: dict[str, FeatureSpace], parameters: tuple[str, ...], jobs: int = 1) -> dict:
    """Rows of Fig. 4.3 for `spaces` (label -> space; "raw" added), and gradient boosting on the raw parameters."""
    started = time.perf_counter()
    used = [e for e in episodes if e.succeeded]
    split = split_episodes(len(used), seed)
    pick = lambda idx: [used[i] for i in idx]  # noqa: E731
    train, validation, test = pick(split.train), pick(split.validation), pick(split.test)
    learn = train + validation
    spaces = {"raw": raw_space(parameters), **spaces}
    train_params, train_targets, _ = intermediate_examples(train, n_i, observed)
    learn_params, learn_targets, _ = intermediate_examples(learn, n_i, observed)
    calls, labels = [], []
    for label, space in spaces.items():
        features = space(train_params)
        for leaf in LEAVES:
            calls.append((make_model_tree, seed, leaf, features, train_targets,
                          *_first_example_features(validation, space)))
            labels.append((label, leaf))
    leaf_of: dict[str, tuple[float, int]] = {}
    for (label, leaf), (mae, _) in zip(labels, _results(_fit_and_test, calls, jobs)):
        if label not in leaf_of or mae < leaf_of[label][0]:
            leaf_of[label] = (mae, leaf)
    calls = [(make_model_tree, seed, leaf_of[label][1], space(learn_params), learn_targets,
              *_first_example_features(test, space)) for label, space in spaces.items()]
    raw = spaces["raw"]
    calls.append((make_baseline, seed, 0, raw(learn_params), learn_targets, *_first_example_features(test, raw)))
    results = list(_results(_fit_and_test, calls, jobs))
    rows = [{"space": label, "name": space.name, "features": len(space.names), "leaf": leaf_of[label][1],
             "mae": results[k][0], "leaves": results[k][1]} for k, (label, space) in enumerate(spaces.items())]
    return {"n_i": n_i, "test_episodes": len(test), "rows": rows, "mae_hgb_raw": results[-1][0],
            "seconds": time.perf_counter() - started}
