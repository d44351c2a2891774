"""The pipeline read top to bottom (Algorithm 4): plan -> instantiate -> assert -> refine -> dispatch.

One named function per stage; `prepare` strings the first ones together for a domain/problem pair on disk
(the PDDL is parsed once, by the planner: the plan carries the objects, types and initial facts).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from tailor.planner_bridge import DEFAULT_PLANNER, AbstractPlan, plan_files, resolve_problem
from tailor.refinement.action_sequence import ActionSequence
from tailor.refinement.assertion import AssertedSequence, Assertion, assert_subgoals
from tailor.refinement.belief import BeliefState, belief_path_for, load_belief
from tailor.refinement.binding import BINDING_FILE, Binding, load_domain_binding
from tailor.refinement.dispatch import dispatch
from tailor.errors import BindingError, ModelFileError
from tailor.refinement.instantiate import instantiate
from tailor.refinement.model_store import MODELS as MODELS_DIR
from tailor.refinement.models.action_models import ActionModel, load_action_models, load_success_models
from tailor.refinement.refine import RefinedSequence, refine
from tailor.sims.episode import SequenceResult

GREEDY_HORIZON = 1


@dataclass(frozen=True)
class Task:
    """A domain/problem pair on disk with what refinement needs beside it."""

    domain: Path
    problem: Path
    belief: Path
    models: Path | None = None  # the model folder (model_store.resolve_models); None: the domain's own

    @property
    def domain_dir(self) -> Path:
        return self.domain.parent

    @property
    def models_dir(self) -> Path:
        return self.models if self.models is not None else self.domain_dir / MODELS_DIR


@dataclass(frozen=True)
class Prepared:
    """Everything before refinement: the plan, its sequence (instantiated, subgoals asserted) and the models to
    refine it with; `instantiated` is the sequence before assertion, `assertions` what Algorithm 5 decided."""

    task: Task
    plan: AbstractPlan
    sequence: ActionSequence
    models: dict[str, ActionModel]
    binding: Binding
    success_models: dict = field(default_factory=dict)
    assertions: tuple[Assertion, ...] = ()
    instantiated: ActionSequence | None = None


def resolve_task(domain_arg: str, problem_arg: str, belief: str | Path | None = None,
                 models: Path | None = None) -> Task:
    """The task of a (bundled name or file) pair; `models` is the folder resolved by model_store."""
    domain, problem = resolve_problem(domain_arg, problem_arg)
    return Task(domain, problem, Path(belief) if belief else belief_path_for(problem), models)


def load_binding(task: Task) -> Binding:
    if not (task.domain_dir / BINDING_FILE).exists():
        raise BindingError(f"no action library binding {BINDING_FILE} beside the domain; refinement needs one",
                           file=str(task.domain_dir / BINDING_FILE))
    return load_domain_binding(task.domain_dir, task.domain)


def load_models(task: Task, sequence: ActionSequence) -> dict[str, ActionModel]:
    needed = tuple(sorted({a.action for a in sequence.actions}))
    models_dir = task.models_dir
    if not models_dir.is_dir():
        raise ModelFileError("no learned action models here (train them with `tailor train`)", file=str(models_dir))
    return load_action_models(models_dir, needed)


def success_models_for(task: Task, binding: Binding, sequence: ActionSequence) -> dict:
    """The success classifiers the binding names for the sequence's PDDL actions (subgoal assertion)."""
    return success_models_in(task.models_dir, binding, sequence)


def success_models_in(models_dir: Path, binding: Binding, sequence: ActionSequence) -> dict:
    """The success classifiers in `models_dir` that the binding names for the sequence's PDDL actions."""
    names = {binding.action(a.pddl.strip("()").split()[0]).success_model for a in sequence.actions}
    names.discard(None)
    return load_success_models(models_dir, names) if names else {}


def assert_task(sequence: ActionSequence, binding: Binding, success_models: dict, plan: AbstractPlan | None = None
                ) -> AssertedSequence:
    """Algorithm 5 (see tailor.refinement.assertion), the object types taken from the plan."""
    types = plan.object_types if plan is not None and plan.objects else None
    return assert_subgoals(sequence, binding, success_models, types)


def plan_task(task: Task, planner: str = DEFAULT_PLANNER, timeout: float | None = None) -> AbstractPlan:
    return plan_files(task.domain, task.problem, planner=planner, timeout=timeout)


def instantiate_task(task: Task, plan: AbstractPlan, binding: Binding, belief: BeliefState | None = None
                     ) -> ActionSequence:
    """Algorithm 3 with the problem's objects, their types (and ancestors) and initial facts from the plan."""
    if belief is None:
        belief = load_belief(task.belief, [name for name, _ in plan.objects] or None, binding.quantities)
    return instantiate(plan, binding, belief)


def prepare(task: Task, planner: str = DEFAULT_PLANNER, timeout: float | None = None, assertion: bool = True
            ) -> Prepared:
    """Plan, instantiate and (unless `assertion` is False: the plain executable actions) assert subgoals."""
    binding = load_binding(task)  # a bad binding fails before the planner runs,
    load_belief(task.belief, None, binding.quantities)  # and so does a belief file bad in itself (its objects
    plan = plan_task(task, planner, timeout)             # are checked against the plan's once there is one)
    instantiated = instantiate_task(task, plan, binding)
    success_models = success_models_for(task, binding, instantiated) if assertion else {}
    asserted = assert_task(instantiated, binding, success_models, plan) if assertion else None
    sequence = asserted.sequence if asserted else instantiated
    return Prepared(task, plan, sequence, load_models(task, sequence), binding, success_models,
                    asserted.assertions if asserted else (), instantiated)


@dataclass(frozen=True)
class Outcome:
    """A refined sequence and, when dispatched, what the simulator measured."""

    refined: RefinedSequence
    simulated: SequenceResult | None


def refine_prepared(prepared: Prepared, horizon: int, method: str, seed: int, risk: float = 0.0,
                    neighbourhood: float = 0.0) -> RefinedSequence:
    """The prepared sequence with its free parameters fixed by refinement with `horizon` (1: greedy)."""
    return refine(prepared.sequence, prepared.models, horizon=horizon, method=method, seed=seed,
                  success_models=prepared.success_models, risk=risk, neighbourhood=neighbourhood)


def dispatched(refined: RefinedSequence, seed: int, simulate: bool) -> Outcome:
    """The refined sequence with, if `simulate`, what the simulator measured executing it."""
    return Outcome(refined, dispatch(refined.sequence, seed=seed) if simulate else None)


def refine_and_dispatch(prepared: Prepared, horizon: int, method: str, seed: int, simulate: bool,
                        risk: float = 0.0, neighbourhood: float = 0.0) -> Outcome:
    return dispatched(refine_prepared(prepared, horizon, method, seed, risk, neighbourhood), seed, simulate)
