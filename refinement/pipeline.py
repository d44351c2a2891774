"""The pipeline read top to bottom (Algorithm 4 without assertion): plan -> instantiate -> refine -> dispatch.

One named function per stage; `prepare` strings the first ones together for a domain/problem pair on disk
(the PDDL is parsed once, by the planner: the plan carries the objects, types and initial facts).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from tailor.planner_bridge import DEFAULT_PLANNER, AbstractPlan, plan_files, resolve_problem
from tailor.refinement.action_sequence import ActionSequence
from tailor.refinement.belief import BeliefState, belief_path_for, load_belief
from tailor.refinement.binding import BINDING_FILE, Binding, load_domain_binding
from tailor.refinement.dispatch import dispatch
from tailor.errors import BindingError, ModelFileError
from tailor.refinement.instantiate import instantiate
from tailor.refinement.model_store import MODELS as MODELS_DIR
from tailor.refinement.models.action_models import ActionModel, load_action_models
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
    """Everything before refinement: the plan, its instantiated sequence and the models to refine it with."""

    task: Task
    plan: AbstractPlan
    sequence: ActionSequence
    models: dict[str, ActionModel]
    binding: Binding


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


def plan_task(task: Task, planner: str = DEFAULT_PLANNER, timeout: float | None = None) -> AbstractPlan:
    return plan_files(task.domain, task.problem, planner=planner, timeout=timeout)


def instantiate_task(task: Task, plan: AbstractPlan, binding: Binding, belief: BeliefState | None = None
                     ) -> ActionSequence:
    """Algorithm 3 with the problem's objects, their types (and ancestors) and initial facts from the plan."""
    if belief is None:
        belief = load_belief(task.belief, [name for name, _ in plan.objects] or None, binding.quantities)
    return instantiate(plan, binding, belief)


def prepare(task: Task, planner: str = DEFAULT_PLANNER, timeout: float | None = None) -> Prepared:
    binding = load_binding(task)  # a bad binding fails before the planner runs
    plan = plan_task(task, planner, timeout)
    sequence = instantiate_task(task, plan, binding)
    return Prepared(task, plan, sequence, load_models(task, sequence), binding)


@dataclass(frozen=True)
class Outcome:
    """A refined sequence and, when dispatched, what the simulator measured."""

    refined: RefinedSequence
    simulated: SequenceResult | None


def refine_and_dispatch(prepared: Prepared, horizon: int, method: str, seed: int, simulate: bool) -> Outcome:
    refined = refine(prepared.sequence, prepared.models, horizon=horizon, method=method, seed=seed)
    simulated = dispatch(refined.sequence, seed=seed) if simulate else None
    return Outcome(refined, simulated)
