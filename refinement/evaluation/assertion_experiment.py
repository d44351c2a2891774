"""Measure subgoal assertion in the simulator (Sec. 6.3, Table 6.1): random situations of a problem whose plan
has an action guarded by a success classifier, each executed with the plain executable action (no assertion)
and with assertion + refinement (h = 2), with the same simulator seed.

The binding names the situations: `[evaluation] assertion = "<situation generator>"`. Reported: the shares of
successful executions without and with assertion, the share of the plain executions' collisions (failures of
the kind the classifier guards against; any failure where the simulator has no "collision" outcome) that
assertion avoided, the needless assertions (a subgoal inserted where the plain action succeeded) and their
time cost, and Table 6.1 (predicted x observed, before and after assertion). Assertion and refinement run as in
`tailor refine`: the risk lambda and neighbourhood resolved from the binding and the models, and a predicted
failure weighed against the detour (`assertion.Weighing`); how often that kept the plain action is reported.

Beside it, Table 4.4 on fresh episodes of any experience scenario (`classifier_table`, `tailor evaluate
--classifier`): how the success classifier does where the plain action fails more or less often than in the
episodes it learned from, against the baseline that predicts success always.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from tailor.refinement.assertion import Detour, assert_subgoals
from tailor.refinement.learning.classifiers import confusion, labels
from tailor.refinement.models.action_models import CollisionModel
from tailor.refinement.models.features import first_examples
from tailor.refinement.pipeline import Options, refine_stage, resolve_options
from tailor.refinement.situations import Job, job_binding, job_models, situation_sequence, stream_seed

COLLISION = "collision"
REFINE_HORIZON = 2
ASSERTION_STREAM = 6  # seed word of the assertion experiment (its situations differ from the comparison's)
# seed word of the classifier's fresh episodes: apart from those `tailor train` learned from (its seed) and
# evaluated on (its seed + FRESH_SEED_OFFSET)
CLASSIFIER_STREAM = 7


@dataclass(frozen=True)
class AssertionSetup:
    """What every episode needs besides its situation: the success classifiers, loaded once per process; how to
    refine (risk lambda and neighbourhood: None, as `tailor refine` does, the binding's and the models' defaults);
    whether assertion weighs the detour against the predicted failure (False: a subgoal wherever failure is
    predicted, Alg. 5 as the dissertation has it)."""

    success_models: dict
    method: str = "analytic"
    risk: float | None = None
    neighbourhood: float | None = None
    weigh: bool = True


def assertion_seed(seed: int, index: int) -> int:
    return stream_seed(ASSERTION_STREAM, seed, index)


def assertion_episode(job: Job, index: int, objects: dict, setup: AssertionSetup, keep: bool = False) -> dict:
    """One situation: the plain action (as instantiated) and with assertion + refinement, same seed; refined with
    the options `tailor refine` would resolve, assertion weighing the detour as the pipeline does."""
    seed = assertion_seed(job.seed, index)
    sequence = situation_sequence(job, objects)
    binding = job_binding(job)
    models = job_models(job, sequence)  # (an asserted subgoal reuses the same executable actions)
    options = resolve_options(Options(horizon=1, optimizer=setup.method, seed=seed, risk=setup.risk,
                                      neighbourhood=setup.neighbourhood, greedy=False, simulate=True), binding, models)
    detour = (Detour(models, options.optimizer, seed, options.risk, options.neighbourhood) if setup.weigh else None)
    started = time.perf_counter()
    asserted = assert_subgoals(sequence, binding, setup.success_models, job.plan.object_types or None, detour)
    assertion_seconds = time.perf_counter() - started
    stage = refine_stage(sequence, models, {}, options)  # the plain action: no guard, greedy
    plain_refined, plain = stage.refined.refined, stage.refined.simulated
    inserted = any(a.inserted for a in asserted.assertions)
    predicted_success = all(a.predicted_success for a in asserted.assertions)
    if inserted or asserted.sequence.free_parameters():
        stage = refine_stage(asserted.sequence, models, setup.success_models, replace(options, horizon=REFINE_HORIZON))
        refined, result = stage.refined.refined, stage.refined.simulated
    else:  # nothing asserted and nothing to choose: the same sequence, the same seed, the same execution
        refined, result = plain_refined, plain
    row = {"index": index, "seed": seed, "problem": job.plan.problem, "inserted": inserted,
           "predicted_success": predicted_success,
           "plain_ok": plain.succeeded, "plain_outcome": _outcome(plain), "plain_time": plain.duration,
           "with_ok": result.succeeded, "with_outcome": _outcome(result), "with_time": result.duration,
           "with_failed_leg": _failed_leg(result, refined.sequence),
           "predicted_plain": plain_refined.predicted_total, "predicted_with": refined.predicted_total,
           "methods": sorted({w.method for w in refined.windows}),
           "optimizer_seconds": sum(w.seconds for w in refined.windows),
           "assertion_seconds": assertion_seconds,
           "weighed_out": any(not a.predicted_success and not a.inserted for a in asserted.assertions),
           "weighings": [a.weighing.to_json() for a in asserted.assertions if a.weighing is not None],
           "reasons": [a.reason() for a in asserted.assertions]}
    if keep:
        row.update(plain_result=plain, with_result=result, sequence=refined.sequence, plain_sequence=sequence,
                   asserted_sequence=asserted.sequence, models=models, success_models=setup.success_models)
    return row


def _failed_leg(result, sequence) -> str | None:
    """Which action of the executed sequence failed: "to subgoal" (reaching an asserted subgoal), "final"."""
    for k, r in enumerate(result.results):
        if r.outcome != "success":
            return "to subgoal" if "to the subgoal" in sequence.actions[k].origin else "final"
    return None


def _outcome(result) -> str:
    for r in result.results:
        if r.outcome != "success":
            return r.outcome
    return "success"


def _share(mask) -> float | None:
    mask = np.asarray(mask, dtype=bool)
    return float(mask.mean()) if len(mask) else None


def confusion_table(predicted_success: np.ndarray, observed_success: np.ndarray) -> dict:
    """Table 6.1: shares of all episodes, rows predicted, columns observed."""
    n = max(1, len(predicted_success))
    out = {}
    for p_name, p in (("fail", False), ("success", True)):
        for o_name, o in (("fail", False), ("success", True)):
            out[f"predicted_{p_name}_observed_{o_name}"] = float(np.sum((predicted_success == p)
                                                                        & (observed_success == o)) / n)
    return out


def summarize_assertion(rows: list[dict]) -> dict:
    """The JSON of `tailor evaluate --assertion`: shares, avoided collisions, needless assertions, Table 6.1."""
    plain_ok = np.array([r["plain_ok"] for r in rows], dtype=bool)
    with_ok = np.array([r["with_ok"] for r in rows], dtype=bool)
    inserted = np.array([r["inserted"] for r in rows], dtype=bool)
    predicted = np.array([r["predicted_success"] for r in rows], dtype=bool)
    outcomes = {r["plain_outcome"] for r in rows}
    kind = COLLISION if COLLISION in outcomes else None  # without collisions in this simulator: any failure
    collided = np.array([(r["plain_outcome"] == kind) if kind else not r["plain_ok"] for r in rows], dtype=bool)
    still = np.array([(r["with_outcome"] == kind) if kind else not r["with_ok"] for r in rows], dtype=bool)
    avoided = collided & ~still
    needless = inserted & plain_ok
    both = needless & with_ok
    cost = [r["with_time"] / r["plain_time"] - 1.0 for r, b in zip(rows, both) if b]
    methods = sorted({m for r in rows for m in r["methods"]})
    seconds = [r["optimizer_seconds"] for r in rows if r["inserted"]]
    weighed_out = np.array([r.get("weighed_out", False) for r in rows], dtype=bool)
    weighing = [w for r in rows for w in r.get("weighings", ())]
    asserting = [r["assertion_seconds"] for r in rows if r.get("weighings")]
    return {
        "episodes": len(rows),
        "success_without": _share(plain_ok),
        "success_with": _share(with_ok),
        "collisions": int(collided.sum()),
        "collision_outcome": kind or "any failure",  # what `collisions` counts (a simulator without collisions)
        "collisions_avoided": float(avoided.sum() / collided.sum()) if collided.any() else None,
        "collisions_avoided_and_succeeded": float((avoided & with_ok).sum() / collided.sum()) if collided.any() else None,
        "asserted": _share(inserted),
        "needless_assertions": _share(needless),
        "needless_cost": float(np.mean(cost)) if cost else None,
        "needless_cost_median": float(np.median(cost)) if cost else None,
        # failure predicted, the detour predicted to cost more than the failure: no subgoal (and how that went)
        "predicted_fail": _share(~predicted),
        "weighed_out": _share(weighed_out),
        "weighed_out_failed": int((weighed_out & ~plain_ok).sum()),
        "failure_probability_sources": sorted({w["failure_probability_source"] for w in weighing}),
        "detour_predicted_median": float(np.median([w["detour"] for w in weighing])) if weighing else None,
        "assertion_ms_median": float(1000 * np.median(asserting)) if asserting else None,
        "failures_without": _counts(r["plain_outcome"] for r in rows),
        "failures_with": _counts(r["with_outcome"] for r in rows),
        "new_failures": int((plain_ok & ~with_ok).sum()),
        "failed_legs_with": _counts(r["with_failed_leg"] or "success" for r in rows),
        "table_before": confusion_table(predicted, plain_ok),
        "table_after": confusion_table(predicted, with_ok),
        "optimizers": methods,
        "optimizer_ms_median": float(1000 * np.median(seconds)) if seconds else None,
    }


def _counts(outcomes) -> dict:
    out: dict[str, int] = {}
    for o in outcomes:
        if o != "success":
            out[o] = out.get(o, 0) + 1
    return dict(sorted(out.items()))


def pick_instances(rows: list[dict], count: int = 3) -> list[dict]:
    """Fig. 6.6: one situation without assertion (success predicted) and the rest with an asserted subgoal,
    the first such situations whose executions with assertion succeeded."""
    plain = [r for r in rows if not r["inserted"] and r["with_ok"]][:1]
    asserted = [r for r in rows if r["inserted"] and r["with_ok"] and not r["plain_ok"]][:count - len(plain)]
    return plain + asserted


def classifier_seed(seed: int) -> int:
    """The seed of the fresh episodes `tailor evaluate --classifier --seed SEED` gathers (every scenario's own)."""
    return stream_seed(CLASSIFIER_STREAM, seed)


def classifier_table(model: CollisionModel, episodes: list) -> dict:
    """Table 4.4 of a success classifier on episodes of its action (predicted from each start, as in training:
    classifiers.confusion), with the shares it is read by: correct, false success (predicted success but failed,
    a share of all episodes), and the 'always success' baseline (the share that succeeded), which a classifier
    must beat by more the fewer episodes fail."""
    table = confusion(model.predict_success(first_examples(episodes)[0]), labels(episodes))
    n = max(1, table["episodes"])
    return {"episodes": table["episodes"],
            "outcomes": _counts(e.outcome for e in episodes),
            "failed": table["observed_fail"],
            "correct": table["accuracy"],
            "false_success": table["counts"]["predicted_success_observed_fail"] / n,
            "failures_predicted_success": table["false_success"],  # of the failures, as the training report has it
            "predicted_fail": table["predicted_fail"],
            "always_success": 1.0 - table["observed_fail"],
            "table": {key: count / n for key, count in table["counts"].items()}}
