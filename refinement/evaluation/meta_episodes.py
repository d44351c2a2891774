"""Episodes of the meta action model (Sec. 5.5.4): one random situation executed greedy (h = 1) and refined,
labelled better / equal / worse, with the features the meta model judges it by (tailor.refinement.meta_filter).

Both executions use the situation's simulator seed (common random numbers), so the filtered execution of a
situation is exactly one of the two: the refined one where the meta model predicts "better", else the greedy
one. Filtered and unfiltered refinement are therefore compared on the very same episodes.
"""

from __future__ import annotations

import numpy as np

from tailor.refinement.evaluation.experiments import EQUAL_BAND, outcome_of, situation_seed
from tailor.refinement.meta_filter import meta_features
from tailor.refinement.pipeline import Options, refine_stage
from tailor.refinement.situations import Job, asserted_situation, job_models

CLASSES = ("better", "equal", "worse")  # Table 5.4's +, 0, -


def label_gain(gain: float, band: float = EQUAL_BAND) -> str:
    """better / equal / worse of a relative gain 1 - t_refined / t_greedy: "equal" within +-band, the tolerance
    `tailor evaluate` counts its better / equal / worse with (1%)."""
    return "better" if gain > band else "worse" if gain < -band else "equal"


def meta_episode(job: Job, index: int, objects: dict, horizon: int, risk: float = 0.0,
                 neighbourhood: float = 0.0) -> dict:
    """One situation: greedy and refined (analytic, `horizon`, with the risk lambda and neighbourhood the
    filtered refinement uses), both dispatched with the situation's seed; what the meta model judges it by (the
    first window's features at the greedy parameterization, refinement's predicted gain)."""
    seed = situation_seed(job.seed, index)
    sequence, success = asserted_situation(job, objects)
    models = job_models(job, sequence)
    options = Options(horizon=horizon, optimizer="analytic", seed=seed, risk=risk, neighbourhood=neighbourhood,
                      simulate=True)
    stage = refine_stage(sequence, models, success, options)
    greedy, refined = stage.greedy.refined, stage.refined.refined
    g, r = stage.greedy.simulated, stage.refined.simulated
    features = meta_features(greedy, refined, models, horizon)
    return {"index": index, "seed": seed, "problem": job.plan.problem, "situation": objects,
            "greedy": g.duration, "refined": r.duration, "greedy_ok": g.succeeded, "refined_ok": r.succeeded,
            "greedy_outcome": outcome_of(g), "refined_outcome": outcome_of(r),
            "predicted_greedy": greedy.predicted_total, "predicted_refined": refined.predicted_total,
            "signature": [list(s) for s in features.signature], "feature_names": list(features.names),
            "features": [float(v) for v in features.values]}


def gain_of(row: dict) -> float | None:
    """1 - t_refined / t_greedy of an episode where both executions succeeded, else None."""
    if not (row["greedy_ok"] and row["refined_ok"]) or row["greedy"] <= 0:
        return None
    return float(1.0 - row["refined"] / row["greedy"])


def outcome_table(rows: list[dict], refined: list[bool] | None = None) -> dict:
    """Table 5.4 (every situation refined) or 5.6 (`refined[i]` False: situation i kept greedy, gain 0) over
    the situations where greedy and refined both succeeded: episodes, mean improvement (Eq. 5.3), better /
    equal / worse with their shares and mean improvements; failures of the executions actually run."""
    from scipy.stats import ttest_rel

    refined = [True] * len(rows) if refined is None else list(refined)
    both = [(r, f) for r, f in zip(rows, refined) if gain_of(r) is not None]
    gains = np.array([gain_of(r) if f else 0.0 for r, f in both])
    labels = np.array([label_gain(g) for g in gains])
    g = np.array([r["greedy"] for r, _ in both])
    t = np.array([r["refined"] if f else r["greedy"] for r, f in both])
    out = {"scenarios": len(rows), "episodes": len(both), "refined": int(sum(refined)),
           "failed": sum(not (r["refined_ok"] if f else r["greedy_ok"]) for r, f in zip(rows, refined)),
           "greedy_mean": float(g.mean()) if len(g) else None, "mean": float(t.mean()) if len(t) else None,
           "improvement": float(gains.mean()) if len(gains) else None,
           "p_value": float(ttest_rel(g, t).pvalue) if len(g) > 1 and np.any(g != t) else None}
    for c in CLASSES:
        mask = labels == c
        out[c] = int(mask.sum())
        out[f"{c}_share"] = float(mask.mean()) if len(labels) else None
        out[f"improvement_{c}"] = float(gains[mask].mean()) if mask.any() else None
    return out
