"""Closed-loop execution (Ch. 8.1): execute a refined plan one action at a time, monitor each against its
prediction, re-refine from the measured state, replan after a failure, and learn from what was executed.

    for event in ClosedLoop(inputs, options, ExecuteOptions()).events():   # inputs: pipeline.read_task
        print(event.kind, event.pddl, event.predicted, event.measured, event.outcome, event.reason)

Before each action (after the first), the executor's measurements are compared with what the plan assumed:
- the window's predicted time from the measured state (the action's observed parameters as measured) against
  the time predicted from the state planned, both with the plan's choices (the models compare the two, so a
  state written in another form, a spot as a frame with offsets or as a pose, compares right);
- every scene object a fact still needed places (an object to fetch) against the belief;
- the success classifiers of the window's guarded actions at the measured state.
A change of the predicted time beyond `time_tolerance`, an object moved beyond `object_tolerance` (a share of
its quantity's range) or a guard predicting failure re-refines the window from the measured state (receding
horizon: the observed parameters bound to the measurement, the moved objects' values replaced) and, where that
changes a choice of the action (beyond `object_tolerance` of its range) or moves an object a later action
reads, marks the next window stale, so it is re-refined in its turn. A guard no choice satisfies, or a failed action, replans:
the facts that hold are those after the plan steps completed (the failed step's effects not applied; a fact
whose predicate the binding marks `lost_on_failure` that the failed step needed is false, and what its producer
deleted holds again), the belief takes the measured scene objects and the subgoals executed so far, and the
planner plans again from them.
Open loop (`closed_loop=False`) runs the same refined plan without monitoring and stops at the first failure.
Every refinement of a run (the first, each re-refined window, each replan's) minimizes the run's objective
within its limits (`Options.objective`, `Options.limits`; Ch. 8.1), as `tailor refine` does.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType

import numpy as np

from tailor.errors import EmptyRangeError, NoPlanError, PlannerError
from tailor.planner_bridge import GOAL, INITIAL, AbstractPlan
from tailor.planner_bridge.replan import StepEffects, with_initial
from tailor.refinement.action_sequence import ActionSequence, Parameter
from tailor.refinement.belief import BeliefState
from tailor.refinement.binding import Binding
from tailor.refinement.dispatch import check_scene
from tailor.refinement.execution.adapt import OnlineLearner
from tailor.refinement.execution.experience import check_log, read_executions, write_executions
from tailor.refinement.execution.executors import (
    Executor,
    SimulatedRobot,
    as_episode,
    call_executor,
    checked,
    checked_scene,
    checked_values,
)
from tailor.refinement.instantiate import scene_name, type_chain
from tailor.refinement.api import _plan_files
from tailor.refinement.pipeline import BELIEF_ARGUMENT, Inputs, Options, prepare
from tailor.refinement.refine import guard_for, model_for, optimize_window, refine
from tailor.sims.episode import FAILED_RUN_PENALTY, SUCCESS, ActionCall, Episode

# share of its quantity's range a scene object (an object to fetch) may lie from where the plan assumed it before
# the window is refined again with it where it is: 0.5% (4 cm on an 8 m field, 6 cm in a 12 m room) is a few
# times the bundled sensors' noise and far less than an object someone moved
OBJECT_TOLERANCE = 0.005
TIME_TOLERANCE = 0.02  # share of a window's predicted time a deviation must change it by to re-refine it
ABSOLUTE_TOLERANCE = 1e-3  # for quantities whose range is a single value


@dataclass(frozen=True)
class ExecuteOptions:
    """How to execute: closed loop (monitor, re-refine, replan up to `replans` times) or open loop; learning in
    operation (`learn`: the duration models recalibrated on executed actions every `learn_every` of them); the
    simulator's `disturbance` and `variant` where the executor is the domain's simulator."""

    closed_loop: bool = True
    replans: int = 2
    learn: bool = False
    learn_every: int = 5
    object_tolerance: float = OBJECT_TOLERANCE
    time_tolerance: float = TIME_TOLERANCE
    disturbance: str | None = None
    variant: str | None = None

    def __post_init__(self) -> None:
        if isinstance(self.replans, bool) or not isinstance(self.replans, int) or self.replans < 0:
            raise ValueError(f"replans must be an integer >= 0, not {self.replans!r}")
        if isinstance(self.learn_every, bool) or not isinstance(self.learn_every, int) or self.learn_every < 1:
            raise ValueError(f"learn_every must be an integer >= 1, not {self.learn_every!r}")
        for name in ("object_tolerance", "time_tolerance"):
            value = getattr(self, name)
            if isinstance(value, bool) or not (isinstance(value, (int, float)) and 0.0 <= value < 1.0):
                raise ValueError(f"{name} must be a share in [0, 1), not {value!r}")


@dataclass(frozen=True)
class Event:
    """One thing the executor did. `kind`: "executed" (an action ran: its call, predicted and measured
    duration, outcome and the scene after), "re-refined" (a window optimized again from the measured state),
    "replanned" (a new plan from the facts that held), "finished" (the run's end: `outcome` "success" or why
    not). `overhead` is the monitoring, re-refinement and replanning time (s, wall clock) it took."""

    kind: str
    step: int | None = None
    pddl: str = ""
    action: str = ""
    goal: tuple[float, ...] = ()
    predicted: float | None = None
    measured: float | None = None
    outcome: str = ""
    scene: Mapping[str, tuple[float, ...]] = field(default_factory=dict)
    reason: str = ""
    overhead: float = 0.0
    plan: tuple[str, ...] = ()  # "replanned": the new plan's steps
    log: Episode | None = field(default=None, compare=False, repr=False)  # "executed": the executor's record
    simulator: str = ""  # "executed": the simulator whose actions the domain binds (its views draw the run)

    def to_json(self) -> dict:
        data = {"kind": self.kind}
        for key in ("step", "pddl", "action", "predicted", "measured", "outcome", "reason"):
            value = getattr(self, key)
            if value not in (None, ""):
                data[key] = value
        if self.goal:
            data["goal"] = list(self.goal)
        if self.scene:
            data["scene"] = {k: list(v) for k, v in self.scene.items()}
        if self.plan:
            data["plan"] = list(self.plan)
        data["overhead"] = self.overhead
        return data


@dataclass(frozen=True)
class RunSummary:
    """A whole run: completed or not, the measured execution time, the overhead, counts of what happened."""

    completed: bool
    duration: float
    overhead: float
    actions: int
    failures: int
    re_refinements: int
    replans: int
    reason: str = ""

    @property
    def penalized(self) -> float:
        """The run's time, a failed run charged FAILED_RUN_PENALTY more (the evaluations' comparison)."""
        return self.duration + (0.0 if self.completed else FAILED_RUN_PENALTY)

    def to_json(self) -> dict:
        return {"completed": self.completed, "duration": self.duration, "overhead": self.overhead,
                "actions": self.actions, "failures": self.failures, "re_refinements": self.re_refinements,
                "replans": self.replans, "reason": self.reason}


def summarize(events: list[Event]) -> RunSummary:
    executed = [e for e in events if e.kind == "executed"]
    end = next((e for e in reversed(events) if e.kind == "finished"), None)
    return RunSummary(end is not None and end.outcome == SUCCESS, float(sum(e.measured or 0.0 for e in executed)),
                      float(sum(e.overhead for e in events)), len(executed),
                      sum(1 for e in executed if e.outcome != SUCCESS), sum(1 for e in events if e.kind == "re-refined"),
                      sum(1 for e in events if e.kind == "replanned"), "" if end is None else end.reason)


class ClosedLoop:
    """One run of a task (see the module's docstring); `events()` runs it."""

    def __init__(self, inputs: Inputs, options: Options, execute: ExecuteOptions, executor: Executor | None = None,
                 learner: OnlineLearner | None = None, prepared=None, refined=None, log: Path | None = None):
        self.inputs, self.options, self.settings = inputs, options, execute
        self.binding: Binding = inputs.binding
        self.entry = self.binding.entry
        if prepared is None:
            first = _plan(inputs.pddl, options.planner, options.timeout) if inputs.pddl is not None else None
            prepared = prepare(inputs, replace(options, simulate=False), first)
        self.prepared = prepared
        self.models = dict(self.prepared.models)
        self.success_models = dict(self.prepared.success_models)
        self.resolved = self.prepared.options
        if executor is None:
            executor = SimulatedRobot(self.entry, options.seed, None, execute.disturbance, execute.variant)
        self.executor = executor
        self.learner = learner if learner is not None else (OnlineLearner(self.entry, execute.learn_every)
                                                            if execute.learn else None)
        self.log = None if log is None else Path(log)
        self.executed: dict[str, list[Episode]] = {}  # this run's executed actions, per action
        if self.log is not None:
            check_log(self.log)
            if self.learner is not None:
                self.learner.extend(read_executions(self.log, self.entry, tuple(self.entry.actions)))
        if self.learner is not None:
            self._take_learned()
        self.initial_refined = refined
        self._effects: StepEffects | None = None
        self.values = {obj: dict(q) for obj, q in self.inputs.belief.objects.items()}  # the belief, as it goes
        self.replans_left = execute.replans
        self._stop_reason = ""

    def _take_learned(self) -> None:
        """The duration models and success classifiers as the learner holds them now."""
        self.models = self.learner.adapted(self.models)
        self.success_models = self.learner.adapted_success(self.success_models)

    def model_files(self) -> list[Path]:
        """The model files the run read (duration models and success classifiers), for provenance."""
        models = [*self.prepared.models.values(), *self.prepared.success_models.values()]
        return sorted({Path(m.source) for m in models if getattr(m, "source", None)})

    # --- the run --------------------------------------------------------------------------------------------
    def events(self) -> Iterator[Event]:
        """The run, event by event; every executed action is kept in the log (where one is named) however the
        run ends: completed, stopped, an executor's error, or the caller stopping early."""
        try:
            yield from self._events()
        finally:
            if self.log is not None and self.executed:
                write_executions(self.log, self.executed, self.entry,
                                 run=f"execute.{self.prepared.plan.problem}.seed{self.options.seed}")

    def _events(self) -> Iterator[Event]:
        plan, sequence = self.prepared.plan, self.prepared.sequence
        if not sequence.actions:
            yield Event("finished", outcome=SUCCESS, reason="the goal holds initially: nothing to execute")
            return
        if isinstance(self.executor, SimulatedRobot):
            check_scene(sequence, self.binding.file)
        refined = self.initial_refined or self._refine(sequence)
        choices = self._choices(refined.sequence)
        call_executor("start", "start", self.executor.start, dict(sequence.scene))
        initial_facts = frozenset(tuple(f) for f in plan.initial)
        done_steps: list = []  # plan steps completed (every action serving them executed)
        stale = False
        i = 0
        while i < len(sequence.actions):
            action = sequence.actions[i]
            where = f"step {action.step} {action.pddl} ({action.action})"
            overhead = 0.0
            if self.settings.closed_loop and i > 0:
                started = time.perf_counter()
                verdict = self._monitor(plan, sequence, choices, i, done_steps, where, stale)
                overhead = time.perf_counter() - started
                if verdict.replan:
                    replanned = self._replan(plan, initial_facts, done_steps, sequence, choices, i, verdict.reason,
                                             failed=False)
                    overhead = time.perf_counter() - started
                    if replanned is None:
                        yield Event("finished", outcome="not_completed", overhead=overhead,
                                    reason=self._why_stopped(verdict.reason))
                        return
                    plan, sequence, choices, initial_facts = replanned
                    done_steps, stale, i = [], False, 0
                    yield Event("replanned", reason=verdict.reason, overhead=overhead,
                                plan=tuple(f"({s.action} {' '.join(s.args)})" for s in plan.steps))
                    continue
                sequence, choices = verdict.sequence, verdict.choices
                if verdict.re_refined:
                    stale = verdict.changed
                    yield Event("re-refined", step=action.step, pddl=action.pddl, action=action.action,
                                reason=verdict.reason, overhead=overhead)
                    overhead = 0.0
                action = sequence.actions[i]
            n_observed = len(self.entry.action(action.action).observed)
            values = action.values(choices)
            call = ActionCall(action.action, tuple(float(v) for v in values[n_observed:]))
            model = model_for(action, self.models)
            predicted = float(model.predict_duration(values[None, :])[0])
            executed = checked(call_executor("execute", where, self.executor.execute, call), self.executor,
                               len(action.params), where)
            episode = as_episode(action.action, executed, self.options.seed, self.entry)
            self.executed.setdefault(action.action, []).append(episode)
            if self.learner is not None:
                self.learner.record(episode, predicted)
                self._take_learned()
            self._remember(action, choices)
            yield Event("executed", step=action.step, pddl=action.pddl, action=action.action, goal=call.goal,
                        predicted=predicted, measured=executed.duration, outcome=executed.outcome,
                        scene=MappingProxyType(dict(executed.scene)), overhead=overhead, log=episode,
                        simulator=self.entry.name)
            if not executed.succeeded:
                reason = f"{where} ended with {executed.outcome}"
                if not self.settings.closed_loop:
                    yield Event("finished", outcome="not_completed", reason=reason + " (open loop)")
                    return
                started = time.perf_counter()
                replanned = self._replan(plan, initial_facts, done_steps, sequence, choices, i, reason, failed=True)
                overhead = time.perf_counter() - started
                if replanned is None:
                    yield Event("finished", outcome="not_completed", overhead=overhead, reason=self._why_stopped(reason))
                    return
                plan, sequence, choices, initial_facts = replanned
                done_steps, stale, i = [], False, 0
                yield Event("replanned", reason=reason, overhead=overhead,
                            plan=tuple(f"({s.action} {' '.join(s.args)})" for s in plan.steps))
                continue
            if i + 1 == len(sequence.actions) or sequence.actions[i + 1].step != action.step:
                done_steps.append(plan.step(action.step))
            i += 1
        yield Event("finished", outcome=SUCCESS, reason="every action succeeded")

    def _why_stopped(self, reason: str) -> str:
        if self._stop_reason:
            return f"{reason}; {self._stop_reason}"
        if self.settings.replans == 0:
            return f"{reason}; no replans allowed (--replans 0)"
        return f"{reason}; the {self.settings.replans} replan(s) allowed are used up" if self.replans_left <= 0 \
            else reason

    # --- refinement -----------------------------------------------------------------------------------------
    def _refine(self, sequence: ActionSequence):
        o = self.resolved
        return refine(sequence, self.models, horizon=o.horizon, method=o.optimizer, seed=o.seed,
                      success_models=self.success_models, risk=o.risk, neighbourhood=o.neighbourhood,
                      objective=o.objective, limits=o.limits)

    @staticmethod
    def _choices(bound: ActionSequence) -> dict[str, float]:
        """Every parameter id's value in a bound sequence (the refined plan's choices)."""
        return {p.id: float(p.value) for a in bound.actions for p in a.params if p.value is not None}

    def _remember(self, action, choices: Mapping[str, float]) -> None:
        """Keep the executed action's subgoal (its internal parameters, object.quantity ids) in the belief, for a
        replan's instantiation. Its observed ones are the previous subgoal or the belief already (or, measured,
        the robot's state in the simulator's own form, which need not be the plan's)."""
        n_observed = len(self.entry.action(action.action).observed)
        for p in action.params[n_observed:]:
            value = p.value if p.value is not None else choices.get(p.id)
            obj, _, quantity = p.id.rpartition(".")
            if obj and value is not None:
                self.values.setdefault(obj.lower(), {})[quantity] = float(value)

    # --- monitoring -----------------------------------------------------------------------------------------
    def _monitor(self, plan: AbstractPlan, sequence: ActionSequence, choices: dict[str, float], i: int,
                 done_steps: list, where: str, stale: bool) -> "_Verdict":
        action = sequence.actions[i]
        spec = self.entry.action(action.action)
        n_observed = len(spec.observed)
        measured = checked_values(call_executor("observe", where, self.executor.observe, action.action),
                                  n_observed, "observed parameters", where)
        scene = checked_scene(call_executor("scene", where, self.executor.scene), where)
        moved = self._moved_objects(plan, sequence, scene, done_steps)
        substituted = self._substituted(sequence, i, measured, moved)
        # compared as the models see them (the same state may be written in several ways: a spot as its table's
        # frame and offsets, or as the base's pose with zero offsets): the window's predicted time with
        # the plan's choices, from the state planned and from the state measured, and the guards' verdicts
        reasons = [f"{name} moved" for name in moved]
        before = self._window_time(sequence, choices, i)
        after = self._window_time(substituted, choices, i)
        if abs(after - before) > self.settings.time_tolerance * max(before, 1e-9):
            reasons.append(f"the window's predicted time {after:.2f} s from the measured state, {before:.2f} s "
                           "planned")
        failing = self._failing_guards(substituted, choices, i)
        reasons += [f"{pddl} no longer predicted to succeed" for pddl in failing]
        if not reasons and not stale:
            return _Verdict(sequence=substituted, choices=choices)
        sequence = substituted
        choices = dict(choices)
        # the next window is re-refined in its turn where this one changes what it reads: a choice of action i
        # (beyond object_tolerance) or a moved object a later action reads
        later = {p.id.rpartition(".")[0].lower() for a in sequence.actions[i + 1:] for p in a.params}
        changed = any(obj.lower() in later for obj, _, _ in moved.values())
        assignment = {pid: v for pid, v in choices.items() if pid in self._fixed_ids(sequence, i)}
        o = self.resolved
        window = optimize_window(sequence.actions, i, o.horizon, assignment, self.models, o.optimizer, o.seed,
                                 self.success_models, o.risk, neighbourhood=o.neighbourhood, objective=o.objective,
                                 limits=o.limits)
        if window is None and failing:
            return _Verdict(replan=True, reason=f"{where}: {failing[0]} is predicted to fail from the measured "
                                                "state and it has nothing left to choose")
        if window is not None:
            objective, result = window
            if failing and not math.isfinite(result.cost):
                return _Verdict(replan=True, reason=f"{where}: no choice lets {failing[0]} succeed from the "
                                                    "measured state")
            chosen = dict(zip((p.id for p in objective.free), result.values))
            for p in sequence.actions[i].params:
                if p.id in chosen:
                    before = choices.get(p.id)
                    choices[p.id] = float(chosen[p.id])
                    changed = changed or before is None or self._differs(
                        choices[p.id], before, p.high - p.low, self.entry.quantity(p.id).angle,
                        self.settings.object_tolerance)
        reason = ", ".join(reasons) if reasons else "the window after a re-refined one"
        return _Verdict(sequence=sequence, choices=choices, re_refined=window is not None or bool(moved), reason=reason,
                        changed=changed)

    def _failing_guards(self, sequence: ActionSequence, choices: Mapping[str, float], i: int) -> list[str]:
        """The guarded actions of the window from action i whose success classifier predicts failure at the
        current choices (Alg. 6's validity, from the measured state)."""
        out = []
        for action in sequence.actions[i:i + self.resolved.horizon]:
            guard = guard_for(action, self.success_models)
            if guard is not None:
                values = action.values(choices)
                if not bool(np.asarray(guard.predict_success(values[None, :]))[0]):
                    out.append(action.pddl)
        return out

    def _window_time(self, sequence: ActionSequence, choices: Mapping[str, float], i: int) -> float:
        """The predicted time of the window from action i with the current choices."""
        total = 0.0
        for action in sequence.actions[i:i + self.resolved.horizon]:
            values = action.values(choices)
            total += float(model_for(action, self.models).predict_duration(values[None, :])[0])
        return total

    def _differs(self, now: float, then: float, width: float, angle: bool, share: float) -> bool:
        diff = now - then
        if angle:
            diff = math.remainder(diff, 2 * math.pi)
        tolerance = share * width if math.isfinite(width) and width > 0 else ABSOLUTE_TOLERANCE
        return abs(diff) > max(tolerance, ABSOLUTE_TOLERANCE)

    @staticmethod
    def _fixed_ids(sequence: ActionSequence, i: int) -> set[str]:
        """Parameter ids the actions before i use: already executed, not to be chosen again."""
        return {p.id for a in sequence.actions[:i] for p in a.params}

    def _actors(self) -> set[str]:
        """Scene-placing predicates whose values are the robot's own (their read quantities cover an action's
        observed ones): measured through `observe`, never taken from the scene into the belief."""
        observed = [set(spec.observed_quantities) for spec in self.entry.actions.values()]
        return {name for name, p in self.binding.predicates.items()
                if p.scene is not None and any(o and o <= set(p.read) for o in observed)}

    def _scene_facts(self, facts) -> list[tuple[str, str, tuple[str, ...]]]:
        """(scene object, PDDL object, read quantities) of each fact among `facts` that places a scene object
        other than the robot itself."""
        actors = self._actors()
        out = []
        for fact in facts:
            predicate = self.binding.predicate(fact[0])
            if predicate is None or predicate.scene is None or predicate.name in actors:
                continue
            objects = predicate.objects(fact, self.binding.file)
            if len(objects) == 1:
                out.append((scene_name(predicate.scene, objects[0]), objects[0], predicate.read))
        return out

    def _moved_objects(self, plan: AbstractPlan, sequence: ActionSequence, scene: Mapping, done_steps: list
                       ) -> dict[str, tuple[str, tuple[str, ...], tuple[float, ...]]]:
        """Scene objects that facts still needed place (initial facts linked to a step not yet done, or the
        goal), measured elsewhere than the plan assumed: name -> (PDDL object, quantities, measured values)."""
        done = {s.id for s in done_steps}
        needed = {tuple(link.fact) for link in plan.links
                  if link.producer == INITIAL and (link.consumer == GOAL or link.consumer not in done)}
        moved = {}
        for name, obj, quantities in self._scene_facts(needed):
            if name not in scene or len(scene[name]) != len(quantities):
                continue
            types = type_chain(obj, self.binding, plan.object_types if plan.objects else None)
            for quantity, now in zip(quantities, scene[name]):
                then = self.values.get(obj.lower(), {}).get(quantity)
                if then is None:
                    continue
                default = self.binding.type_range(types, quantity)
                width = default[0][1] - default[0][0] if default else 0.0
                if self._differs(now, then, width, self.entry.quantity(quantity).angle,
                                 self.settings.object_tolerance):
                    moved[name] = (obj, quantities, tuple(scene[name]))
                    break
        return moved

    def _substituted(self, sequence: ActionSequence, i: int, measured: tuple[float, ...],
                     moved: Mapping[str, tuple[str, tuple[str, ...], tuple[float, ...]]]) -> ActionSequence:
        """The sequence with action i's observed parameters bound to the measurement and the moved objects'
        bound values replaced (from action i on); the belief takes the moved objects' values."""
        replaced: dict[str, float] = {}
        for obj, quantities, values in moved.values():
            for quantity, value in zip(quantities, values):
                replaced[f"{obj}.{quantity}".lower()] = value
                self.values.setdefault(obj.lower(), {})[quantity] = value
        n_observed = len(self.entry.action(sequence.actions[i].action).observed)
        actions = list(sequence.actions)
        for k in range(i, len(actions)):
            params = []
            for j, p in enumerate(actions[k].params):
                if k == i and j < n_observed:
                    value = measured[j]
                    params.append(Parameter(p.id, p.name, value, value, value))
                elif not p.free and p.id.lower() in replaced:
                    value = replaced[p.id.lower()]
                    params.append(Parameter(p.id, p.name, value, min(p.low, value), max(p.high, value)))
                else:
                    params.append(p)
            actions[k] = replace(actions[k], params=tuple(params))
        return replace(sequence, actions=tuple(actions))

    # --- replanning -----------------------------------------------------------------------------------------
    def _replan(self, plan: AbstractPlan, initial_facts, done_steps: list, sequence: ActionSequence,
                choices: dict[str, float], i: int, reason: str, failed: bool):
        """Plan again from the facts that hold now (see the module's docstring); None where no replan is left,
        the planner finds no plan or the new plan cannot be instantiated from the measured state."""
        if self.replans_left <= 0 or self.inputs.pddl is None:
            return None
        self.replans_left -= 1
        if self._effects is None:
            self._effects = _effects_of(self.inputs.pddl)
        facts = set(self._effects.after(initial_facts, done_steps))
        step = sequence.actions[i].step
        for link in plan.links_to(step):
            predicate = self.binding.predicate(link.fact[0])
            if predicate is not None and predicate.lost_on_failure and link.producer != INITIAL \
                    and tuple(link.fact) in facts:
                facts.discard(tuple(link.fact))
                facts |= set(self._effects.of(plan.step(link.producer))[1])
        scene = checked_scene(call_executor("scene", f"replanning after {reason}", self.executor.scene), "replanning")
        for name, obj, quantities in self._scene_facts(facts):
            if name in scene and len(scene[name]) == len(quantities):
                self.values.setdefault(obj.lower(), {}).update(zip(quantities, scene[name]))
        task = with_initial(self.inputs.pddl, facts)
        o = self.resolved
        try:
            new_plan = _plan(task, o.planner, o.timeout)
            belief = BeliefState(MappingProxyType({k: MappingProxyType(dict(v)) for k, v in self.values.items()}),
                                 BELIEF_ARGUMENT)
            inputs = replace(self.inputs, pddl=task, belief=belief)
            prepared = prepare(inputs, replace(self.options, simulate=False), new_plan, warn=False)
        except (NoPlanError, EmptyRangeError) as exc:
            self.replans_left = 0
            self._stop_reason = f"no plan from the facts that hold now: {exc}"
            return None
        except PlannerError:
            raise
        models = dict(prepared.models)
        models.update({k: v for k, v in self.models.items() if k in models})
        self.models = models
        self.success_models.update(prepared.success_models)
        if self.learner is not None:
            self.success_models = self.learner.adapted_success(self.success_models)
        new_sequence = prepared.sequence
        if not new_sequence.actions:
            return new_plan, new_sequence, {}, frozenset(facts)
        # the first action starts where the robot is: its observed parameters measured
        where = f"replanning after {reason}"
        first = new_sequence.actions[0]
        measured = checked_values(call_executor("observe", where, self.executor.observe, first.action),
                                  len(self.entry.action(first.action).observed), "observed parameters", where)
        new_sequence = self._substituted(new_sequence, 0, measured, {})
        refined = self._refine(new_sequence)
        return new_plan, new_sequence, self._choices(refined.sequence), frozenset(facts)


_EFFECTS: dict = {}  # the domain's effects per task read (parsing it with unified-planning costs a replan most)


def _effects_of(task) -> StepEffects:
    key = (task.domain_text, task.problem_text)
    if key not in _EFFECTS:
        if len(_EFFECTS) > 32:
            _EFFECTS.clear()
        _EFFECTS[key] = StepEffects(task)
    return _EFFECTS[key]


_PLANS: dict = {}  # plans of the tasks posed so far (the planner is deterministic: the same task, the same plan)


def _plan(task, planner: str, timeout: float | None) -> AbstractPlan:
    """Plan in the session's planner process (started once: a replan costs the search, not a start-up); a task
    posed before (a replan from the facts that held at the start) takes the plan found then."""
    key = (task.domain_text, task.problem_text, planner)
    if key not in _PLANS:
        if len(_PLANS) > 256:
            _PLANS.clear()
        _PLANS[key] = _plan_files(task.domain, task.problem, planner, timeout, task)
    return _PLANS[key]


@dataclass(frozen=True)
class _Verdict:
    """What monitoring decided before an action: replan, or go on with (possibly re-refined) choices."""

    replan: bool = False
    reason: str = ""
    sequence: ActionSequence | None = None
    choices: dict | None = None
    re_refined: bool = False
    changed: bool = False  # the re-refinement changed what the next window reads (it is re-refined in its turn)
