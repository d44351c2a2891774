"""Learning in operation (Ch. 8.1): the executed actions kept as experience, and the duration models that follow
the robot's real task distribution and a robot that has changed.

Warm-started, not incremental: every `every` executions each action's model is recalibrated from all its
executed actions so far. The learned tree's splits are kept (they were learned from thousands of episodes; a
few hundred executions cannot place better ones) and its leaves' linear models are mapped: first one affine
correction per action, duration' = a * duration + b, least squares shrunk toward (1, 0) by PRIOR executions'
worth, then a per-leaf shift of the remaining error where a leaf has executions, shrunk by LEAF_PRIOR. (Each
leaf's own affine map instead of its shift fitted the executions as well but refined worse, on a bundled variant
17.9% faster than greedy on the last 20 of 200 tasks against 22.4%: the optimizer finds the leaves whose slope a
few executions tilted.) The
result is again a model tree over the same features, so every optimizer (analytic, certified, genetic) refines
with it as with the trained one; it predicts the trained model until executions say otherwise. Where a robot has
changed in a way no such map follows, the executions say more than the trained tree: from RETRAIN_FROM successful
executions of an action on (and every RETRAIN_EVERY more), a tree trained on them alone (the training protocol, in
features selected on them with the trained model's competing: a changed robot may break what its features take as
known, such as an acceleration limit) competes with the trained tree, both fitted on all but the most recent
RECENT_SHARE of them and recalibrated there; the one predicting those recent executions better is what
recalibration starts from until the next judgement.

The success classifiers (Sec. 4.2.2) are recalibrated alike: the tree's splits kept, the executions that reached a
leaf counted into it (beside its training episodes, weighed as at most TRAINED_WEIGHT executions: the robot may
have changed), and the leaf's verdict taken again by the classifier's own rule (its failures weighed by its class
weight against its successes) where at least MIN_LEAF_EXECUTIONS executions reached it. An execution counts as a
failure only with an outcome the classifier learned (its report's `outcomes`, e.g. "collision"): a disturbance's
failure says nothing about the region.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from tailor.refinement.models.action_models import ActionModel, CollisionModel
from tailor.refinement.models.expression_space import ExpressionSpace
from tailor.sims.episode import Episode
from tailor.sims.protocol import SimulatorEntry

MIN_EXECUTIONS = 5  # successful executions of an action before its model is recalibrated
PRIOR = 3.0  # executions' worth of belief in the trained model (a = 1, b = 0)
LEAF_PRIOR = 2.0  # executions' worth of belief in no per-leaf shift
RETRAIN_FROM = 200  # successful executions of an action before a tree trained on them alone may replace the trained
RETRAIN_EVERY = 100  # ... judged again after this many more
RECENT_SHARE = 0.2  # ... on the most recent share of them, each candidate fitted on the rest
MIN_LEAF_EXECUTIONS = 3  # executions reaching a classifier's leaf before they can change its verdict
TRAINED_WEIGHT = 20.0  # at most this many executions' worth of a classifier leaf's training episodes
# a retrained tree learns in generated features only where they predict the executions with at most this share of
# the trained features' cross-validated error (measured on the bundled variants: 0.04 where the trained space bakes
# in an acceleration limit the variant lowers, 260 executions; 0.79 on 200 executions and 1.32 on 600 where it reads
# an obstacle map the generated features cannot, and switching there at 0.79 predicted the last tasks 4 times worse)
RESELECT_SHARE = 0.5


class OnlineLearner:
    """Keeps executed actions (`record`) and recalibrates the models every `every` of them (`adapted`)."""

    def __init__(self, entry: SimulatorEntry, every: int = 5):
        if isinstance(every, bool) or not isinstance(every, int) or every < 1:
            raise ValueError(f"every must be an integer >= 1, not {every!r}")
        self.entry = entry
        self.every = every
        self.episodes: dict[str, list[Episode]] = {}
        # (action, predicted before it ran, measured, its parameters) of each successful execution, in order
        self.errors: list[tuple[str, float, float, tuple[float, ...]]] = []
        self.count = 0
        self.refits = 0
        self._trained: dict[str, ActionModel] = {}  # the models as trained, per action
        self._adapted: dict[str, ActionModel] = {}
        # per action: what recalibration starts from where it is not the trained model (a tree trained on the
        # executions alone, where that predicted the recent ones better), and when that was last judged
        self._base: dict[str, ActionModel] = {}
        self._judged: dict[str, int] = {}
        self._trained_guards: dict[str, CollisionModel] = {}  # the success classifiers as trained, per name
        self._adapted_guards: dict[str, CollisionModel] = {}

    def record(self, episode: Episode, predicted: float | None = None) -> None:
        """One executed action; every `every` of them the models are recalibrated."""
        self.episodes.setdefault(episode.action, []).append(episode)
        if predicted is not None and episode.succeeded:
            self.errors.append((episode.action, float(predicted), float(episode.duration),
                                tuple(float(v) for v in episode.params)))
        self.count += 1
        if self.count % self.every == 0:
            self._refit()

    def extend(self, episodes) -> None:
        """Executions of earlier runs (a log): kept, and the models recalibrated on them at once."""
        for episode in episodes:
            self.episodes.setdefault(episode.action, []).append(episode)
            self.count += 1
        self._refit()

    def adapted(self, models: Mapping[str, ActionModel]) -> dict[str, ActionModel]:
        """`models` with each action's recalibrated model where there is one (the first model seen for an action
        is the trained one every recalibration starts from)."""
        out = {}
        for action, model in models.items():
            if action not in self._trained and model is not self._adapted.get(action):
                self._trained[action] = model
                if self.episodes.get(action):
                    self._refit_action(action)
            out[action] = self._adapted.get(action, model)
        return out

    def adapted_success(self, success_models: Mapping[str, object]) -> dict[str, object]:
        """`success_models` with each success classifier recalibrated on the executions of its action where there
        are any (the first classifier seen under a name is the trained one; other kinds of guard pass as given)."""
        out = {}
        for name, model in success_models.items():
            if not isinstance(model, CollisionModel):
                out[name] = model
                continue
            if name not in self._trained_guards and model is not self._adapted_guards.get(name):
                self._trained_guards[name] = model
                self._refit_guard(name)
            out[name] = self._adapted_guards.get(name, model)
        return out

    def mean_error(self) -> float | None:
        """Mean absolute error (s) of the predictions made before each executed action ran (prequential)."""
        if not self.errors:
            return None
        return float(np.mean([abs(p - m) for _, p, m, _ in self.errors]))

    def _refit(self) -> None:
        for action in self.episodes:
            if action in self._trained:
                self._refit_action(action)
        for name in self._trained_guards:
            self._refit_guard(name)
        self.refits += 1

    def _refit_guard(self, name: str) -> None:
        trained = self._trained_guards[name]
        executed = self.episodes.get(trained.action, [])
        if not executed:
            return
        self._adapted_guards[name] = recalibrated_classifier(trained, executed)

    def _refit_action(self, action: str) -> None:
        used = [e for e in self.episodes.get(action, []) if e.succeeded]
        if len(used) < MIN_EXECUTIONS:
            return
        params = np.array([e.params for e in used], dtype=float)
        durations = np.array([e.duration for e in used], dtype=float)
        if len(used) >= RETRAIN_FROM and len(used) - self._judged.get(action, 0) >= RETRAIN_EVERY:
            self._judged[action] = len(used)
            self._base[action] = self._better_base(action, used)
        self._adapted[action] = recalibrated(self._base.get(action, self._trained[action]), params, durations)

    def _better_base(self, action: str, used: list[Episode]) -> ActionModel:
        """The trained model, or a tree trained on the executions alone (the trained model's features, the training
        protocol) where, both fitted on all but the most recent RECENT_SHARE of them and recalibrated on the same,
        it predicts those recent ones with a smaller error: the executions then say more than the recalibrated
        trained tree can (a robot changed in a way no affine map of its leaves follows)."""
        trained = self._trained[action]
        cut = round(len(used) * (1.0 - RECENT_SHARE))
        early, recent = used[:cut], used[cut:]
        candidate = retrained(trained, early, self.entry)
        if candidate is None:
            return trained
        params = np.array([e.params for e in early], dtype=float)
        durations = np.array([e.duration for e in early], dtype=float)
        test = np.array([e.params for e in recent], dtype=float)
        truth = np.array([e.duration for e in recent], dtype=float)

        def error(model: ActionModel) -> float:
            return float(np.mean(np.abs(recalibrated(model, params, durations).predict_duration(test) - truth)))

        if error(candidate) >= error(trained):
            return trained
        return retrained(trained, used, self.entry) or trained


def recalibrated(model: ActionModel, params: np.ndarray, durations: np.ndarray) -> ActionModel:
    """`model` with its leaves' linear models mapped to fit the executed (params, durations) (see the module's
    docstring); the same splits, features and uncertainty."""
    features = model.features(params)
    predicted, leaf = model.duration.predict_with_leaf(features)
    n = len(durations)
    scale = float(np.mean(predicted ** 2)) if n else 1.0
    # ridge toward (a, b) = (1, 0): minimize sum (y - a s - b)^2 + PRIOR * (scale (a - 1)^2 + b^2)
    lhs = np.array([[predicted @ predicted + PRIOR * scale, predicted.sum()],
                    [predicted.sum(), n + PRIOR]])
    rhs = np.array([predicted @ durations + PRIOR * scale, durations.sum()])
    a, b = np.linalg.solve(lhs, rhs)
    residual = durations - (a * predicted + b)
    tree = copy.deepcopy(model.duration)
    arrays = tree.tree_
    shift = np.zeros(len(arrays.intercept))
    for index in np.unique(leaf):
        inside = leaf == index
        shift[index] = residual[inside].sum() / (inside.sum() + LEAF_PRIOR)
    tree._set_tree(replace(arrays, coef=arrays.coef * a, intercept=arrays.intercept * a + b + shift))
    report = {**model.report, "recalibrated": {"executions": int(n), "scale": float(a), "offset": float(b)}}
    return replace(model, duration=tree, report=report)


def recalibrated_classifier(model: CollisionModel, episodes) -> CollisionModel:
    """`model` with the executions `episodes` (of its action) counted into the leaves they reached and those
    leaves' verdicts taken again (see the module's docstring); the same splits and features."""
    learned = (model.report or {}).get("outcomes")
    failing = None if not isinstance(learned, dict) else {o for o in learned if o != "success"}
    kept = [e for e in episodes if e.succeeded or failing is None or e.outcome in failing]
    tree = model.tree
    if not kept or tree.failures is None:  # (no counts to weigh the executions against: kept as trained)
        return model
    failed = np.array([not e.succeeded for e in kept])
    leaves = model.leaf(np.array([e.params for e in kept], dtype=float))
    nodes = len(tree.children_left)
    runs = np.bincount(leaves, minlength=nodes)
    fails = np.bincount(leaves, weights=failed, minlength=nodes)
    weight = float((model.report or {}).get("class_weight_fail", 1.0))
    success = tree.success.copy()
    for leaf in np.flatnonzero(runs >= MIN_LEAF_EXECUTIONS):
        share = min(1.0, TRAINED_WEIGHT / tree.samples[leaf]) if tree.samples[leaf] else 0.0
        n = tree.samples[leaf] * share + runs[leaf]
        f = tree.failures[leaf] * share + fails[leaf]
        success[leaf] = weight * f <= n - f  # the classifier's rule: failures weighed against successes
    counted = tree.counted_more(leaves, failed)
    report = {**model.report, "recalibrated": {"executions": len(kept), "failed": int(failed.sum()),
                                               "leaves_changed": int(np.sum(success != tree.success))}}
    return replace(model, tree=replace(counted, success=success), report=report)


def retrained(model: ActionModel, episodes: list[Episode], entry: SimulatorEntry) -> ActionModel | None:
    """A duration model of `model`'s action trained on the executed `episodes` alone, by the training protocol (one
    sample per execution: its start), in features selected on them (`reselected`): the robot may have changed in
    what `model`'s features take as known (an acceleration limit a space bakes in). The further measures' models,
    which share the features, are trained on the executions too where the features changed, and kept as trained
    where not (where the executions do not report those measures, the features are kept); None where the executions
    are too few."""
    from tailor.errors import DataError
    from tailor.refinement.learning.duration_protocol import train_duration_model
    from tailor.refinement.learning.training import measure_models

    observed = tuple(entry.action(model.action).observed)
    starts = [Episode(e.action, np.asarray(e.params, dtype=float), np.zeros(1),
                      np.asarray(e.params, dtype=float)[None, :len(observed)], observed, e.outcome, e.duration, e.seed,
                      measures=e.measures)
              for e in episodes]
    # new features need the further measures' models anew: only where every execution reports those measures
    measured = all(set(model.measures) <= set(e.measures) for e in starts if e.succeeded)
    generated = reselected(model, starts, entry) if measured else None
    own = model.expressions if model.expressions is not None else model.feature_space
    space = generated if generated is not None else own
    try:
        fresh = train_duration_model(model.action, starts, 0, space, observed, n_i_candidates=(1,)).model
        measures = model.measures
        if generated is not None and model.measures:
            measures = measure_models(model.action, tuple(model.measures), space, starts, 0, observed, entry)
    except DataError:
        return None
    retraining = {"executions": len(episodes), "features": list(fresh.feature_names)}
    if generated is None:  # the duration tree and its leaves' uncertainty are the new ones
        return replace(model, duration=fresh.duration, n_i=fresh.n_i, uncertainty=fresh.uncertainty,
                       report={**model.report, "retrained": retraining})
    return replace(fresh, measures=measures, report={**fresh.report, "retrained": retraining}, source=model.source)


def reselected(model: ActionModel, episodes: list[Episode], entry: SimulatorEntry) -> ExpressionSpace | None:
    """The generated features to learn `episodes` (executions) in, or None to keep `model`'s own: None unless the
    features automatic selection (Sec. 4.1.1) generates on them predict them with at most RESELECT_SHARE of the own
    space's cross-validated error. A few hundred executions select noisily, and the own space has proven itself on
    the robot as trained."""
    from tailor.refinement.learning.feature_selection import select_features

    selection = select_features(entry.action(model.action), entry, episodes, 0, others={"own": model.space})
    errors = selection.report["candidate_sets"]  # cross-validated MAE on the executions (own's always finishes)
    if selection.generated is None or not errors["generated"] <= RESELECT_SHARE * errors["own"]:
        return None
    return selection.generated
