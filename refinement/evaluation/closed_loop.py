"""Closed loop against open loop (issue 30, Ch. 8.1): the same refined plans, executed one action at a time with
the same noise (and disturbance) seeds, once open loop (the first failure ends the run) and once closed loop
(monitored, re-refined, replanned); and a stream of tasks on which the models learn in operation.

A failed run is charged its time + FAILED_RUN_PENALTY s (`penalized`), so failing fast does not look fast.
"""

from __future__ import annotations

from dataclasses import replace
from statistics import median

import numpy as np
from scipy import stats

from tailor.progress import stage_bar
from tailor.refinement.belief import parse_belief
from tailor.refinement.execution import FAILED_RUN_PENALTY, ClosedLoop, ExecuteOptions, OnlineLearner, summarize
from tailor.refinement.pipeline import BELIEF_ARGUMENT, Options, read_task, prepare
from tailor.refinement.refine import refine
from tailor.refinement.evaluation.experiments import situation_seed
from tailor.refinement.situations import Job, stream_seed
from tailor.sims.episode import Episode

_INPUTS: dict = {}  # per worker process: each problem's inputs, read once


def _inputs(job: Job):
    key = (str(job.task.domain), str(job.task.problem), str(job.task.models_dir))
    if key not in _INPUTS:
        _INPUTS[key] = read_task(job.task, job.task.models_dir)
    return _INPUTS[key]


def closed_loop_episode(job: Job, index: int, objects: dict, disturbance: str | None, horizon: int = 2,
                        replans: int = 2) -> dict:
    """One situation: its plan refined once, then executed open and closed loop with the same simulator seed."""
    seed = situation_seed(job.seed, index)
    base = _inputs(job)
    belief = parse_belief({"objects": objects}, BELIEF_ARGUMENT, None, base.binding.quantities)
    inputs = replace(base, belief=belief)
    options = Options(horizon=horizon, seed=seed, greedy=False)
    prepared = prepare(inputs, options, job.plan, warn=False)
    o = prepared.options
    refined = refine(prepared.sequence, prepared.models, horizon=o.horizon, method=o.optimizer, seed=seed,
                     success_models=prepared.success_models, risk=o.risk, neighbourhood=o.neighbourhood)
    row = {"index": index, "seed": seed, "problem": job.plan.problem}
    for name, closed in (("open_loop", False), ("closed_loop", True)):
        settings = ExecuteOptions(closed_loop=closed, replans=replans, disturbance=disturbance)
        events = list(ClosedLoop(inputs, options, settings, prepared=prepared, refined=refined).events())
        row[name] = summarize(events).to_json()
    return row


def _charged(run: dict) -> float:
    """A run's time (a RunSummary's JSON), a failed run charged FAILED_RUN_PENALTY more."""
    return run["duration"] + (0.0 if run["completed"] else FAILED_RUN_PENALTY)


def _side(rows: list[dict], name: str) -> dict:
    runs = [r[name] for r in rows]
    penalized = [_charged(r) for r in runs]
    done = [r["duration"] for r in runs if r["completed"]]
    return {"runs": len(runs), "failed_runs": sum(1 for r in runs if not r["completed"]),
            "mean_penalized": float(np.mean(penalized)) if penalized else None,
            "mean_completed_time": float(np.mean(done)) if done else None,
            "re_refinements": sum(r["re_refinements"] for r in runs), "replans": sum(r["replans"] for r in runs)}


def summarize_closed_loop(rows: list[dict]) -> dict:
    """The floors' numbers: each side's failed runs and mean penalized time, the share of the runs open loop
    fails that closed loop completes, the median overhead share of closed loop, and the one-sided Wilcoxon
    signed-rank p of closed loop's penalized times being lower (paired by situation)."""
    out = {"open_loop": _side(rows, "open_loop"), "closed_loop": _side(rows, "closed_loop"),
           "penalty": FAILED_RUN_PENALTY}
    failed_open = [r for r in rows if not r["open_loop"]["completed"]]
    out["recovered_share"] = (sum(1 for r in failed_open if r["closed_loop"]["completed"]) / len(failed_open)
                              if failed_open else None)
    shares = [r["closed_loop"]["overhead"] / r["closed_loop"]["duration"] for r in rows
              if r["closed_loop"]["duration"] > 0]
    out["overhead_share"] = float(median(shares)) if shares else None
    out["overhead_share_mean"] = float(np.mean(shares)) if shares else None
    diff = np.array([_charged(r["closed_loop"]) - _charged(r["open_loop"]) for r in rows])
    if np.any(diff != 0):
        out["p_closed_faster"] = float(stats.wilcoxon(diff, alternative="less").pvalue)
    else:
        out["p_closed_faster"] = None
    out["closed_minus_open_mean"] = float(diff.mean()) if len(diff) else None
    return out


# --- learning in operation on a stream of tasks ------------------------------------------------------------
def learning_stream(items: list[tuple[Job, int, dict]], variant: str | None, every: int = 5, horizon: int = 2
                    ) -> tuple[list[dict], OnlineLearner | None]:
    """Execute the tasks in turn, closed loop, the models learning in operation (one OnlineLearner across the
    stream) on the robot `variant`; per task: the models' error on its actions before they ran (prequential),
    the executed time, and the greedy (h = 1) time with the same models on the same seed. Also the learner as
    the stream leaves it (None without tasks)."""
    learner = None
    rows = []
    with stage_bar(len(items), "tasks learning in operation", "task") as bar:
        for job, index, objects in items:
            row, learner = _learning_task(job, index, objects, variant, every, horizon, learner)
            rows.append(row)
            bar.update()
    return rows, learner


def _learning_task(job: Job, index: int, objects: dict, variant: str | None, every: int, horizon: int,
                   learner: OnlineLearner | None) -> tuple[dict, OnlineLearner]:
    """One task of the stream: refined (learning) and greedy (not), with the same simulator seed."""
    seed = situation_seed(job.seed, index)
    base = _inputs(job)
    if learner is None:
        learner = OnlineLearner(base.binding.entry, every)
    inputs = replace(base, belief=parse_belief({"objects": objects}, BELIEF_ARGUMENT, None, base.binding.quantities))
    before = len(learner.errors)
    row = {"index": index, "seed": seed}
    for name, h in (("refined", horizon), ("greedy", 1)):
        options = Options(horizon=h, seed=seed, greedy=False)
        settings = ExecuteOptions(closed_loop=True, variant=variant, learn=name == "refined")
        use = learner if name == "refined" else frozen(learner)
        summary = summarize(list(ClosedLoop(inputs, options, settings, learner=use).events()))
        row[name] = summary.penalized
        row[f"{name}_completed"] = summary.completed
    errors = learner.errors[before:]
    row["abs_errors"] = [abs(p - m) for _, p, m, _ in errors]
    row["relative_errors"] = [abs(p - m) / m for _, p, m, _ in errors if m > 0]
    row["executions"] = [{"action": a, "params": list(x), "duration": m} for a, _, m, x in errors]
    return row, learner


class _Frozen(OnlineLearner):
    """The stream's learner as it stands, not learning from the greedy run (the greedy comparison only)."""

    def record(self, episode, predicted=None) -> None:
        return None


def frozen(learner: OnlineLearner) -> OnlineLearner:
    """`learner` as it stands (its models and classifiers), learning nothing more."""
    still = _Frozen(learner.entry, learner.every)
    still._trained, still._adapted = learner._trained, learner._adapted
    still._trained_guards, still._adapted_guards = learner._trained_guards, learner._adapted_guards
    return still


def reference_models(domain_dir, binding, models: dict, variant: str | None, episodes: int, seed: int, jobs: int = 1
                     ) -> dict:
    """Duration models of `models`' actions trained from scratch on `episodes` episodes per experience scenario of
    the robot `variant` (the training recipe's scenarios, each model's own feature space, the protocol of Fig.
    4.9): what learning in operation is measured against."""
    from tailor.refinement.learning.duration_protocol import train_duration_model
    from tailor.refinement.learning.recipe import load_recipe
    from tailor.sims.parallel import run_in_workers

    recipe = load_recipe(domain_dir)
    entry = binding.entry
    out = {}
    for action, model in models.items():
        scenarios = next((m.scenarios for m in recipe.models if m.action == action), ())
        if not scenarios:
            continue
        items = [(entry.name, name, stream_seed(seed, k, i), variant) for k, name in enumerate(scenarios)
                 for i in range(episodes)]
        gathered = run_in_workers(variant_episode, items, jobs, f"{action} on {variant or 'the modelled robot'}")
        space = model.expressions if model.expressions is not None else model.feature_space
        out[action] = train_duration_model(action, gathered, seed, space, entry.action(action).observed).model
    return out


def variant_episode(simulator: str, scenario: str, seed: int, variant: str | None):
    """One experience episode of a scenario on the robot `variant` (None: the modelled robot)."""
    from tailor.sims import registry

    run = registry.get(simulator).scenarios[scenario].run
    return run(seed, variant=variant) if variant is not None else run(seed)


def reference_improvement(items: list[tuple[Job, int, dict]], variant: str | None, models: dict,
                          horizon: int = 2) -> float | None:
    """Refined vs greedy improvement on `items` executed closed loop on the robot `variant` with `models` (the
    models trained from scratch on it; no learning in operation): what learning in operation is measured against."""
    return frozen_runs(items, variant, fixed_models(models), horizon)[0]


def fixed_models(models: dict) -> OnlineLearner:
    """A learner that holds `models` and learns nothing (what frozen_runs executes with)."""
    fixed = _Frozen(None, 1)
    fixed._adapted = dict(models)
    return fixed


def frozen_runs(items: list[tuple[Job, int, dict]], variant: str | None, learner: OnlineLearner,
                horizon: int = 2) -> tuple[float | None, list[Episode]]:
    """Refined vs greedy improvement on `items` executed closed loop on the robot `variant` with the models (and
    success classifiers) `learner` holds, frozen: nothing executed here is learned from (held-out tasks); and the
    actions both runs executed (as episodes)."""
    fixed = learner if isinstance(learner, _Frozen) else frozen(learner)
    times = {"refined": [], "greedy": []}
    executed = []
    for job, index, objects in items:
        seed = situation_seed(job.seed, index)
        base = _inputs(job)
        inputs = replace(base, belief=parse_belief({"objects": objects}, BELIEF_ARGUMENT, None, base.binding.quantities))
        for name, h in (("refined", horizon), ("greedy", 1)):
            settings = ExecuteOptions(closed_loop=True, variant=variant, learn=True)
            events = list(ClosedLoop(inputs, Options(horizon=h, seed=seed, greedy=False), settings,
                                     learner=fixed).events())
            executed += [e.log for e in events if e.kind == "executed" and e.log is not None]
            times[name].append(summarize(events).penalized)
    if not items:
        return None, executed
    greedy = float(np.mean(times["greedy"]))
    return (greedy - float(np.mean(times["refined"]))) / greedy, executed


def episodes_error(episodes: list[Episode], models: dict) -> float | None:
    """Mean absolute error (s) of `models` on the successful `episodes` of their actions."""
    errors = [abs(float(models[e.action].predict_duration(np.asarray(e.params, dtype=float)[None, :])[0])
                  - e.duration) for e in episodes if e.succeeded and e.action in models]
    return float(np.mean(errors)) if errors else None


def reference_error(rows: list[dict], models: dict) -> float | None:
    """Mean absolute error (s) of `models` on the successful executions of `rows`."""
    errors = []
    for row in rows:
        for e in row.get("executions", ()):
            model = models.get(e["action"])
            if model is not None:
                predicted = float(model.predict_duration(np.array([e["params"]], dtype=float))[0])
                errors.append(abs(predicted - e["duration"]))
    return float(np.mean(errors)) if errors else None


__all__ = ["closed_loop_episode", "summarize_closed_loop", "learning_stream", "reference_models", "reference_error",
           "reference_improvement", "frozen", "frozen_runs", "fixed_models", "episodes_error"]
