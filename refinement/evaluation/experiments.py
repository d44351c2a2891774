"""Measure subgoal refinement in the simulator (Sec. 5.5): greedy (h = 1) vs refined (h = 2) on random
approachBall -> dribbleBall scenarios, the distance to the simulated optimum, optimizer speed, and the
four-way-point navigation with horizons 1-4 (Table 5.3).

Every scenario goes through the real pipeline: a random belief state for the bundled problem, Algorithm 3,
refinement, dispatch. Greedy and refined execution of one scenario use the same simulator seed (common
random numbers), so their difference is the effect of the chosen subgoal, not of the noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from tailor.refinement.belief import BeliefState
from tailor.refinement.dispatch import dispatch
from tailor.refinement.instantiate import instantiate
from tailor.refinement.pipeline import Prepared, Task, load_binding, load_models
from tailor.refinement.refine import refine

FIELD_X = (-4.0, 4.0)  # m, the simulated field (sims.soccer)
FIELD_Y = (-3.0, 3.0)
MARGIN = 0.8  # m kept free between random positions and the walls
MIN_GAP = 1.0  # m between consecutive random positions
EQUAL_BAND = 0.01  # |1 - t_refined / t_greedy| below this counts as "equal" (Table 5.4)
AGREEMENT = 0.01  # analytic and ga agree when their predicted costs differ by at most 1%
ORACLE_HEADINGS = 36  # grid of the exhaustive simulated search: headings (10 degree steps) ...
ORACLE_SPEEDS = 4  # ... times speeds spread over the free range


def _point(rng: np.random.Generator, margin: float = MARGIN) -> tuple[float, float]:
    return (float(rng.uniform(FIELD_X[0] + margin, FIELD_X[1] - margin)),
            float(rng.uniform(FIELD_Y[0] + margin, FIELD_Y[1] - margin)))


def _points(rng: np.random.Generator, n: int) -> list[tuple[float, float]]:
    """n random positions on the field, each at least MIN_GAP from the one before."""
    points = [_point(rng)]
    while len(points) < n:
        p = _point(rng)
        if math.dist(p, points[-1]) >= MIN_GAP:
            points.append(p)
    return points


def score_belief(rng: np.random.Generator) -> dict[str, dict[str, float]]:
    """A random situation of problem `score`: robot at rest at pos1, the ball at pos2, the target pose pos3."""
    robot, ball, target = _points(rng, 3)
    heading = lambda: float(rng.uniform(-math.pi, math.pi))  # noqa: E731
    return {"pos1": {"x": robot[0], "y": robot[1], "phi": heading(), "v": 0.0},
            "pos2": {"x": ball[0], "y": ball[1]},
            "pos3": {"x": target[0], "y": target[1], "phi": heading(), "v": 0.0}}


def waypoints_belief(rng: np.random.Generator) -> dict[str, dict[str, float]]:
    """A random situation of problem `waypoints`: start p0 at rest, way-points w1..w4, stop at w4."""
    points = _points(rng, 5)
    objects = {"p0": {"x": points[0][0], "y": points[0][1], "phi": float(rng.uniform(-math.pi, math.pi)), "v": 0.0}}
    for k in range(1, 5):
        objects[f"w{k}"] = {"x": points[k][0], "y": points[k][1]}
    objects["w4"].update(phi=float(rng.uniform(-math.pi, math.pi)), v=0.0)
    return objects


BELIEFS = {"score": score_belief, "waypoints": waypoints_belief}


@dataclass(frozen=True)
class Job:
    """Everything a worker process needs to run scenarios of one problem (plain, picklable values)."""

    task: Task
    plan: object  # AbstractPlan
    facts: object  # ProblemFacts
    seed: int


_CACHE: dict = {}


def _binding(job: Job):
    """The action library binding, loaded once per worker process."""
    key = (str(job.task.domain), str(job.task.problem))
    if key not in _CACHE:
        _CACHE[key] = load_binding(job.task)
    return _CACHE[key]


def scenario_sequence(job: Job, objects: dict):
    """The instantiated plan of `job` for one random situation (belief values per object)."""
    binding = _binding(job)
    belief = BeliefState(MappingProxyType({k: MappingProxyType(v) for k, v in objects.items()}))
    return instantiate(job.plan, binding, belief, object_types=job.facts.types, initial_state=job.facts.initial)


def _models(job: Job, sequence):
    key = ("models", str(job.task.domain), tuple(sorted({a.action for a in sequence.actions})))
    if key not in _CACHE:
        _CACHE[key] = load_models(job.task, sequence)
    return _CACHE[key]


def _episode_seed(job: Job, index: int) -> int:
    return int(np.random.SeedSequence([job.seed, index]).generate_state(1)[0])


def score_episode(job: Job, index: int, oracle: bool) -> dict:
    """One approachBall -> dribbleBall scenario: greedy, refined (analytic and ga), and optionally the oracle."""
    seed = _episode_seed(job, index)
    rng = np.random.default_rng(seed)
    sequence = scenario_sequence(job, score_belief(rng))
    models = _models(job, sequence)
    greedy = refine(sequence, models, horizon=1, method="analytic", seed=seed)
    refined = refine(sequence, models, horizon=2, method="analytic", seed=seed)
    genetic = refine(sequence, models, horizon=2, method="ga", seed=seed)
    g, r = dispatch(greedy.sequence, seed=seed), dispatch(refined.sequence, seed=seed)
    out = {"index": index, "seed": seed,
           "greedy": g.duration, "refined": r.duration, "greedy_ok": g.succeeded, "refined_ok": r.succeeded,
           "predicted_greedy": greedy.predicted_total, "predicted_refined": refined.predicted_total,
           "analytic_seconds": sum(w.seconds for w in refined.windows),
           "analytic_method": ",".join(w.method for w in refined.windows),
           "ga_seconds": sum(w.seconds for w in genetic.windows),
           "analytic_cost": refined.predicted_total, "ga_cost": genetic.predicted_total}
    if oracle:
        out["oracle"] = _oracle(sequence, seed)
    return out


def _oracle(sequence, seed: int) -> float | None:
    """The best simulated duration over a dense grid of the free parameters (the true optimum the models aim
    at); None if no grid point succeeds."""
    free = sequence.free_parameters()
    axes = []
    for p in free:
        if p.name.startswith("phi"):
            axes.append(np.linspace(p.low, p.high, ORACLE_HEADINGS, endpoint=False))
        else:
            axes.append(np.linspace(p.low, p.high, ORACLE_SPEEDS))
    best = None
    for point in np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(free)):
        result = dispatch(sequence.bind({p.id: float(v) for p, v in zip(free, point)}), seed=seed)
        if result.succeeded and (best is None or result.duration < best):
            best = result.duration
    return best


def waypoint_episode(job: Job, index: int, horizons: tuple[int, ...]) -> dict:
    """One four-way-point navigation, executed with each horizon (same simulator seed for all)."""
    seed = _episode_seed(job, index)
    rng = np.random.default_rng(seed)
    sequence = scenario_sequence(job, waypoints_belief(rng))
    models = _models(job, sequence)
    out = {"index": index, "seed": seed}
    for h in horizons:
        refined = refine(sequence, models, horizon=h, method="analytic", seed=seed)
        result = dispatch(refined.sequence, seed=seed)
        out[f"h{h}"] = result.duration
        out[f"h{h}_ok"] = result.succeeded
        out[f"h{h}_predicted"] = refined.predicted_total
        out[f"h{h}_methods"] = sorted({w.method for w in refined.windows})
    return out


def prepared_job(prepared: Prepared, seed: int) -> Job:
    return Job(task=prepared.task, plan=prepared.plan, facts=prepared.facts, seed=seed)


def _mean(values) -> float | None:
    return float(np.mean(values)) if len(values) else None


def summarize_score(rows: list[dict]) -> dict:
    """Table 5.1 / 5.4 numbers over the scenarios where greedy and refined execution both succeeded."""
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
    return {
        "episodes": len(both),
        "scenarios": len(rows),
        "failed_greedy": sum(not r["greedy_ok"] for r in rows),
        "failed_refined": sum(not r["refined_ok"] for r in rows),
        "greedy_mean": _mean(g),
        "refined_mean": _mean(t),
        "improvement": _mean(gain),
        "p_value": p_value,
        "better": int(better.sum()),
        "equal": int(equal.sum()),
        "worse": int(worse.sum()),
        "improvement_better": _mean(gain[better]),
        "improvement_equal": _mean(gain[equal]),
        "improvement_worse": _mean(gain[worse]),
        "predicted_improvement": _mean([1 - r["predicted_refined"] / r["predicted_greedy"] for r in both]),
        "oracle_episodes": len(oracle_rows),
        "oracle_ratio": (float(np.mean([r["refined"] for r in oracle_rows]) / np.mean([r["oracle"] for r in oracle_rows]))
                         if oracle_rows else None),
        "oracle_ratio_per_episode": _mean([r["refined"] / r["oracle"] for r in oracle_rows]),
        "greedy_oracle_ratio": (float(np.mean([r["greedy"] for r in oracle_rows]) / np.mean([r["oracle"] for r in oracle_rows]))
                                if oracle_rows else None),
        "analytic_ms_median": float(np.median(analytic_ms)) if len(rows) else None,
        "ga_ms_median": float(np.median(ga_ms)) if len(rows) else None,
        "analytic_fallbacks": sum("analytic" not in r["analytic_method"] for r in rows),
        "analytic_ga_agree": float(np.mean(agree)) if rows else None,
    }


def summarize_waypoints(rows: list[dict], horizons: tuple[int, ...]) -> dict:
    """Table 5.3: mean duration per horizon over the episodes where every horizon succeeded."""
    from scipy.stats import ttest_rel

    ok = [r for r in rows if all(r[f"h{h}_ok"] for h in horizons)]
    out = {"episodes": len(ok), "scenarios": len(rows), "horizons": []}
    base = np.array([r[f"h{horizons[0]}"] for r in ok])
    previous = base
    for h in horizons:
        times = np.array([r[f"h{h}"] for r in ok])
        p = float(ttest_rel(previous, times).pvalue) if h != horizons[0] and len(ok) > 1 and np.any(previous != times) else None
        out["horizons"].append({
            "horizon": h, "mean": _mean(times),
            "improvement": _mean(1 - times / base) if len(ok) else None,
            "improvement_over_previous": _mean(1 - times / previous) if len(ok) else None,
            "p_value_vs_previous": p,
            "failed": sum(not r[f"h{h}_ok"] for r in rows),
            "methods": sorted({m for r in rows for m in r[f"h{h}_methods"]}),
        })
        previous = times
    return out
