"""The driver (Algorithm 4), one for every caller: read -> plan -> instantiate -> assert -> refine -> dispatch.

`read_task` reads each input of a task once (the PDDL pair, the binding checked against the domain's
signature, the belief file); `run` takes what it read and options, and returns one `Result`: the plan, the
instantiated sequence, the assertions, the greedy and refined (and zero-baseline) executions with their
predictions, the meta filter's decision and the optimizers' notes. The command line formats a Result, the API
checks its arguments and calls `run`, and the evaluations call `refine_stage` on each random situation (their
plan made once per problem, their belief drawn by the simulator), so the stages are chained in one place.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from pathlib import Path

from tailor.errors import BeliefError, BindingError, ModelFileError, UsageError
from tailor.planner_bridge import DEFAULT_PLANNER, AbstractPlan, PDDLTask, plan_pddl, read_pddl, resolve_problem
from tailor.refinement.action_sequence import ActionSequence
from tailor.refinement.assertion import AssertedSequence, Assertion, Detour, assert_subgoals
from tailor.refinement.belief import BeliefState, belief_path_for, load_belief, parse_belief
from tailor.refinement.binding import BINDING_FILE, Binding, known_measures, load_domain_binding
from tailor.refinement.check import TaskCheck, check_task
from tailor.refinement.dispatch import check_scene, dispatch
from tailor.refinement.meta_filter import MetaDecision, decide
from tailor.refinement.model_store import ModelSource, resolve_models
from tailor.refinement.models.action_models import ActionModel, load_action_models, load_success_models
from tailor.refinement.optimizers import DEFAULT_OPTIMIZER
from tailor.refinement.binding_domain import did_you_mean
from tailor.refinement.objective_grammar import MeasureBound, WeightedObjective
from tailor.refinement.refine import (RefinedSequence, check_measures, predicted_durations, predicted_measures, refine,
                                      resolve_risk)
from tailor.sims.episode import SequenceResult

GREEDY_HORIZON = 1
BELIEF_ARGUMENT = "<belief argument>"  # where a belief given as values (the API's dict) is said to come from


@dataclass(frozen=True)
class Task:
    """A domain/problem pair on disk with what refinement needs beside it."""

    domain: Path
    problem: Path | None  # None: a unified-planning Problem given as an object (no file, no belief file beside it)
    belief: Path | None
    models: Path | None = None  # the model folder (model_store.resolve_models); None: the domain's own

    @property
    def domain_dir(self) -> Path:
        return self.domain.parent

    @property
    def models_dir(self) -> Path:
        return self.models if self.models is not None else self.domain_dir / "models"


@dataclass(frozen=True)
class Inputs:
    """A task's inputs, each read once: the PDDL pair (read and checked, not yet planned), the binding
    (checked against the domain's signature), the belief (checked in itself; its objects once there is a plan)
    and where the action models come from."""

    task: Task
    pddl: PDDLTask | None  # None where the caller brings the plan (and the problem object) itself
    binding: Binding
    belief: BeliefState
    models: ModelSource


@dataclass(frozen=True)
class Options:
    """How to refine. None: the binding's `[refinement]` default (filter, neighbourhood, zero), or for `risk`
    refine.DEFAULT_RISK where every model stores its uncertainty."""

    horizon: int = 2
    optimizer: str = DEFAULT_OPTIMIZER
    seed: int = 0
    risk: float | None = None
    neighbourhood: float | None = None
    filter: bool | None = None
    zero: bool | None = False  # also execute every free parameter at 0 (the baseline of Fig. 5.14)
    assertion: bool = True  # subgoal assertion (Alg. 5) where the binding names success models
    greedy: bool = True  # also refine greedily (h = 1), the baseline; always where the filter runs
    simulate: bool = False  # dispatch each execution to the simulator
    planner: str = DEFAULT_PLANNER
    timeout: float | None = None
    strict: bool = False  # the check's warnings (refinement.check) are errors
    # what refinement minimizes (Ch. 8.1): None, the binding's [objective] (default: the predicted duration)
    objective: WeightedObjective | None = None
    limits: tuple[MeasureBound, ...] = ()  # bounds on every action's predicted measures (`--max error=0.05`)


@dataclass(frozen=True)
class Execution:
    """A refined sequence and, when dispatched, what the simulator measured."""

    refined: RefinedSequence
    simulated: SequenceResult | None = None


@dataclass(frozen=True)
class Refinements:
    """What refinement made of one instantiated sequence: the refined execution (the greedy one where the meta
    filter kept it), greedy (h = 1) and the zero baseline where asked for, and the filter's decision."""

    refined: Execution
    greedy: Execution | None = None
    zero: Execution | None = None
    decision: MetaDecision | None = None
    optimized: RefinedSequence | None = None  # the refinement itself, also where the filter kept greedy


@dataclass(frozen=True)
class Prepared:
    """Everything before refinement: the plan, its sequence instantiated and asserted, the models to refine it
    with, and the options with every default resolved (risk, neighbourhood, filter, zero)."""

    plan: AbstractPlan
    instantiated: ActionSequence  # Alg. 3: free parameters as ranges
    sequence: ActionSequence  # after the assert stage (Alg. 5): what is refined
    assertions: tuple[Assertion, ...]
    binding: Binding
    models_source: ModelSource
    models: dict[str, ActionModel]
    success_models: dict
    options: Options
    warnings: tuple[str, ...] = ()  # what refinement.check found odd in the binding and belief

    @property
    def empty(self) -> bool:
        """The goal holds initially: nothing to refine or execute."""
        return not self.sequence.actions

    @property
    def models_dir(self) -> Path:
        return self.models_source.path


@dataclass(frozen=True)
class Result(Prepared):
    """One run of the driver: every stage's output (Prepared's) and the executions refinement made."""

    refined: Execution | None = None
    greedy: Execution | None = None
    zero: Execution | None = None
    decision: MetaDecision | None = None


def resolve_task(domain_arg: str, problem_arg: str, belief: str | Path | None = None,
                 models: Path | None = None) -> Task:
    """The task of a (bundled name or file) pair; `models` is the folder resolved by model_store."""
    domain, problem = resolve_problem(domain_arg, problem_arg)
    return Task(domain, problem, Path(belief) if belief else belief_path_for(problem), models)


def load_binding(task: Task, signature=None) -> Binding:
    """The binding beside the task's domain, checked against the domain (its signature where it was read)."""
    if not (task.domain_dir / BINDING_FILE).exists():
        raise BindingError(f"no action library binding {BINDING_FILE} beside the domain; refinement needs one",
                           file=str(task.domain_dir / BINDING_FILE))
    return load_domain_binding(task.domain_dir, task.domain, signature)


def read_task(task: Task, models: str | Path | None = None, belief: Mapping | None = None, pddl: bool = True,
              ) -> Inputs:
    """Read each input of `task` once: the PDDL pair first (read and checked; `pddl` False where the caller brings
    its own plan or Problem), then the binding against the domain's signature, the belief (the values `belief`
    as a belief file's `objects` table, else the task's belief file) and the model folder (`models`, else
    model_store's order)."""
    read = read_pddl(task.domain, task.problem) if pddl else None
    binding = load_binding(task, read.signature if read is not None else None)
    if belief is not None:
        belief = parse_belief({"objects": belief}, BELIEF_ARGUMENT, None, binding.quantities)
    elif task.belief is None:
        raise BeliefError("no belief: a unified-planning Problem has no belief file beside it; give the values as "
                          "{object: {quantity: value}} or a belief file", file=BELIEF_ARGUMENT)
    else:
        belief = load_belief(task.belief, None, binding.quantities)
    source = resolve_models(task.domain_dir, models)
    return Inputs(replace(task, models=source.path), read, binding, belief, source)


def load_models(models_dir: Path, sequence: ActionSequence) -> dict[str, ActionModel]:
    """The duration models of the sequence's executable actions."""
    if not Path(models_dir).is_dir():
        raise ModelFileError("no learned action models here (train them with `tailor train`)", file=str(models_dir))
    return load_action_models(Path(models_dir), tuple(sorted({a.action for a in sequence.actions})))


def success_models_in(models_dir: Path, binding: Binding, sequence: ActionSequence) -> dict:
    """The success classifiers in `models_dir` that the binding names for the sequence's PDDL actions."""
    names = {binding.action(a.pddl.strip("()").split()[0]).success_model for a in sequence.actions}
    names.discard(None)
    return load_success_models(Path(models_dir), names) if names else {}


def assert_task(sequence: ActionSequence, binding: Binding, success_models: dict, plan: AbstractPlan | None = None,
                detour: Detour | None = None) -> AssertedSequence:
    """Algorithm 5 (see tailor.refinement.assertion), the object types taken from the plan; with `detour`, a
    subgoal only where the predicted failure costs more than the detour."""
    types = plan.object_types if plan is not None and plan.objects else None
    return assert_subgoals(sequence, binding, success_models, types, detour)


def resolve_options(options: Options, binding: Binding, models: dict[str, ActionModel]) -> Options:
    """`options` with the binding's `[refinement]` defaults and the risk filled in."""
    defaults = binding.refinement
    return replace(options,
                   objective=binding.objective if options.objective is None else options.objective,
                   risk=resolve_risk(options.risk, models.values()),
                   neighbourhood=defaults.neighbourhood if options.neighbourhood is None else options.neighbourhood,
                   filter=defaults.filter if options.filter is None else options.filter,
                   zero=defaults.zero_baseline if options.zero is None else options.zero)


def unknown_measure(binding: Binding, objective: WeightedObjective | None, limits=()) -> str | None:
    """What is wrong with a measure the objective or a limit names that the binding's simulator does not have
    (None: nothing); the command line and the API each raise it as their own error (a usage error)."""
    known = known_measures(binding.entry)
    named = [*(objective.measures if objective is not None else ()), *(limit.measure for limit in limits)]
    for measure in named:
        if measure not in known:
            return (f"unknown measure {measure!r}: the measures of simulator {binding.simulator!r} are "
                    f"{', '.join(known)}{did_you_mean(measure, known)}")
    return None


def zero_assignment(sequence: ActionSequence) -> dict[str, float]:
    """Every free parameter at 0, clipped into its range (e.g. stop at every way-point)."""
    return {p.id: min(max(0.0, p.low), p.high) for p in sequence.free_parameters()}


def refine_stage(sequence: ActionSequence, models: dict[str, ActionModel], success_models: dict, options: Options,
                 meta=None) -> Refinements:
    """Refine an asserted sequence with resolved `options` (see resolve_options): greedy where asked for or
    where the meta model `meta` judges refinement (Sec. 5.5.4: refine, or keep greedy), the zero baseline, and
    with `options.simulate` each execution dispatched with the same simulator seed."""
    seed = options.seed

    def execution(refined: RefinedSequence) -> Execution:
        return Execution(refined, dispatch(refined.sequence, seed=seed) if options.simulate else None)

    judged = meta is not None and options.horizon > GREEDY_HORIZON and sequence.actions
    greedy = None
    objective = {} if options.objective is None else {"objective": options.objective}
    if options.greedy or judged:  # the same objective and limits, one action at a time
        greedy = refine(sequence, models, horizon=GREEDY_HORIZON, method=options.optimizer, seed=seed,
                        success_models=success_models, limits=options.limits, **objective)
    optimized = refine(sequence, models, horizon=options.horizon, method=options.optimizer, seed=seed,
                       success_models=success_models, risk=options.risk, neighbourhood=options.neighbourhood,
                       limits=options.limits, **objective)
    decision = decide(meta, greedy, models, optimized) if judged else None
    kept_greedy = decision is not None and not decision.refine
    greedy_run = execution(greedy) if greedy is not None else None
    refined_run = greedy_run if kept_greedy else execution(optimized)
    zero = None
    if options.zero and sequence.free_parameters():
        bound = sequence.bind(zero_assignment(sequence))
        zero = execution(RefinedSequence(bound, predicted_durations(bound, models), (), 0,
                                         measures=predicted_measures(bound, models)))
    return Refinements(refined_run, greedy_run if options.greedy else None, zero, decision, optimized)


def check(inputs: Inputs, plan: AbstractPlan) -> TaskCheck:
    """Alg. 3 on `plan`, noting what it reads from the belief (refinement.check): the belief's objects checked
    against the plan's first. `prepare` and `tailor check` both start here."""
    objects = [name for name, _ in plan.objects]
    belief = inputs.belief.check_objects(objects) if objects else inputs.belief
    return check_task(plan, inputs.binding, belief)


def prepare(inputs: Inputs, options: Options = Options(), plan: AbstractPlan | None = None, warn: bool = True
            ) -> Prepared:
    """Algorithm 4 up to refinement on a task read by `read_task`: plan (unless `plan` is given), instantiate,
    assert (unless `options.assertion` is False), load the models, resolve the options' defaults. `warn` False:
    the check's warnings are kept in the result, not logged (a replan's belief holds values executed so far)."""
    if plan is None:
        plan = plan_pddl(inputs.pddl, planner=options.planner, timeout=options.timeout)
    checked = check(inputs, plan)
    for warning in checked.warnings:
        if options.strict:
            raise BindingError(f"{warning} (--strict)")
        if warn:
            logging.getLogger(__name__).warning("%s", warning)
    instantiated = checked.sequence
    success_models: dict = {}
    sequence, assertions = instantiated, ()
    models = load_models(inputs.models.path, instantiated)  # (an asserted subgoal reuses the same actions)
    resolved = resolve_options(options, inputs.binding, models)
    if options.assertion:  # the detour weighed as the refine stage will take it
        success_models = success_models_in(inputs.models.path, inputs.binding, instantiated)
        detour = Detour(models, resolved.optimizer, resolved.seed, resolved.risk, resolved.neighbourhood)
        asserted = assert_task(instantiated, inputs.binding, success_models, plan, detour)
        sequence, assertions = asserted.sequence, asserted.assertions
    wrong = unknown_measure(inputs.binding, resolved.objective, resolved.limits)
    if wrong is not None:
        raise UsageError(wrong)
    check_measures(sequence.actions, models, resolved.objective, resolved.limits)  # each has a model of each
    if not sequence.actions:
        resolved = replace(resolved, simulate=False)  # nothing to execute
    return Prepared(plan, instantiated, sequence, tuple(assertions), inputs.binding, inputs.models, models,
                    success_models, resolved, checked.warnings)


def run(inputs: Inputs, options: Options = Options(), plan: AbstractPlan | None = None, meta=None) -> Result:
    """Algorithm 4 on a task read by `read_task`: prepare (plan unless `plan` is given, instantiate, assert),
    refine and, with `options.simulate`, dispatch. `meta` is the meta action model where the filter may run (the
    caller loads it before planning, so a bad one fails before the planner's time is spent)."""
    prepared = prepare(inputs, options, plan)
    resolved = prepared.options
    if not resolved.filter:
        meta = None
    elif meta is not None and meta.horizon != resolved.horizon and resolved.horizon > GREEDY_HORIZON:
        logging.getLogger(__name__).warning("the meta model judges refinement with h=%d, not the h=%d asked for",
                                            meta.horizon, resolved.horizon)
    if resolved.simulate:  # a scene object the simulator lacks fails before refining
        check_scene(prepared.sequence, inputs.binding.file)
    stage = refine_stage(prepared.sequence, prepared.models, prepared.success_models, resolved, meta)
    return Result(**{f.name: getattr(prepared, f.name) for f in fields(Prepared)}, refined=stage.refined,
                  greedy=stage.greedy, zero=stage.zero, decision=stage.decision)
