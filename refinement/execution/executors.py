"""Executors: what runs one action call at a time for closed-loop execution, a simulator or a real robot.

A real robot's adapter implements `Executor` (four methods) instead of a simulator:

    class MyRobot:
        outcomes = ("success", "collision", "timeout")     # optional: the outcomes it may report
        def start(self, scene): ...            # the world as the task's belief places it (a simulator resets;
                                               # a robot may check that it agrees, or ignore it)
        def observe(self, action): ...         # the action's observed parameters, as measured now
        def scene(self): ...                   # every scene object's measured values now: {name: (values...)}
        def execute(self, call): ...           # run ActionCall(action, goal) until it ends -> Executed

What an executor reports is checked (`checked`) before anything uses it: an exception, a duration that is not
a finite number >= 0, an outcome it does not declare, a state that is not finite numbers: one ExecutionError
naming the step.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol, runtime_checkable

import numpy as np

from tailor.errors import ExecutionError, SimError, TailorError, shown
from tailor.sims.episode import SUCCESS, ActionCall, Episode
from tailor.sims.protocol import Observable, SimulatorEntry

Scene = Mapping[str, tuple[float, ...]]
OUTCOME = re.compile(r"^[a-z][a-z0-9_]*$")  # an outcome's name: "success", "collision", "timeout", ...
TRACE_FORMAT = "tailor.execution_trace/1"


@dataclass(frozen=True)
class Executed:
    """What the robot reports of one executed action: how long it took, how it ended, its parameters at its
    start (observed then internal, the ActionSpec's order: what the models learn from), the scene measured
    after it, and the full log where the executor keeps one (a simulator's Episode)."""

    duration: float
    outcome: str
    params: tuple[float, ...]
    scene: Mapping[str, tuple[float, ...]]
    episode: Episode | None = field(default=None, compare=False)

    @property
    def succeeded(self) -> bool:
        return self.outcome == SUCCESS


@runtime_checkable
class Executor(Protocol):
    """Runs action calls one at a time and says what it measures between them (see the module's docstring)."""

    def start(self, scene: Scene) -> None: ...

    def observe(self, action: str) -> tuple[float, ...]: ...

    def scene(self) -> Scene: ...

    def execute(self, call: ActionCall) -> Executed: ...


class SimulatedRobot:
    """A registered simulator as an executor: one simulator for the whole run (the state carried over from one
    action to the next), with its seeded noise, and a disturbance or a changed robot (variant) where asked."""

    def __init__(self, entry: SimulatorEntry, seed: int = 0, noise=None, disturbance: str | None = None,
                 variant: str | None = None):
        self.entry = entry
        self.simulator = entry.simulator(seed, noise, disturbance, variant)
        if not isinstance(self.simulator, Observable):
            raise SimError(f"simulator {entry.name!r} cannot run closed loop: it measures nothing between actions "
                           "(it has no observe(action) and scene(); see tailor.sims.protocol.Observable)")

    def start(self, scene: Scene) -> None:
        self.simulator.reset({name: tuple(float(v) for v in values) for name, values in scene.items()})

    def observe(self, action: str) -> tuple[float, ...]:
        return tuple(float(v) for v in self.simulator.observe(action))

    def scene(self) -> Scene:
        return {name: tuple(float(v) for v in values) for name, values in self.simulator.scene().items()}

    def execute(self, call: ActionCall) -> Executed:
        episode = self.simulator.run(call)
        return Executed(float(episode.duration), episode.outcome, tuple(float(v) for v in episode.params),
                        self.scene(), episode)


@dataclass(frozen=True)
class TraceStep:
    """One recorded action: what was observed before it, the call, and what the robot reported."""

    observed: tuple[float, ...]
    scene_before: Mapping[str, tuple[float, ...]]
    call: ActionCall
    executed: Executed


class ReplayRobot:
    """An executor that is no simulator: it replays a recorded trace (e.g. a real robot's log of a run), step by
    step, and refuses a call the trace did not record (the closed loop must not ask for what never happened)."""

    outcomes: tuple[str, ...] = ()

    def __init__(self, steps: Sequence[TraceStep], start_scene: Scene | None = None, tolerance: float = 1e-6):
        self.steps = list(steps)
        self.start_scene = start_scene
        self.tolerance = tolerance
        self.position = 0
        self.outcomes = tuple(sorted({s.executed.outcome for s in self.steps} | {SUCCESS}))

    def start(self, scene: Scene) -> None:
        self.position = 0

    def _next(self) -> TraceStep:
        if self.position >= len(self.steps):
            raise ExecutionError(f"the trace has no step {self.position + 1}: it recorded {len(self.steps)}")
        return self.steps[self.position]

    def observe(self, action: str) -> tuple[float, ...]:
        step = self._next()
        if step.call.action != action:
            raise ExecutionError(f"the trace's step {self.position + 1} is {step.call.action}, not {action}")
        return step.observed

    def scene(self) -> Scene:
        return self._next().scene_before if self.position < len(self.steps) else self.steps[-1].executed.scene

    def execute(self, call: ActionCall) -> Executed:
        step = self._next()
        if call.action != step.call.action or len(call.goal) != len(step.call.goal) or any(
                abs(a - b) > self.tolerance * max(1.0, abs(b)) for a, b in zip(call.goal, step.call.goal)):
            raise ExecutionError(f"the trace's step {self.position + 1} recorded {step.call}, not {call}")
        self.position += 1
        return step.executed

    # --- a trace as a file -------------------------------------------------------------------------------
    def to_json(self) -> dict:
        return {"format": TRACE_FORMAT, "steps": [
            {"observed": list(s.observed), "scene_before": {k: list(v) for k, v in s.scene_before.items()},
             "action": s.call.action, "goal": list(s.call.goal), "duration": s.executed.duration,
             "outcome": s.executed.outcome, "params": list(s.executed.params),
             "scene": {k: list(v) for k, v in s.executed.scene.items()}} for s in self.steps]}

    @classmethod
    def from_json(cls, data: Mapping, file: str = "<trace>") -> "ReplayRobot":
        if not isinstance(data, Mapping) or data.get("format") != TRACE_FORMAT:
            raise ExecutionError(f"not an execution trace (format {TRACE_FORMAT!r} expected)", file=file)
        try:
            steps = [TraceStep(tuple(float(v) for v in s["observed"]),
                               {k: tuple(float(v) for v in vs) for k, vs in s["scene_before"].items()},
                               ActionCall(str(s["action"]), tuple(float(v) for v in s["goal"])),
                               Executed(float(s["duration"]), str(s["outcome"]), tuple(float(v) for v in s["params"]),
                                        {k: tuple(float(v) for v in vs) for k, vs in s["scene"].items()}))
                     for s in data["steps"]]
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise ExecutionError(f"malformed execution trace: {exc!r}", file=file) from None
        return cls(steps)

    @classmethod
    def read(cls, path: str | Path) -> "ReplayRobot":
        try:
            data = json.loads(Path(path).read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise ExecutionError(f"cannot read the execution trace: {exc}", file=str(path)) from None
        return cls.from_json(data, str(path))


class Recorder:
    """Wraps an executor and records what it measures: the trace a ReplayRobot plays back."""

    def __init__(self, executor: Executor):
        self.executor = executor
        self.steps: list[TraceStep] = []
        self._observed: tuple[float, ...] = ()

    def start(self, scene: Scene) -> None:
        self.executor.start(scene)

    def observe(self, action: str) -> tuple[float, ...]:
        self._observed = self.executor.observe(action)
        return self._observed

    def scene(self) -> Scene:
        return self.executor.scene()

    def execute(self, call: ActionCall) -> Executed:
        before = self.executor.scene()
        observed = self._observed or self.executor.observe(call.action)
        executed = self.executor.execute(call)
        self.steps.append(TraceStep(observed, before, call, replace_episode(executed)))
        self._observed = ()
        return executed

    def replay(self) -> ReplayRobot:
        return ReplayRobot(self.steps)


def replace_episode(executed: Executed) -> Executed:
    """The report without its log (a trace keeps what a robot reports, not the simulator's log)."""
    return Executed(executed.duration, executed.outcome, executed.params, executed.scene)


# --- checks of what an executor reports ------------------------------------------------------------------
def call_executor(what: str, where: str, function, *args):
    """Call an executor's method; anything it raises becomes one ExecutionError naming the step."""
    try:
        return function(*args)
    except TailorError as exc:
        if isinstance(exc, ExecutionError):
            raise ExecutionError(f"{where}: {exc.message}", file=exc.file) from None
        raise ExecutionError(f"{where}: the executor's {what} failed: {exc}") from None
    except Exception as exc:  # an adapter's own bug or its robot's failure: one line, never a traceback
        raise ExecutionError(f"{where}: the executor's {what} raised {type(exc).__name__}: {exc}") from None


def checked_values(values, count: int | None, what: str, where: str) -> tuple[float, ...]:
    """`values` as a tuple of finite floats (`count` of them where given), or an ExecutionError."""
    try:
        out = tuple(float(v) for v in values)
    except (TypeError, ValueError):
        raise ExecutionError(f"{where}: the executor reported {what} {shown(values)}, not a list of numbers") from None
    if count is not None and len(out) != count:
        raise ExecutionError(f"{where}: the executor reported {len(out)} values of {what}, expected {count}")
    bad = [v for v in out if not math.isfinite(v)]
    if bad:
        raise ExecutionError(f"{where}: the executor reported {what} with a value that is not finite ({bad[0]})")
    return out


def checked_scene(scene, where: str) -> dict[str, tuple[float, ...]]:
    if not isinstance(scene, Mapping):
        raise ExecutionError(f"{where}: the executor's scene is {shown(scene)}, not a mapping of object -> values")
    return {str(name): checked_values(values, None, f"scene object {name!r}", where) for name, values in scene.items()}


def checked(executed, executor, n_params: int, where: str) -> Executed:
    """An executor's report, checked: a finite duration >= 0, a known outcome, finite parameters and scene."""
    if not isinstance(executed, Executed):
        raise ExecutionError(f"{where}: the executor returned {type(executed).__name__}, not an Executed")
    duration = executed.duration
    if isinstance(duration, bool) or not isinstance(duration, (int, float, np.floating)) \
            or not math.isfinite(duration) or duration < 0:
        raise ExecutionError(f"{where}: the executor reported a duration of {shown(duration)} (a finite number of "
                             "seconds >= 0 expected)")
    outcome = executed.outcome
    declared = tuple(getattr(executor, "outcomes", ()) or ())
    if not isinstance(outcome, str) or not OUTCOME.match(outcome) or (declared and outcome not in declared):
        known = f" (it declares {', '.join(declared)})" if declared else " (a lower-case name: success or a failure)"
        raise ExecutionError(f"{where}: the executor reported an unknown outcome {shown(outcome)}{known}")
    params = checked_values(executed.params, n_params, "parameters", where)
    return Executed(float(duration), outcome, params, checked_scene(executed.scene, where), executed.episode)


def as_episode(action: str, executed: Executed, seed: int, entry: SimulatorEntry) -> Episode:
    """An executed action as experience, what the models learn from: the executor's own log where it keeps one,
    else an Episode of one logged row, its start (the observed parameters)."""
    if executed.episode is not None:
        return executed.episode
    params = np.asarray(executed.params, dtype=float)
    observed = entry.action(action).observed
    return Episode(action, params, np.zeros(1), params[None, :len(observed)], tuple(observed), executed.outcome,
                   executed.duration, seed)
