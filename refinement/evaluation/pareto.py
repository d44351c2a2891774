"""The time-energy Pareto front (Ch. 8.1): the same random situations refined for a sweep of energy weights and
executed in the simulator, `tailor evaluate DOMAIN --pareto 0,0.1,0.3,1`.

Each situation goes through the pipeline as in the comparison (tailor.refinement.evaluation.experiments): a random
belief state, Algorithm 3 on the problem's plan, subgoal assertion, then refinement (h = 2) minimizing
`duration + W * energy` for each weight W (W = 0: the duration alone, the dissertation's objective) and greedily
(h = 1) for the duration, the baseline; with `limits` (`--max error=E`) also duration-only refinement keeping every
action's predicted measure within its bound. Every run of a situation is dispatched with the same simulator seed
(common random numbers), so the differences between weights are the effect of the choices, not of the noise.

A run's measured duration and energy are the sums over its actions; its error is the largest end error of its
actions (a limit bounds every action's). A situation where any run failed is left out of every mean (excluded
pairwise, so that all means are over the same situations); the failures are counted per run. Energy (and time)
at each weight are compared with W = 0 by the Wilcoxon signed-rank test, two-sided, paired by situation.
"""

from __future__ import annotations

import math

import numpy as np

from tailor.refinement.evaluation.experiments import outcome_of, situation_seed
from tailor.refinement.objective_grammar import DURATION, DURATION_ONLY, MeasureBound, WeightedObjective
from tailor.refinement.optimizers import DEFAULT_OPTIMIZER
from tailor.refinement.pipeline import Options, refine_stage
from tailor.refinement.refine import limit_violations
from tailor.refinement.situations import Job, asserted_situation, job_models

ENERGY, ERROR = "energy", "error"  # the measure weighed against time; the one a run's precision is told by
REPORTED = (DURATION, ENERGY, ERROR)
GREEDY, LIMITED = "greedy", "limited"  # the baseline run, the run keeping the limits


def energy_objective(weight: float) -> WeightedObjective:
    """`duration + weight * energy`; weight 0 is the duration alone."""
    if not (math.isfinite(weight) and weight >= 0):
        raise ValueError(f"an energy weight is a finite number >= 0, not {weight!r}")
    return DURATION_ONLY if weight == 0 else WeightedObjective(((DURATION, 1.0), (ENERGY, float(weight))))


def weight_key(weight: float) -> str:
    """A weight as a row's key and as the JSON's `p_energy` keys: "0", "0.3"."""
    return f"{weight:g}"


def _run(execution, limits: tuple[MeasureBound, ...]) -> dict:
    """What one dispatched run measured: sums of duration and energy, the largest end error, whether every action
    ended within each limit, and the refinement's prediction."""
    result, refined = execution.simulated, execution.refined
    measures = [a.measures for a in result.results]

    def largest(name):
        values = [m[name] for m in measures if name in m]
        return max(values) if len(values) == len(measures) and values else None

    out = {"ok": result.succeeded, "outcome": outcome_of(result), "duration": result.duration,
           "energy": (float(sum(m[ENERGY] for m in measures)) if measures and all(ENERGY in m for m in measures)
                      else None),
           "error": largest(ERROR), "predicted_duration": refined.predicted_total,
           "predicted_energy": refined.measure_total(ENERGY)}
    if limits:  # a failed run, or one missing the measure, does not end within it
        out["within"] = bool(result.succeeded and all(
            (value := largest(limit.measure)) is not None and value <= limit.bound for limit in limits))
        out["actions_within"] = [[a.action, all(limit.measure in a.measures and a.measures[limit.measure] <= limit.bound
                                               for limit in limits)] for a in result.results]
        out["predicted_within"] = [[a.action, all(limit.measure in m and m[limit.measure] <= limit.bound
                                                  for limit in limits)]
                                   for a, m in zip(refined.sequence.actions, refined.measures)]
    return out


def pareto_episode(job: Job, index: int, objects: dict, weights: tuple[float, ...],
                   limits: tuple[MeasureBound, ...] = (), optimizer: str = DEFAULT_OPTIMIZER, risk: float = 0.0,
                   neighbourhood: float = 0.0) -> dict:
    """One situation: greedy (duration, h = 1) and refined (h = 2) for each energy weight, and with `limits` a
    duration-only refinement keeping them, all dispatched with the same simulator seed. The weights must hold 0
    (the reference); `binds` says whether duration-only refinement's choice breaks a limit (as predicted)."""
    if 0.0 not in weights:
        raise ValueError(f"the energy weights must hold 0 (the reference), not {weights!r}")
    seed = situation_seed(job.seed, index)
    sequence, success = asserted_situation(job, objects)
    models = job_models(job, sequence)
    row = {"index": index, "seed": seed, "problem": job.plan.problem, "weights": {}}
    for weight in weights:
        options = Options(horizon=2, optimizer=optimizer, seed=seed, risk=risk, neighbourhood=neighbourhood,
                          greedy=weight == 0, simulate=True, objective=energy_objective(weight))
        stage = refine_stage(sequence, models, success, options)
        row["weights"][weight_key(weight)] = _run(stage.refined, limits)
        if weight == 0:
            row[GREEDY] = _run(stage.greedy, limits)
            if limits:
                row["binds"] = bool(limit_violations(stage.refined.refined.sequence, models, limits))
    if limits:
        options = Options(horizon=2, optimizer=optimizer, seed=seed, risk=risk, neighbourhood=neighbourhood,
                          greedy=False, simulate=True, objective=DURATION_ONLY, limits=limits)
        stage = refine_stage(sequence, models, success, options)
        row[LIMITED] = _run(stage.refined, limits)
        row[LIMITED]["unattainable"] = bool(stage.refined.refined.violations)  # no choice kept a limit somewhere
    return row


# --- the summary -------------------------------------------------------------------------------------------------
def _mean(values) -> float | None:
    return float(np.mean(values)) if len(values) else None


def _means(runs: list[dict]) -> dict:
    return {name: _mean([r[name] for r in runs if r[name] is not None]) for name in REPORTED}


def _change(value: float | None, reference: float | None) -> float | None:
    """value / reference - 1: the relative change of a mean against weight 0's."""
    return None if value is None or not reference else value / reference - 1.0


def _wilcoxon(a: list[float], b: list[float]) -> float | None:
    """Two-sided Wilcoxon signed-rank p of the paired samples (None: fewer than two, or no difference)."""
    from scipy.stats import wilcoxon

    diff = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    if len(diff) < 2 or not np.any(diff != 0):
        return None
    return float(wilcoxon(diff).pvalue)


def front(points: list[tuple[float | None, float | None]]) -> list[bool]:
    """Per (duration, energy) point, whether no other point is at most as long and as costly and better in one
    of them (the non-dominated ones: the Pareto front). A point without both means is on no front."""
    out = []
    for k, (t, e) in enumerate(points):
        if t is None or e is None:
            out.append(False)
            continue
        out.append(not any(j != k and t2 is not None and e2 is not None and t2 <= t and e2 <= e and (t2 < t or e2 < e)
                           for j, (t2, e2) in enumerate(points)))
    return out


def summarize_pareto(rows: list[dict], weights: tuple[float, ...], limits: tuple[MeasureBound, ...] = ()) -> dict:
    """The means of greedy and of each weight over the situations where all of them succeeded, each weight's
    failed runs, its relative changes against weight 0 and the Wilcoxon p of its energy (and time) against weight
    0's, paired by situation; which points are on the front; with limits, the share of runs within them."""
    keys = [weight_key(w) for w in weights]
    reference = weight_key(0.0)
    ok = [r for r in rows if r[GREEDY]["ok"] and all(r["weights"][k]["ok"] for k in keys)]
    greedy = {**_means([r[GREEDY] for r in ok]), "failed": sum(not r[GREEDY]["ok"] for r in rows)}
    base = _means([r["weights"][reference] for r in ok])
    pareto = []
    for weight, key in zip(weights, keys):
        runs = [r["weights"][key] for r in ok]
        entry = {"weight": weight, **_means(runs), "failed": sum(not r["weights"][key]["ok"] for r in rows)}
        entry.update({f"{name}_change": _change(entry[name], base[name]) for name in REPORTED})
        for name in (ENERGY, DURATION):
            paired = [(run[name], r["weights"][reference][name]) for run, r in zip(runs, ok)
                      if run[name] is not None and r["weights"][reference][name] is not None]
            entry[f"p_{name}"] = None if key == reference else _wilcoxon([a for a, _ in paired],
                                                                         [b for _, b in paired])
        pareto.append(entry)
    marked = front([(greedy[DURATION], greedy[ENERGY])] + [(e[DURATION], e[ENERGY]) for e in pareto])
    greedy["front"] = marked[0]
    for entry, on in zip(pareto, marked[1:]):
        entry["front"] = on
    out = {"situations": len(rows), "episodes": len(ok), "failed_runs_treatment":
           "a situation where greedy or any weight's run failed is left out of every mean (excluded pairwise); "
           "the failures are counted per run", "test": "Wilcoxon signed-rank, two-sided, paired by situation",
           "greedy": greedy, "pareto": pareto,
           "p_energy": {key: entry["p_energy"] for key, entry in zip(keys, pareto) if key != reference}}
    if limits:
        out["limit"] = summarize_limit(rows, limits)
    return out


def summarize_limit(rows: list[dict], limits: tuple[MeasureBound, ...]) -> dict:
    """Duration-only refinement with and without the limits: the share of runs that end within them (a failed run
    does not), overall and where the limit binds (duration-only refinement's choice breaks it as predicted), the
    situations where no choice keeps it, and the limited runs' means against weight 0's over the situations where
    both succeeded."""
    reference = weight_key(0.0)
    binding = [r for r in rows if r["binds"]]

    def share(chosen, name):
        runs = [r["weights"][reference] if name == reference else r[name] for r in chosen]
        return sum(run["within"] for run in runs) / len(runs) if runs else None

    def per_action(name):  # every executed action's share within, by action
        runs = [r["weights"][reference] if name == reference else r[name] for r in rows]
        flags: dict[str, list[bool]] = {}
        for run in runs:
            for action, within in run["actions_within"]:
                flags.setdefault(action, []).append(within)
        return {action: sum(f) / len(f) for action, f in sorted(flags.items())}

    both = [r for r in rows if r["weights"][reference]["ok"] and r[LIMITED]["ok"]]
    limited = _means([r[LIMITED] for r in both])
    plain = _means([r["weights"][reference] for r in both])
    return {"bounds": {limit.measure: limit.bound for limit in limits}, "situations": len(rows),
            "binds": len(binding), "binds_share": len(binding) / len(rows) if rows else None,
            "within_duration_only": share(rows, reference), "within_limited": share(rows, LIMITED),
            "within_duration_only_where_binding": share(binding, reference),
            "within_limited_where_binding": share(binding, LIMITED),
            "actions_within": {"duration_only": per_action(reference), "limited": per_action(LIMITED)},
            "unattainable": sum(r[LIMITED]["unattainable"] for r in rows),
            "failed_limited": sum(not r[LIMITED]["ok"] for r in rows),
            "failed_duration_only": sum(not r["weights"][reference]["ok"] for r in rows),
            "episodes": len(both), "limited": limited, "duration_only": plain,
            **{f"{name}_change": _change(limited[name], plain[name]) for name in REPORTED}}
