"""The Python API, one call per stage: `tailor.plan`, `tailor.refine`, `tailor.dispatch` (exported by `tailor`).

    import tailor
    plan = tailor.plan(domain, problem)                        # files, bundled names, or a UP Problem
    refined = tailor.refine(domain, problem, horizon=2)        # belief: the problem's file, a dict or a path
    refined.chosen                                             # free parameter -> value: {"pos2.phi": 2.356}
    result = tailor.dispatch(refined, seed=0)                  # what the simulator measured

Files are planned in one planner child process kept for the whole session (fixed hash seed: the same files give
the same plan on every run; its start-up is paid once), which lives as long as this process, whichever thread
started it; unified-planning Problems are planned in this process (under a timeout, in a forked copy of it).
Every call may come from any thread, also from several at once: the planner process serves them in turn.
Every error is a `tailor.TailorError`; a wrong argument is its ArgumentTypeError (a TypeError) or
ArgumentValueError (a ValueError), naming the argument.
"""

from __future__ import annotations

import atexit
import numbers
import threading
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from tailor.errors import ArgumentTypeError, ArgumentValueError
from tailor.planner_bridge import (DEFAULT_PLANNER, AbstractPlan, PDDLTask, plan_pddl, read_pddl, resolve_domain_dir,
                                   resolve_problem)
from tailor.planner_bridge.reading import parse_task
from tailor.planner_bridge.bridge import check_limits
from tailor.planner_bridge.up_interop import link_plan, plan_problem
from tailor.planner_bridge.worker import PlannerProcess
from tailor.refinement import pipeline
from tailor.refinement.action_sequence import ActionSequence
from tailor.refinement.binding import DOMAIN_FILE
from tailor.refinement.dispatch import dispatch as dispatch_sequence
from tailor.refinement.models.meta_model import load_meta_model
from tailor.refinement.objective_grammar import (MeasureBound, ObjectiveSyntaxError, WeightedObjective, bounds_of,
                                                 objective_from_table, parse_objective)
from tailor.refinement.optimizers import DEFAULT_OPTIMIZER, OPTIMIZERS
from tailor.refinement.refine import RefinedSequence, check_neighbourhood, check_risk
from tailor.sims.episode import SequenceResult
from tailor.sims.experience import MAX_SEED

_PLANNER = None  # the session's planner child process (planner_bridge.worker.PlannerProcess)
_PLANNER_LOCK = threading.Lock()  # one request at a time: the child answers them in turn


@dataclass(frozen=True)
class Refinement:
    """A plan refined for the fastest predicted execution: what was free, what it was set to, and why."""

    plan: AbstractPlan
    instantiated: ActionSequence  # after Alg. 3 and the assert stage (Alg. 5): free parameters as ranges
    refined: RefinedSequence  # every parameter bound, with its predicted durations
    models: Path  # the folder the action models came from
    assertions: tuple = ()  # the assert stage's decisions (tailor.refinement.assertion), with their provenance
    filter: object = None  # the meta filter's decision (tailor.refinement.meta_filter.MetaDecision) when it ran

    @property
    def sequence(self) -> ActionSequence:
        """The executable sequence, every parameter bound (what `dispatch` runs)."""
        return self.refined.sequence

    @property
    def free(self) -> dict[str, tuple[float, float]]:
        """Each free parameter's id with its range (low, high), in plan order."""
        return {p.id: (p.low, p.high) for p in self.instantiated.free_parameters()}

    @property
    def chosen(self) -> dict[str, float]:
        """Each free parameter's id with the value refinement chose: `{"pos2.phi": 2.356, ...}`."""
        values = {p.id: p.value for a in self.refined.sequence.actions for p in a.params}
        return {pid: values[pid] for pid in self.free}

    @property
    def predicted_total(self) -> float:
        """The predicted duration of the whole sequence, seconds."""
        return self.refined.predicted_total

    @property
    def measures(self) -> list[dict[str, float]]:
        """Per action, every measure its model predicts at the chosen values: `{"duration": 3.2, "energy": 41.0}`."""
        return [dict(m) for m in self.refined.measures]

    @property
    def violations(self) -> tuple:
        """The limits no choice could keep (refine.Violation: step, measure, predicted, bound); () where all hold."""
        return self.refined.violations

    def to_json(self) -> dict:
        return {"plan": self.plan.to_json(), "models": str(self.models), "horizon": self.refined.horizon,
                "risk": self.refined.risk, "neighbourhood": self.refined.neighbourhood,
                "objective": self.refined.objective.to_json(),
                "limits": {b.measure: b.bound for b in self.refined.limits},
                "assertions": [a.to_json() for a in self.assertions],
                "filter": None if self.filter is None else self.filter.to_json(),
                "free_parameters": [{"id": pid, "low": low, "high": high, "value": self.chosen[pid]}
                                    for pid, (low, high) in self.free.items()],
                "sequence": self.sequence.to_json(), "predicted_s": list(self.refined.predicted),
                "predicted_total_s": self.predicted_total, "measures": self.measures,
                "violations": [v.to_json() for v in self.violations]}


def plan(domain, problem=None, *, planner: str = DEFAULT_PLANNER, timeout: float | None = None) -> AbstractPlan:
    """A validated partial-order plan with causal links, for a PDDL pair (paths or bundled names) or for a
    unified-planning Problem (given alone, as `domain`, or as `problem`). `timeout` limits parsing, compiling
    and search together, in seconds (a PlannerTimeoutError), for either. Safe to call from any thread and from
    several at once: files are planned in the session's one planner process, one request at a time."""
    _check(planner, str, "planner")
    _check_timeout(timeout)
    up_problem = _up_problem(domain if problem is None else problem)
    if up_problem is not None:
        return plan_problem(up_problem, planner, timeout=timeout)
    if problem is None:
        raise ArgumentValueError("problem is missing: give a PDDL problem (path or name) or a unified-planning "
                                 "Problem")
    return _plan_files(domain, problem, planner, timeout)


def refine(domain, problem, belief=None, *, plan: object = None, horizon: int = 2, optimizer: str = DEFAULT_OPTIMIZER,
           seed: int = 0, models: str | Path | None = None, planner: str = DEFAULT_PLANNER,
           timeout: float | None = None, assertion: bool = True, filter: bool | None = None,
           risk: float | None = None, neighbourhood: float | None = None, objective=None, limits=None
           ) -> Refinement:
    """Plan (unless `plan` is given: ours, or a SequentialPlan / PartialOrderPlan of any UP engine),
    instantiate (Alg. 3), assert subgoals where a success model predicts failure (Alg. 5; unless `assertion`
    is False) and refine over `horizon` actions (Sec. 5.4; 1 is greedy), as `tailor refine` does.

    `domain` is a bundled name, a domain folder or its domain.pddl (the binding `actions.toml` beside it says
    how its actions execute); `problem` a PDDL file, a problem name or a unified-planning Problem; `belief`
    the continuous values `{object: {quantity: value}}`, a belief file, or None for the problem's own file.
    `models` is a model folder (default: as the CLI, see model_store). `filter` (default: the binding's
    `[refinement] filter`): refine only where the meta action model `models/meta.json` predicts that refinement
    makes execution faster, else keep the greedy (h = 1) parameterization (Sec. 5.5.4); `.filter` says which
    and why. `risk` is lambda of the risk-aware objective, expected duration + lambda * uncertainty (None:
    refine.DEFAULT_RISK where every model stores its uncertainty, else 0 with a warning; an explicit lambda > 0
    needs it, see models.uncertainty); `neighbourhood` the share of each free range around a choice whose
    worst predicted time is minimized (None: the binding's `[refinement] neighbourhood`, else 0); greedy (h = 1)
    stays plain. `optimizer` names one of OPTIMIZERS: "auto" (default) runs the analytic minimization where it
    applies, else the certified branch and bound where the feature spaces declare bounds, else the genetic
    algorithm; each window of `.refined.windows` says which ran, why the others did not, and its certified gap
    (`.gap`, None where there is no bound).

    `objective` is what refinement minimizes (Ch. 8.1): text as `--objective` takes it ("duration + 0.3*energy"),
    a mapping {measure: weight}, a WeightedObjective, or None for the binding's `[objective]` (else the
    duration); `limits` bound every action's predicted measures: {measure: bound}, or texts "error=0.05". Every
    measure named must be one the domain's simulator reports and every action's model predicts (a ModelFileError
    naming the file otherwise). A limit no choice keeps does not raise: `.violations` names each."""
    seed, horizon = _refine_arguments(domain, problem, belief, seed, horizon, models, assertion, filter, risk,
                                      neighbourhood, optimizer, timeout)
    objective, limits = _objective_arguments(objective, limits)
    up_problem = _up_problem(problem)
    domain_dir = resolve_domain_dir(domain)
    if up_problem is None:
        task = pipeline.resolve_task(domain, problem, belief if isinstance(belief, (str, Path)) else None)
    else:
        task = pipeline.Task(domain_dir / DOMAIN_FILE, None, Path(belief) if isinstance(belief, (str, Path)) else None)
    inputs = pipeline.read_task(task, models, _belief_table(belief) if isinstance(belief, Mapping) else None,
                                pddl=task.problem is not None)
    if up_problem is None and _is_up_plan(plan):  # a plan of unified-planning for the files named: their Problem
        up_problem = parse_task(inputs.pddl)  # (its actions are matched by name: a plan found elsewhere links too)
    abstract = _given_plan(plan, up_problem, domain_dir)
    if isinstance(plan, AbstractPlan) and inputs.pddl is not None and plan.problem.lower() != inputs.pddl.problem_name:
        raise ArgumentValueError(f"plan is a plan of problem {plan.problem!r}, not of {inputs.pddl.problem_name!r} "
                                 f"({task.problem})")
    for name, weighed, bounds in (("objective", objective, ()), ("limits", None, limits)):
        wrong = pipeline.unknown_measure(inputs.binding, weighed, bounds)
        if wrong is not None:
            raise ArgumentValueError(f"{name}: {wrong}")
    use_filter = inputs.binding.refinement.filter if filter is None else filter
    meta = load_meta_model(inputs.models.path) if use_filter else None
    if abstract is None:
        abstract = (plan_problem(up_problem, planner, timeout=timeout) if up_problem is not None
                    else _plan_files(task.domain, task.problem, planner, timeout, inputs.pddl))
    options = pipeline.Options(horizon=horizon, optimizer=optimizer, seed=seed, risk=risk, neighbourhood=neighbourhood,
                               filter=filter, assertion=assertion, greedy=False, planner=planner, timeout=timeout,
                               objective=objective, limits=limits)
    result = pipeline.run(inputs, options, plan=abstract, meta=meta)
    return Refinement(result.plan, result.sequence, result.refined.refined, result.models_dir, result.assertions,
                      result.decision)


def _refine_arguments(domain, problem, belief, seed, horizon, models, assertion, filter, risk, neighbourhood,
                      optimizer, timeout) -> tuple[int, int]:
    """The checks of `refine`'s arguments (an ArgumentTypeError or ArgumentValueError naming the argument);
    the seed and horizon as Python ints."""
    _check(domain, (str, Path), "domain")
    seed, horizon = _whole(seed), _whole(horizon)  # (numpy's integers are whole numbers too)
    _check_seed(seed)
    _check(horizon, int, "horizon")
    _check_timeout(timeout)
    if models is not None:
        _check(models, (str, Path), "models")
    if not isinstance(assertion, bool):
        raise ArgumentTypeError(f"assertion must be bool, not {type(assertion).__name__}")
    if filter is not None and not isinstance(filter, bool):
        raise ArgumentTypeError(f"filter must be bool or None, not {type(filter).__name__}")
    if horizon < 1:
        raise ArgumentValueError(f"horizon must be at least 1, not {horizon}")
    if risk is not None:
        if isinstance(risk, bool) or not isinstance(risk, (int, float)):
            raise ArgumentTypeError(f"risk must be a number or None, not {type(risk).__name__}")
        check_risk(risk)
    if neighbourhood is not None:
        if isinstance(neighbourhood, bool) or not isinstance(neighbourhood, (int, float)):
            raise ArgumentTypeError(f"neighbourhood must be a number or None, not {type(neighbourhood).__name__}")
        check_neighbourhood(neighbourhood)
    if optimizer not in OPTIMIZERS:
        raise ArgumentValueError(f"optimizer must be one of {', '.join(sorted(OPTIMIZERS))}, not {optimizer!r}")
    if _up_problem(problem) is None:
        _check(problem, (str, Path), "problem")
    if belief is None and _up_problem(problem) is not None:
        raise ArgumentValueError("belief is missing: a unified-planning Problem has no belief file beside it; "
                                 "give the values as {object: {quantity: value}} or a belief file")
    if belief is not None and not isinstance(belief, (Mapping, str, Path)):
        raise ArgumentTypeError(f"belief must be a mapping {{object: {{quantity: value}}}}, a path or None, "
                                f"not {type(belief).__name__}")
    return seed, horizon


def _objective_arguments(objective, limits) -> tuple[WeightedObjective | None, tuple[MeasureBound, ...]]:
    """`refine`'s objective and limits as the pipeline takes them (an ArgumentTypeError or ArgumentValueError
    naming the argument)."""
    try:
        if isinstance(objective, str):
            objective = parse_objective(objective)
        elif isinstance(objective, Mapping):
            objective = objective_from_table(dict(objective))
        elif objective is not None and not isinstance(objective, WeightedObjective):
            raise ArgumentTypeError(f"objective must be text, a mapping {{measure: weight}}, a WeightedObjective or "
                                    f"None, not {type(objective).__name__}")
    except ObjectiveSyntaxError as exc:
        raise ArgumentValueError(f"objective {objective!r}: {exc}") from None
    except ValueError as exc:
        raise ArgumentValueError(f"objective: {exc}") from None
    if limits is None:
        return objective, ()
    if isinstance(limits, Mapping):
        items = []
        for measure, bound in limits.items():
            if isinstance(bound, bool) or not isinstance(bound, (int, float)) and not _real(bound):
                raise ArgumentTypeError(f"limits: the bound of {measure!r} must be a number, not "
                                        f"{type(bound).__name__}")
            try:
                items.append(MeasureBound(str(measure), float(bound)))
            except ValueError as exc:
                raise ArgumentValueError(f"limits: {exc}") from None
        limits = items
    elif isinstance(limits, (str, bytes)) or not hasattr(limits, "__iter__"):
        raise ArgumentTypeError(f"limits must be a mapping {{measure: bound}} or a list of \"measure=bound\" texts, "
                                f"not {type(limits).__name__}")
    try:
        return objective, bounds_of(list(limits))
    except ObjectiveSyntaxError as exc:
        raise ArgumentValueError(f"limits: {exc}") from None


def _is_up_plan(plan) -> bool:
    """Whether `plan` is a plan of unified-planning (without importing it for a plan of ours or None)."""
    if plan is None or isinstance(plan, (AbstractPlan, str, int, float)):
        return False
    from unified_planning.plans import Plan

    return isinstance(plan, Plan)


def dispatch(refined, seed: int = 0) -> SequenceResult:
    """Execute a refined (fully bound) sequence in its simulator: durations, outcomes and the trajectory."""
    seed = _whole(seed)
    _check_seed(seed)
    sequence = refined.sequence if isinstance(refined, (Refinement, RefinedSequence)) else refined
    if not isinstance(sequence, ActionSequence):
        raise ArgumentTypeError(f"refined must be a Refinement, RefinedSequence or ActionSequence, "
                                f"not {type(refined).__name__}")
    if sequence.free_parameters():
        raise ArgumentValueError("refined has free parameters left: "
                                 + ", ".join(p.id for p in sequence.free_parameters()) + " (refine it first)")
    return dispatch_sequence(sequence, seed=seed)


def _check(value, types, name: str) -> None:
    if isinstance(value, bool) or not isinstance(value, types):
        names = " or ".join(t.__name__ for t in (types if isinstance(types, tuple) else (types,)))
        raise ArgumentTypeError(f"{name} must be {names}, not {type(value).__name__}")


def _whole(value):
    """A numpy integer (np.int64 out of an array) as the Python int it is; anything else as it is."""
    return int(value) if isinstance(value, numbers.Integral) and not isinstance(value, bool) else value


def _check_seed(seed) -> None:
    """A seed as the command line takes it: a whole number from 0 to MAX_SEED (numpy's generators take no
    negative seed, and experience files store seeds as 64-bit integers)."""
    _check(seed, int, "seed")
    if not 0 <= seed <= MAX_SEED:
        raise ArgumentValueError(f"seed must be a whole number from 0 to 2**63 - 1, not {seed}")


def _up_problem(value):
    """`value` if it is a unified-planning Problem, else None (without importing unified-planning for paths)."""
    if isinstance(value, (str, Path)) or value is None:
        return None
    from unified_planning.model import Problem

    if isinstance(value, Problem):
        return value
    raise ArgumentTypeError(f"problem must be a path, a problem name or a unified_planning Problem, "
                            f"not {type(value).__name__}")


def _given_plan(given, up_problem, domain_dir: Path) -> AbstractPlan | None:
    """The caller's plan as ours: an AbstractPlan as it is, a UP plan linked against the problem."""
    if given is None or isinstance(given, AbstractPlan):
        return given
    from unified_planning.plans import Plan

    if not isinstance(given, Plan):
        raise ArgumentTypeError(f"plan must be a tailor AbstractPlan, a unified-planning plan or None, "
                                f"not {type(given).__name__}")
    if up_problem is None:
        raise ArgumentValueError("plan: a unified-planning plan needs the unified-planning Problem it solves "
                                 "(pass problem=Problem)")
    return link_plan(up_problem, given, domain=domain_dir.name)


def _real(value) -> bool:
    """A real number that is not a bool: Python's, or numpy's (np.float32, np.int64) out of an array."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and not isinstance(value, (int, float))


def _belief_table(belief: Mapping) -> dict:
    """A belief given in Python as the TOML file's `objects` table (values checked by parse_belief)."""
    table = {}
    for name, values in belief.items():
        if not isinstance(name, str) or not isinstance(values, Mapping):
            raise ArgumentTypeError("belief must map object names to {quantity: value} mappings, "
                                    f"got {name!r}: {type(values).__name__}")
        table[name] = {quantity: float(value) if _real(value) else value for quantity, value in values.items()}
    return table


def _check_timeout(timeout) -> None:
    if timeout is not None and (isinstance(timeout, bool) or not isinstance(timeout, (int, float))):
        raise ArgumentTypeError(f"timeout must be a number of seconds or None, not {type(timeout).__name__}")
    check_limits(timeout)


def _plan_files(domain, problem, planner: str, timeout: float | None, pddl: PDDLTask | None = None) -> AbstractPlan:
    """Plan a PDDL pair (`pddl` where it has been read already) in the session's planner process (started on
    first use, ended at exit)."""
    global _PLANNER
    _check(domain, (str, Path), "domain")
    _check(problem, (str, Path), "problem")
    _check_timeout(timeout)
    if pddl is None:
        pddl = read_pddl(*resolve_problem(domain, problem))
    with _PLANNER_LOCK:
        if _PLANNER is None:
            _PLANNER = PlannerProcess()
            atexit.register(_PLANNER.close)
        return plan_pddl(pddl, planner, timeout, process=_PLANNER)


__all__ = ["Refinement", "plan", "refine", "dispatch"]
