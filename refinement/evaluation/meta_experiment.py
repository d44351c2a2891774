"""The meta action model experiment (Sec. 5.5.4, Tables 5.4-5.6): evaluate refinement on training situations,
learn the meta model from their labels, and measure it on fresh situations of another index range.

Training situations are indices 0..N-1 of the comparison generator's stream for the seed, fresh ones N..N+M-1:
never the same situations. On the fresh ones refinement is reported unfiltered (Table 5.4) and filtered by the
meta model (Table 5.6) over the very same executions (common random numbers, see meta_episodes), beside the
tree's confusion matrix there (Table 5.5).
"""

from __future__ import annotations

import numpy as np

from tailor.refinement.evaluation.meta_episodes import CLASSES, outcome_table


def fresh_report(model, rows: list[dict]) -> dict:
    """Table 5.4 vs 5.6 and the confusion matrix (Table 5.5) of `model` on fresh episodes `rows`."""
    from tailor.refinement.learning.meta_learning import confusion, episode_label

    covered = [tuple(tuple(s) for s in r["signature"]) == model.window for r in rows]
    refine = []
    predicted, actual = [], []
    for row, inside in zip(rows, covered):
        if not inside:  # a window the model does not know: refined, as without the filter
            refine.append(True)
            continue
        label = str(model.predict(np.array(row["features"], dtype=float)[None, :])[0])
        refine.append(label == "better")
        truth = episode_label(row, model.equal_band)
        if truth is not None:
            predicted.append(CLASSES.index(label))
            actual.append(truth)
    unfiltered, filtered = outcome_table(rows), outcome_table(rows, refine)
    return {"episodes": len(rows), "not_judged": int(len(rows) - sum(covered)),
            "unfiltered": unfiltered, "filtered": filtered,
            "confusion": confusion(np.array(actual, dtype=int), np.array(predicted, dtype=int)),
            "floor": floor_check(unfiltered, filtered)}


def floor_check(unfiltered: dict, filtered: dict) -> dict:
    """The issue's floor: the worse share drops by at least two thirds, the mean improvement does not drop."""
    u, f = unfiltered.get("worse_share"), filtered.get("worse_share")
    drop = None if not u else 1.0 - f / u
    kept = (filtered["improvement"] is not None and unfiltered["improvement"] is not None
            and filtered["improvement"] >= unfiltered["improvement"])
    return {"worse_share_drop": drop, "worse_drop_met": drop is not None and drop >= 2 / 3,
            "improvement_kept": kept}
