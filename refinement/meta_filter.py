"""The meta filter (Sec. 5.5.4): refine a situation only where the meta action model predicts that refinement
makes its execution faster ("better"); elsewhere keep the greedy parameterization.

The meta model judges a situation by the features its action models see in the first refinement window at the
greedy (h = 1) parameterization: the same invariant features (Table 4.1) the duration models learned from, so
a situation translated, rotated or mirrored is judged alike, and any domain gets them without code. For a
chain of navigation actions they say how well start, subgoal and goal line up (the greedy heading at the
subgoal against the direction of the next leg) and how far apart they are: what the dissertation's tree
splits on.

Beside them the meta model sees what the action models predict refinement gains there (`REFINEMENT_FEATURES`:
the whole sequence's predicted gain over greedy, relative and in seconds). The situation's features say where
refinement tends to hurt; the prediction says how much it expects to win, and a refinement that expects to win
little is the one the models' errors can overturn. Both are invariant, as the window features are.

The decision is per situation, "refine or keep greedy", so it composes with however the refined sequence is
computed (horizon, optimizer, any other objective): `decide` needs the greedy sequence and, for a meta model
that judges refinement's prediction, the refined one.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from tailor.refinement.action_sequence import ActionSequence
from tailor.refinement.models.meta_model import REFINEMENT_FEATURES
from tailor.refinement.refine import RefinedSequence

BETTER = "better"  # the class where refinement is applied


@dataclass(frozen=True)
class WindowFeatures:
    """The features the action models of the first window see: `signature` names each action and its feature
    space, `names` each value ("<step>.<action>.<feature>", e.g. "1.move.dist")."""

    signature: tuple[tuple[str, str], ...]
    names: tuple[str, ...]
    values: np.ndarray


def window_features(sequence: ActionSequence, models: Mapping[str, object], size: int) -> WindowFeatures:
    """The features of the first `size` actions of a fully bound sequence, each in its action model's feature
    space, concatenated in step order."""
    signature, names, values = [], [], []
    for k, action in enumerate(sequence.actions[:size]):
        model = models[action.action]
        signature.append((action.action, model.feature_space))
        names += [f"{k + 1}.{action.action}.{name}" for name in model.feature_names]
        values.append(np.asarray(model.features(action.values()[None, :]), dtype=float)[0])
    return WindowFeatures(tuple(signature), tuple(names),
                          np.concatenate(values) if values else np.empty(0))


def refinement_features(greedy: RefinedSequence, refined: RefinedSequence) -> np.ndarray:
    """REFINEMENT_FEATURES of a situation: the predicted gain of its refined sequence over its greedy one, from
    the durations refinement predicted for each."""
    t_greedy, t_refined = greedy.predicted_total, refined.predicted_total
    return np.array([1.0 - t_refined / t_greedy if t_greedy > 0 else 0.0, t_greedy - t_refined])


def meta_features(greedy: RefinedSequence, refined: RefinedSequence | None, models: Mapping[str, object], size: int
                  ) -> WindowFeatures:
    """What the meta model judges a situation by: the first window's features at the greedy parameterization,
    then (given the `refined` sequence) refinement's predicted gain."""
    window = window_features(greedy.sequence, models, size)
    if refined is None:
        return window
    return WindowFeatures(window.signature, window.names + REFINEMENT_FEATURES,
                          np.concatenate([window.values, refinement_features(greedy, refined)]))


@dataclass(frozen=True)
class MetaDecision:
    """What the meta filter decided for one situation, and why."""

    prediction: str | None  # the class the meta model predicts; None where it does not cover the situation
    refine: bool  # refine (True) or keep the greedy parameterization (False)
    leaf: int | None = None  # the meta tree's leaf, where it predicted
    reason: str = ""

    def to_json(self) -> dict:
        return {"prediction": self.prediction, "refine": self.refine, "leaf": self.leaf, "reason": self.reason}


def decide(meta, greedy: RefinedSequence, models: Mapping[str, object], refined: RefinedSequence | None = None
           ) -> MetaDecision:
    """Refine or keep greedy, from the greedy (h = 1) sequence of a situation and, where the meta model judges
    refinement's prediction (`meta.judges_refinement`), its refined sequence: refine where the meta model
    predicts "better"; where its window differs from the one it was trained on (other actions, e.g. an asserted
    subgoal) it cannot judge, and refinement is applied as without the filter."""
    if meta.judges_refinement and refined is None:
        raise ValueError("this meta model judges refinement's predicted gain: give the refined sequence")
    features = meta_features(greedy, refined if meta.judges_refinement else None, models, len(meta.window))
    if features.signature != meta.window:
        got = ", ".join(a for a, _ in features.signature) or "none"
        return MetaDecision(None, True, None, f"not judged: the first window holds {got}, the meta model knows "
                                              f"{', '.join(a for a, _ in meta.window)}; refined")
    leaf = int(meta.tree.apply(features.values[None, :])[0])
    prediction = meta.tree.classes[int(meta.tree.label[leaf])]
    refine = prediction == BETTER
    counts = ", ".join(f"{c} {int(n)}" for c, n in zip(meta.tree.classes, meta.tree.counts[leaf]))
    verdict = "refined" if refine else "greedy kept"
    return MetaDecision(prediction, refine, leaf, f"meta model predicts {prediction} (leaf {leaf}: {counts} "
                                                  f"training episodes); {verdict}")
