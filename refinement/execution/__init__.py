"""Closed-loop execution and learning in operation (Ch. 8.1): `tailor.execute` and `tailor execute`.

    import tailor
    for event in tailor.execute(domain, problem, seed=3, disturbance=name):
        print(event.kind, event.pddl, event.predicted, event.measured, event.outcome, event.reason)

An executor runs one action call at a time: the domain's simulator (`SimulatedRobot`, the default), or a real
robot's adapter implementing `Executor` (see tailor.refinement.execution.executors; `ReplayRobot` replays a
recorded trace). The loop (tailor.refinement.execution.loop) monitors each action against its prediction,
re-refines from the measured state, replans after a failure; `learn` recalibrates the duration models on what
was executed (tailor.refinement.execution.adapt).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from pathlib import Path

from tailor.errors import ArgumentTypeError, ArgumentValueError
from tailor.planner_bridge import DEFAULT_PLANNER
from tailor.refinement import pipeline
from tailor.refinement.api import _belief_table, _objective_arguments, _refine_arguments
from tailor.refinement.execution.adapt import OnlineLearner, recalibrated
from tailor.refinement.execution.executors import (
    Executed,
    Executor,
    Recorder,
    ReplayRobot,
    SimulatedRobot,
    TraceStep,
)
from tailor.refinement.execution.loop import (
    FAILED_RUN_PENALTY,
    ClosedLoop,
    Event,
    ExecuteOptions,
    RunSummary,
    summarize,
)
from tailor.refinement.optimizers import DEFAULT_OPTIMIZER


def execute(domain, problem, belief=None, **options) -> Iterator[Event]:
    """Plan, refine and execute a task one action at a time; an iterator of `Event`s (see loop.Event). The keyword
    arguments are `run`'s; planning, refining and executing start when iteration does."""
    return run(domain, problem, belief, **options).events()


def run(domain, problem, belief=None, *, horizon: int = 2, optimizer: str = DEFAULT_OPTIMIZER, seed: int = 0,
            models: str | Path | None = None, closed_loop: bool = True, replans: int = 2, learn: bool = False,
            learn_every: int = 5, disturbance: str | None = None, variant: str | None = None,
            executor: Executor | None = None, learner: OnlineLearner | None = None, log: str | Path | None = None,
            planner: str = DEFAULT_PLANNER, timeout: float | None = None, objective=None, limits=None
            ) -> ClosedLoop:
    """The run of a task, planned and refined, ready to execute (`.events()`; `execute` is that).

    `domain`, `problem`, `belief`, `horizon`, `optimizer`, `seed`, `models`, `planner`, `timeout`, `objective`,
    `limits`: as for `tailor.refine` (every refinement of the run, re-refinements and replans too, minimizes that
    objective within those limits). `closed_loop` False runs the refined plan open loop (no monitoring, the first failure ends
    it). `replans`: how often to plan again after a failure. `learn`: recalibrate the duration models every
    `learn_every` executed actions (or pass a `learner` kept across calls). `executor`: a robot adapter (default:
    the domain's simulator with `seed`, `disturbance` and `variant`). `log`: a folder where every executed
    action is added to `<action>.csv` (and, with `learn`, the executions there recalibrate the models first).
    The task is read, planned and refined here; nothing is executed until `.events()` is iterated."""
    seed, horizon = _refine_arguments(domain, problem, belief, seed, horizon, models, True, None, None, None,
                                      optimizer, timeout)
    objective, limits = _objective_arguments(objective, limits)
    for name, value in (("closed_loop", closed_loop), ("learn", learn)):
        if not isinstance(value, bool):
            raise ArgumentTypeError(f"{name} must be bool, not {type(value).__name__}")
    for name, value in (("disturbance", disturbance), ("variant", variant)):
        if value is not None and not isinstance(value, str):
            raise ArgumentTypeError(f"{name} must be str or None, not {type(value).__name__}")
    try:
        settings = ExecuteOptions(closed_loop=closed_loop, replans=replans, learn=learn or learner is not None,
                                  learn_every=learn_every, disturbance=disturbance, variant=variant)
    except ValueError as exc:
        raise ArgumentValueError(str(exc)) from None
    if executor is not None and not isinstance(executor, Executor):
        raise ArgumentTypeError(f"executor must implement start, observe, scene and execute (tailor.refinement."
                                f"execution.Executor), not {type(executor).__name__}")
    if log is not None and (isinstance(log, bool) or not isinstance(log, (str, Path))):
        raise ArgumentTypeError(f"log must be a folder (str or Path) or None, not {type(log).__name__}")
    task = pipeline.resolve_task(domain, problem, belief if isinstance(belief, (str, Path)) else None)
    inputs = pipeline.read_task(task, models, _belief_table(belief) if isinstance(belief, Mapping) else None)
    entry = inputs.binding.entry
    wrong = entry.unknown_option(disturbance, variant) if executor is None else None
    if wrong is not None:
        raise ArgumentValueError(wrong)
    for name, weighed, bounds in (("objective", objective, ()), ("limits", None, limits)):
        wrong = pipeline.unknown_measure(inputs.binding, weighed, bounds)  # before planning, as `refine`
        if wrong is not None:
            raise ArgumentValueError(f"{name}: {wrong}")
    options = pipeline.Options(horizon=horizon, optimizer=optimizer, seed=seed, greedy=False, planner=planner,
                               timeout=timeout, objective=objective, limits=limits)
    return ClosedLoop(inputs, options, settings, executor, learner, log=None if log is None else Path(log))


__all__ = ["execute", "run", "ClosedLoop", "Event", "ExecuteOptions", "RunSummary", "summarize", "Executed",
           "Executor", "SimulatedRobot", "ReplayRobot", "Recorder", "TraceStep", "OnlineLearner", "recalibrated",
           "FAILED_RUN_PENALTY"]
