"""Measure subgoal refinement in the simulator (Sec. 5.5): greedy (h = 1) vs refined (h = 2) on random
situations, the distance to the simulated optimum, optimizer speed, an optional baseline with every free
parameter zero, and the horizons 1-4 (Table 5.3), for any domain whose binding names its situations:

    [evaluation]
    comparison = "score"     # situation generator of the simulator for greedy vs refined (Tables 5.1, 5.4)
    horizons = "waypoints"   # situation generator for the horizon experiment (Table 5.3); optional
    assertion = "approach"   # situation generator for subgoal assertion (Table 6.1, `--assertion`); optional

The binding's `[refinement]` table (binding.RefinementDefaults) says whether the zero baseline (every free
parameter 0) is executed too, whether the meta filter runs, and the neighbourhood refinement minimizes over.

Every situation goes through the real pipeline: a random belief state, Algorithm 3 on the problem's plan
(planned once per problem), subgoal assertion (Alg. 5) where the binding names success models, refinement
within their predicted-success regions (Alg. 6), dispatch. All executions of one situation use the same simulator
seed (common random numbers), so their difference is the effect of the chosen subgoals, not of the noise.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping

import numpy as np

from tailor.refinement.action_sequence import ActionSequence
from tailor.refinement.dispatch import dispatch
from tailor.refinement.optimizers import DEFAULT_OPTIMIZER
from tailor.refinement.pipeline import Options, refine_stage
from tailor.refinement.refine import refine
from tailor.refinement.models.meta_model import EQUAL_BAND  # "equal" within 1% (Table 5.4), as the meta model's
from tailor.sims.episode import FAILED_RUN_PENALTY
from tailor.refinement.situations import Job, asserted_situation, job_meta_model, job_models, stream_seed

AGREEMENT = 0.01  # analytic and ga agree when their predicted costs differ by at most 1%
ORACLE_ANGLES = 36  # grid of the simulated search: a free parameter spanning a full circle (10 degree steps) ...
ORACLE_VALUES = 4  # ... any other free parameter: values spread over its range
ORACLE_GRID_LIMIT = 5000  # larger grids are searched coordinate-wise instead (see _oracle)
ORACLE_PASSES = 2  # coordinate-search passes over all free parameters
ORACLE_LINE_VALUES = 9  # values per free parameter in a coordinate-search line
FULL_CIRCLE = 2 * math.pi - 1e-9
# s, what a failed execution costs on top of the time it ran, in the penalized means (every scenario counted):
# a failure is as bad as waiting for one more action to time out (30 s: the mobile robot's action timeout)
FAILURE_PENALTY_S = FAILED_RUN_PENALTY


def situation_seed(seed: int, index: int) -> int:
    return stream_seed(seed, index)


def comparison_episode(job: Job, index: int, objects: dict, oracle: bool, zero: bool, meta: bool = False,
                       risk: float = 0.0, sweep: tuple[float, ...] = (), neighbourhood: float = 0.0,
                       optimizer: str = DEFAULT_OPTIMIZER) -> dict:
    """One situation: greedy, refined (with `optimizer`, auto by default, and the GA; with the risk lambda
    `risk`), optionally the zero baseline, the oracle, and the refined sequence with each risk lambda of `sweep`,
    all dispatched with the same simulator seed. With `meta`, the refined execution is the greedy one where the
    meta model (models/meta.json) does not predict that refinement makes it better (Sec. 5.5.4); the optimizer
    statistics still describe the refinement. Every window records which optimizer's choice it took, its time
    and gap, and where that optimizer was not the GA, the GA's cost on the same window."""
    seed = situation_seed(job.seed, index)
    sequence, success = asserted_situation(job, objects)
    models = job_models(job, sequence)
    options = Options(horizon=2, optimizer=optimizer, seed=seed, risk=risk, neighbourhood=neighbourhood, filter=meta,
                      zero=zero, simulate=True)
    stage = refine_stage(sequence, models, success, options, job_meta_model(job) if meta else None)
    greedy, refined, optimized, decision = stage.greedy.refined, stage.refined.refined, stage.optimized, stage.decision
    # where every window took the GA's choice, the GA run is that same run; else the GA refines on its own, and
    # each window is minimized by both (the same seed and inputs: the same windows and choices again)
    fell_back = optimized.windows and all(w.method == "ga" for w in optimized.windows)
    genetic = optimized if fell_back else refine(sequence, models, horizon=2, method="ga", seed=seed,
                                                 success_models=success, risk=risk, neighbourhood=neighbourhood)
    both = optimized if fell_back or not optimized.windows else refine(
        sequence, models, horizon=2, method=optimizer, seed=seed, success_models=success, risk=risk,
        neighbourhood=neighbourhood, compare="ga")
    g, r = stage.greedy.simulated, stage.refined.simulated
    out = {"index": index, "seed": seed, "problem": job.plan.problem,
           "greedy": g.duration, "refined": r.duration, "greedy_ok": g.succeeded, "refined_ok": r.succeeded,
           "greedy_outcome": outcome_of(g), "refined_outcome": outcome_of(r),
           "predicted_greedy": greedy.predicted_total, "predicted_refined": refined.predicted_total,
           "analytic_seconds": sum(w.seconds for w in optimized.windows),
           "analytic_window_seconds": [w.seconds for w in optimized.windows],
           "analytic_method": ",".join(w.method for w in optimized.windows),
           "ga_seconds": sum(w.seconds for w in genetic.windows),
           "analytic_cost": optimized.predicted_total, "ga_cost": genetic.predicted_total,
           "windows": [_window_row(w, optimized.window_actions[k] if k < len(optimized.window_actions) else k,
                                   both.compared[k] if k < len(both.compared) else None)
                       for k, w in enumerate(optimized.windows)],
           "greedy_actions": [[a.action, a.duration] for a in g.results],
           "refined_actions": [[a.action, a.duration] for a in r.results]}
    if decision is not None:
        out["filter"] = decision.to_json()
    if sweep:  # each lambda's refinement, as refined (unfiltered: the sweep compares objectives)
        out["sweep"] = {}
        for lam in sweep:
            at = optimized if lam == risk else refine(sequence, models, horizon=2, method=optimizer, seed=seed,
                                                      success_models=success, risk=lam, neighbourhood=neighbourhood)
            result = dispatch(at.sequence, seed=seed) if at is not refined else r
            out["sweep"][repr(float(lam))] = {"refined": result.duration, "refined_ok": result.succeeded,
                                              "refined_outcome": outcome_of(result),
                                              "predicted_refined": at.predicted_total}
    if zero:  # (a sequence without free parameters has nothing to set to zero: its zero run is the greedy one)
        z = stage.zero.simulated if stage.zero is not None else g
        out["zero"], out["zero_ok"] = z.duration, z.succeeded
    if oracle:
        start = {p.id: p.value for a in refined.sequence.actions for p in a.params}
        out["oracle"], out["oracle_method"] = _oracle(sequence, seed, start)
    return out


def _window_row(window, action: int, ga) -> dict:
    """One window of the refined run: the optimizer whose choice it took, its time, cost and gap, and (where that
    optimizer was not the GA) the GA's cost and time on the same window."""
    row = {"method": window.method, "seconds": window.seconds, "cost": window.cost, "gap": window.gap,
           "action": action}
    if ga is not None and window.method != "ga":
        row.update(ga_cost=ga.cost, ga_seconds=ga.seconds)
    return row


def outcome_of(result) -> str:
    """A dispatched sequence's outcome: "success", or the first failing action's outcome (e.g. "timeout")."""
    return next((r.outcome for r in result.results if r.outcome != "success"), "success" if result.results
                else "not_started")


def situation_rows(rows: list[dict], situations: dict[int, dict]) -> list[dict]:
    """Per situation, what a re-analysis needs: the situation (belief values per object), and the greedy and
    refined (and zero-baseline, oracle) predicted and simulated durations (s) with their outcomes."""
    out = []
    for r in rows:
        row = {"index": r["index"], "seed": r["seed"], "problem": r["problem"],
               "situation": situations.get(r["index"]),
               "greedy": {"predicted": r["predicted_greedy"], "simulated": r["greedy"],
                          "outcome": r["greedy_outcome"]},
               "refined": {"predicted": r["predicted_refined"], "simulated": r["refined"],
                           "outcome": r["refined_outcome"], "optimizer": r["analytic_method"]}}
        if "zero" in r:
            row["zero"] = {"simulated": r["zero"], "outcome": "success" if r["zero_ok"] else "failed"}
        if r.get("oracle_method"):
            row["oracle"] = {"simulated": r.get("oracle"), "method": r["oracle_method"]}
        if "filter" in r:
            row["filter"] = r["filter"]
        if "sweep" in r:  # the refined execution with each risk lambda of the sweep
            row["risk_sweep"] = {lam: {"predicted": v["predicted_refined"], "simulated": v["refined"],
                                       "outcome": v["refined_outcome"]} for lam, v in r["sweep"].items()}
        out.append(row)
    return out


def horizon_rows(rows: list[dict], situations: dict[int, dict], horizons: tuple[int, ...]) -> list[dict]:
    """Per situation of the horizon experiment: the situation, its number of actions and, per horizon, the
    horizon in effect (at most that number), predicted and simulated (s)."""
    return [{"index": r["index"], "seed": r["seed"], "problem": r["problem"], "situation": situations.get(r["index"]),
             "actions": r["actions"],
             "horizons": [{"horizon": h, "effective": effective_horizon(h, r["actions"]),
                           "predicted": r[f"h{h}_predicted"], "simulated": r[f"h{h}"],
                           "succeeded": r[f"h{h}_ok"], "optimizer": r[f"h{h}_methods"]} for h in horizons]}
            for r in rows]


def effective_horizon(horizon: int, actions: int) -> int:
    """The horizon refinement acts with on a sequence of `actions` actions: a window longer than the sequence
    is the whole sequence, so h > n is h = n."""
    return max(1, min(horizon, actions))


def distinct_horizons(rows: list[dict], horizons: tuple[int, ...]) -> tuple[int, ...]:
    """The horizons that differ from a shorter one in at least one situation of `rows` (the first always): a
    horizon longer than every sequence refines as the longest sequence's length, and is not reported."""
    longest = max((r["actions"] for r in rows), default=0)
    return tuple(h for h in horizons if h == horizons[0] or h <= longest)


def _axis(p) -> np.ndarray:
    if p.high - p.low >= FULL_CIRCLE:
        return np.linspace(p.low, p.high, ORACLE_ANGLES, endpoint=False)
    return np.linspace(p.low, p.high, ORACLE_VALUES)


def _simulated(sequence: ActionSequence, assignment: Mapping[str, float], seed: int) -> float | None:
    result = dispatch(sequence.bind(assignment), seed=seed)
    return result.duration if result.succeeded else None


def _oracle(sequence: ActionSequence, seed: int, start: Mapping[str, float]) -> tuple[float | None, str]:
    """The best simulated duration over the free parameters (the optimum the models aim at): an exhaustive grid
    where it has at most ORACLE_GRID_LIMIT points, else a coordinate search in the simulator from the refined
    values (each free parameter swept over its range in turn, ORACLE_PASSES times): an upper bound of the
    optimum. None if no point succeeds."""
    free = sequence.free_parameters()
    axes = [_axis(p) for p in free]
    if math.prod(len(a) for a in axes) <= ORACLE_GRID_LIMIT:
        best = None
        for point in itertools.product(*axes):
            d = _simulated(sequence, {p.id: float(v) for p, v in zip(free, point)}, seed)
            if d is not None and (best is None or d < best):
                best = d
        return best, "grid"
    current = {p.id: float(start[p.id]) for p in free}
    best = _simulated(sequence, current, seed)
    for _ in range(ORACLE_PASSES):
        for p in free:
            for value in np.linspace(p.low, p.high, ORACLE_LINE_VALUES):
                trial = {**current, p.id: float(value)}
                d = _simulated(sequence, trial, seed)
                if d is not None and (best is None or d < best):
                    best, current = d, trial
    return best, "coordinate search"


def horizon_episode(job: Job, index: int, objects: dict, horizons: tuple[int, ...]) -> dict:
    """One situation, executed with each horizon (same simulator seed for all); a horizon longer than the
    sequence is its length (effective_horizon): refined and simulated once, its results repeated."""
    seed = situation_seed(job.seed, index)
    sequence, success = asserted_situation(job, objects)
    models = job_models(job, sequence)
    out = {"index": index, "seed": seed, "problem": job.plan.problem, "actions": len(sequence.actions)}
    done: dict[int, dict] = {}  # effective horizon -> its results
    for h in horizons:
        effective = effective_horizon(h, len(sequence.actions))
        if effective not in done:
            options = Options(horizon=effective, seed=seed, risk=0.0, neighbourhood=0.0, greedy=False, simulate=True)
            stage = refine_stage(sequence, models, success, options)
            refined, result = stage.refined.refined, stage.refined.simulated
            done[effective] = {"": result.duration, "_ok": result.succeeded, "_predicted": refined.predicted_total,
                               "_methods": sorted({w.method for w in refined.windows}),
                               "_actions": [[a.action, a.duration] for a in result.results]}
        out.update({f"h{h}{key}": value for key, value in done[effective].items()})
    return out


def _mean(values) -> float | None:
    return float(np.mean(values)) if len(values) else None


def _ratio(rows: list[dict], key: str) -> float | None:
    return float(np.mean([r[key] for r in rows]) / np.mean([r["oracle"] for r in rows])) if rows else None


def summarize_comparison(rows: list[dict]) -> dict:
    """Table 5.1 / 5.4 numbers over the situations where greedy and refined execution both succeeded."""
    from scipy.stats import ttest_rel

    both = [r for r in rows if r["greedy_ok"] and r["refined_ok"]]
    g = np.array([r["greedy"] for r in both])
    t = np.array([r["refined"] for r in both])
    gain = 1.0 - t / g if len(both) else np.array([])
    better, worse = gain > EQUAL_BAND, gain < -EQUAL_BAND
    equal = ~better & ~worse
    p_value = float(ttest_rel(g, t).pvalue) if len(both) > 1 and np.any(g != t) else None
    oracle_rows = [r for r in both if r.get("oracle") is not None]
    analytic_ms = 1000 * np.array([r["analytic_seconds"] for r in rows])
    ga_ms = 1000 * np.array([r["ga_seconds"] for r in rows])
    agree = [abs(r["ga_cost"] - r["analytic_cost"]) <= AGREEMENT * r["analytic_cost"] for r in rows]
    out = {
        "episodes": len(both),
        "scenarios": len(rows),
        **_failure_summary(rows),
        "problems": sorted({r["problem"] for r in rows}),
        "failed_greedy": sum(not r["greedy_ok"] for r in rows),
        "failed_refined": sum(not r["refined_ok"] for r in rows),
        "greedy_mean": _mean(g),
        "refined_mean": _mean(t),
        "improvement": _mean(gain),
        "p_value": p_value,
        "better": int(better.sum()),
        "equal": int(equal.sum()),
        "worse": int(worse.sum()),
        "worse_share": float(worse.mean()) if len(both) else None,
        "improvement_better": _mean(gain[better]),
        "improvement_equal": _mean(gain[equal]),
        "improvement_worse": _mean(gain[worse]),
        "predicted_improvement": _mean([1 - r["predicted_refined"] / r["predicted_greedy"] for r in both]),
        "oracle_episodes": len(oracle_rows),
        "oracle_methods": sorted({r["oracle_method"] for r in oracle_rows}),
        "oracle_ratio": _ratio(oracle_rows, "refined"),
        "oracle_ratio_per_episode": _mean([r["refined"] / r["oracle"] for r in oracle_rows]),
        "greedy_oracle_ratio": _ratio(oracle_rows, "greedy"),
        "analytic_ms_median": float(np.median(analytic_ms)) if len(rows) else None,
        "window_ms_median": (float(1000 * np.median([w for r in rows for w in r.get("analytic_window_seconds", [])]))
                             if any(r.get("analytic_window_seconds") for r in rows) else None),
        "optimizer_share": (_mean([r["analytic_seconds"] / r["refined"] for r in both if r["refined"] > 0])
                            if both else None),
        "ga_ms_median": float(np.median(ga_ms)) if len(rows) else None,
        "analytic_fallbacks": sum("analytic" not in r["analytic_method"] for r in rows),
        "analytic_ga_agree": float(np.mean(agree)) if rows else None,
        # refining the next window while the current action executes: the time execution waits for it
        "optimizer_wait_share": (_mean([_wait_share(r) for r in both if r["refined"] > 0 and "windows" in r])
                                 if any("windows" in r for r in both) else None),
        "optimizers": optimizer_summary(rows),
    }
    out["per_action"] = _per_action(both)
    if any("filter" in r for r in rows):
        decisions = [r["filter"] for r in rows if "filter" in r]
        out["filter_decisions"] = {"refined": sum(d["refine"] for d in decisions),
                         "kept_greedy": sum(not d["refine"] for d in decisions),
                         "not_judged": sum(d["prediction"] is None for d in decisions)}
    if rows and "zero" in rows[0]:
        out.update(_zero_summary(rows))
    out.update(_stronger_baseline(rows))
    return out


def optimizer_summary(rows: list[dict]) -> dict:
    """Per optimizer whose choices the refined windows took: its share of the windows, median time per window,
    its certified gaps, and where it was not the GA, its cost against the GA's on the same windows."""
    windows = [w for r in rows for w in r.get("windows", ())]
    out = {}
    for method in sorted({w["method"] for w in windows}):
        mine = [w for w in windows if w["method"] == method]
        shares = [w["gap"] / abs(w["cost"]) for w in mine if w.get("gap") is not None and w["cost"]]
        entry = {"windows": len(mine), "share": len(mine) / len(windows),
                 "median_ms": float(1000 * np.median([w["seconds"] for w in mine])),
                 "certified_windows": len(shares),
                 "gap_share_median": float(np.median(shares)) if shares else None,
                 "gap_share_max": float(np.max(shares)) if shares else None}
        paired = [(w["cost"], w["ga_cost"]) for w in mine if "ga_cost" in w]
        if paired:
            cost, ga = np.array(paired).T
            above = (cost - ga) / np.abs(ga)
            entry["vs_ga"] = {"windows": len(paired), "cost_mean": float(cost.mean()), "ga_cost_mean": float(ga.mean()),
                              "above_ga_max": float(above.max()), "above_ga_by_more_than_0.1%": int((above > 1e-3).sum()),
                              "below_ga": int((cost < ga - 1e-9 * np.abs(ga)).sum()),
                              "ga_median_ms": float(1000 * np.median([w["ga_seconds"] for w in mine if "ga_cost" in w]))}
        out[method] = entry
    return out


def _wait_share(row: dict) -> float:
    """How long execution waits for the optimizer, as a share of the executed duration, where each window is
    refined while the action before it executes (the first before execution starts): action a starts when
    action a - 1 has ended and its own window (begun when action a - 1 began) is done."""
    durations = [d for _, d in row["refined_actions"]]
    if not durations or not sum(durations):
        return 0.0
    seconds = [0.0] * len(durations)
    for w in row["windows"]:
        if w["action"] < len(seconds):
            seconds[w["action"]] += w["seconds"]
    start = end = wait = 0.0
    for a, d in enumerate(durations):
        ready = start + seconds[a] if a else seconds[0]
        begin = max(end, ready)
        wait += begin - end
        start, end = begin, begin + d
    return wait / sum(durations)


def _stronger_baseline(rows: list[dict]) -> dict:
    """Refined against the better of greedy and the zero baseline (where the binding runs it): the one with the
    lower mean over the situations where all of them succeeded, and the mean improvement over it there (greedy
    can be slower than stopping at every way-point, and an improvement over greedy then overstates refinement)."""
    has_zero = bool(rows) and "zero" in rows[0]
    ok = [r for r in rows if r["greedy_ok"] and r["refined_ok"] and (not has_zero or r["zero_ok"])]
    if not ok:
        return {"stronger_baseline": None, "improvement_over_stronger_baseline": None}
    means = {"greedy": float(np.mean([r["greedy"] for r in ok]))}
    if has_zero:
        means["zero"] = float(np.mean([r["zero"] for r in ok]))
    name = min(means, key=means.get)
    return {"stronger_baseline": name, "stronger_baseline_mean": means[name], "stronger_baseline_episodes": len(ok),
            "improvement_over_stronger_baseline": float(np.mean([1.0 - r["refined"] / r[name] for r in ok]))}


SWEEP_KEYS = ("episodes", "failure_rate_greedy", "failure_rate_refined", "penalized_improvement", "improvement",
              "predicted_improvement", "better", "equal", "worse", "worse_share", "oracle_episodes", "oracle_ratio",
              "oracle_ratio_per_episode", "greedy_oracle_ratio")


def summarize_risk_sweep(rows: list[dict]) -> list[dict]:
    """Per risk lambda of the sweep, the comparison's headline numbers with that lambda's refined executions
    (the same situations, greedy runs and oracle for every lambda)."""
    if not rows or "sweep" not in rows[0]:
        return []
    table = []
    for lam in rows[0]["sweep"]:
        summary = summarize_comparison([{**r, **r["sweep"][lam]} for r in rows])
        table.append({"risk": float(lam), **{k: summary[k] for k in SWEEP_KEYS}})
    return table


def _failure_summary(rows: list[dict]) -> dict:
    """Failure rates of greedy and refined side by side, and the means over every scenario with a failed run
    counted as its elapsed time plus FAILURE_PENALTY_S (the means above hide failures: they keep only the
    scenarios where both succeeded)."""
    if not rows:
        return {"failure_rate_greedy": None, "failure_rate_refined": None, "penalized_greedy_mean": None,
                "penalized_refined_mean": None, "penalized_improvement": None,
                "failure_penalty_s": FAILURE_PENALTY_S}
    g = np.array([r["greedy"] + (0.0 if r["greedy_ok"] else FAILURE_PENALTY_S) for r in rows])
    t = np.array([r["refined"] + (0.0 if r["refined_ok"] else FAILURE_PENALTY_S) for r in rows])
    return {
        "failure_rate_greedy": float(np.mean([not r["greedy_ok"] for r in rows])),
        "failure_rate_refined": float(np.mean([not r["refined_ok"] for r in rows])),
        "penalized_greedy_mean": float(g.mean()),
        "penalized_refined_mean": float(t.mean()),
        "penalized_improvement": float(np.mean(1.0 - t / g)),
        "failure_penalty_s": FAILURE_PENALTY_S,
    }


def _per_action(both: list[dict]) -> list[dict]:
    """Table 5.2: the mean duration of each action of each problem's executed sequence, greedy and refined
    (Eq. 5.4), over the situations where both executions succeeded. Subgoal assertion may insert an action in
    some situations of a problem: each sequence of actions is a table of its own (`situations` says how many)."""
    groups: dict[tuple, list[dict]] = {}
    for r in both:
        if "greedy_actions" not in r:
            continue
        actions = tuple(action for action, _ in r["refined_actions"])
        if actions == tuple(action for action, _ in r["greedy_actions"]):
            groups.setdefault((r["problem"], actions), []).append(r)
    table = []
    for (problem, actions), rows in sorted(groups.items(), key=lambda item: (item[0][0], -len(item[1]))):
        for k, action in enumerate(actions):
            table.append({"problem": problem, "step": k + 1, "action": action, "situations": len(rows),
                          "greedy_mean": _mean([r["greedy_actions"][k][1] for r in rows]),
                          "refined_mean": _mean([r["refined_actions"][k][1] for r in rows])})
    return table


def _zero_summary(rows: list[dict]) -> dict:
    """Refined vs the zero baseline, paired over the situations where both succeeded."""
    from scipy.stats import ttest_rel

    both = [r for r in rows if r["zero_ok"] and r["refined_ok"]]
    z = np.array([r["zero"] for r in both])
    t = np.array([r["refined"] for r in both])
    return {
        "zero_episodes": len(both),
        "failed_zero": sum(not r["zero_ok"] for r in rows),
        "zero_mean": _mean(z),
        "improvement_over_zero": _mean(1.0 - t / z) if len(both) else None,
        "p_value_zero": float(ttest_rel(z, t).pvalue) if len(both) > 1 and np.any(z != t) else None,
    }


def summarize_horizons(rows: list[dict], horizons: tuple[int, ...]) -> dict:
    """Table 5.3: mean duration per horizon over the situations where every horizon succeeded; per horizon also
    how many situations have fewer actions than it (there it acts as their length)."""
    from scipy.stats import ttest_rel

    ok = [r for r in rows if all(r[f"h{h}_ok"] for h in horizons)]
    out = {"episodes": len(ok), "scenarios": len(rows), "problems": sorted({r["problem"] for r in rows}),
           "horizons": []}
    base = np.array([r[f"h{horizons[0]}"] for r in ok])
    previous = base
    for h in horizons:
        times = np.array([r[f"h{h}"] for r in ok])
        p = (float(ttest_rel(previous, times).pvalue)
             if h != horizons[0] and len(ok) > 1 and np.any(previous != times) else None)
        out["horizons"].append({
            "horizon": h, "mean": _mean(times),
            "improvement": _mean(1 - times / base) if len(ok) else None,
            "improvement_over_previous": _mean(1 - times / previous) if len(ok) else None,
            "p_value_vs_previous": p,
            "failed": sum(not r[f"h{h}_ok"] for r in rows),
            "shorter": sum(r["actions"] < h for r in rows if "actions" in r),
            "methods": sorted({m for r in rows for m in r[f"h{h}_methods"]}),
        })
        previous = times
    out["per_action"] = horizon_per_action(ok, horizons)
    return out


def horizon_per_action(ok: list[dict], horizons: tuple[int, ...]) -> list[dict]:
    """Table 5.2(b): the mean duration of each action of the horizon sequence with the first horizon (greedy,
    h = 1) and the next (refined, h = 2), over the situations where every horizon succeeded (those of Table 5.3,
    so each column sums to its horizon's mean); as Table 5.2(a), one table per executed sequence."""
    if len(horizons) < 2 or not all(f"h{h}_actions" in r for r in ok for h in horizons[:2]):
        return []
    first, second = horizons[:2]
    return _per_action([{"problem": r["problem"], "greedy_actions": r[f"h{first}_actions"],
                         "refined_actions": r[f"h{second}_actions"]} for r in ok])
