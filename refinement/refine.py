"""Subgoal refinement (Sec. 5.4): choose the free parameters so the summed predicted duration is minimal.

The sequence is refined h actions at a time (the horizon): at action i the still-free parameters of
actions i..i+h-1 are optimized for the sum of their predicted durations, then the ones action i uses are
fixed and the window moves on. h = 1 is the greedy baseline of Sec. 5.5.1: each subgoal is chosen for the
action that reaches it only. Each window is one Objective for the optimizers (`auto` by default: analytic,
certified or the GA, see optimizers); a term carries the enclosure its model's feature space declares
(FeatureSpace.bounds) over the boxes of action parameters a box of free values gives, for the certified one.

Beyond the dissertation: with a risk lambda > 0 each action's predicted duration is charged lambda times its
uncertainty (the held-out spread of the leaf it comes from, models.uncertainty), so the optimizer stops
chasing subgoals the models do not know; every choice keeps a margin (MARGIN_SHARE of each free range)
from the splits of the models, so no chosen subgoal sits on a knife edge between two leaves; and with a
neighbourhood (a share of each free range, the size of the execution noise: the binding's `[evaluation]
neighbourhood`) the optimizers minimize the worst predicted sum within it around a choice, so they stop
choosing a dip of the models narrower than the robot can hit (a subgoal whose next action's planned path
changes word a few degrees away).

Beyond duration (Ch. 8.1): the objective may be a weighted sum of measures (`objective_grammar`: duration +
0.3 * energy), each action then one term per weighted measure, its model scaled by the weight; and limits on
measures (`error=0.05`) keep every action's predicted measure within its bound the way a success model keeps
predicted success: a choice that breaks one is invalid (Term.valid). Where no choice keeps a bound, the
refined sequence says so (`RefinedSequence.violations`) instead of hiding it.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Mapping

import numpy as np

from tailor.refinement.action_sequence import ActionSequence, ExecutableAction
from tailor.errors import ArgumentValueError, DataError, ModelFileError
from tailor.refinement.models.features import feature_space
from tailor.refinement.objective_grammar import DURATION, DURATION_ONLY, MeasureBound, WeightedObjective
from tailor.refinement.optimizers import DEFAULT_OPTIMIZER, FreeParameter, Objective, OptimizationResult, Term, optimize
from tailor.refinement.optimizers.objective import scaled
from tailor.progress import progress_bar
from tailor.sims.protocol import FeatureSpace

# of each free range, kept from every split of the models: 0.031 rad of a full heading range, 4 cm of 8 m (a
# mobile base's noise: 1 deg, 1 cm)
MARGIN_SHARE = 0.005
# lambda of the user-facing default (CLI, API, evaluate): expected duration + lambda * uncertainty, chosen by
# `tailor evaluate --risk-sweep` on a bundled domain (README, "Risk-aware refinement"); it applies where every
# model stores its uncertainty (`resolve_risk`). The core `refine` defaults to 0: the dissertation's objective.
DEFAULT_RISK = 1.0
MAX_RISK = 1e6  # seconds of spread charged a million times over already rank by spread alone; beyond, overflow

if TYPE_CHECKING:  # the models' module imports scikit-learn; refining needs only their methods
    from tailor.refinement.models.action_models import ActionModel


@dataclass(frozen=True)
class RefinedSequence:
    """A fully bound action sequence with its predicted durations and how each window was optimized."""

    sequence: ActionSequence
    predicted: tuple[float, ...]  # per action, seconds
    windows: tuple[OptimizationResult, ...]
    horizon: int
    risk: float = 0.0  # lambda of the objective: expected duration + lambda * uncertainty
    spread: tuple[float, ...] | None = None  # per action, its model's uncertainty (s); None where one has none
    neighbourhood: float = 0.0  # share of each free range whose worst predicted case was minimized (0: the point)
    window_actions: tuple[int, ...] = ()  # per window, the index of the action whose parameters it fixed
    # per window, the same objective minimized by the optimizer `refine(compare=...)` names (evaluation: the
    # choices of two optimizers on the same windows); () where none was asked for
    compared: tuple[OptimizationResult, ...] = ()
    objective: WeightedObjective = DURATION_ONLY  # what the windows minimized (Ch. 8.1)
    limits: tuple[MeasureBound, ...] = ()  # bounds on every action's predicted measures
    # per action, every measure its model predicts at the chosen values (duration first), checked; () where none
    measures: tuple[Mapping[str, float], ...] = ()
    violations: tuple[Violation, ...] = ()  # the limits no choice kept (empty: every one holds)

    @property
    def predicted_total(self) -> float:
        return float(sum(self.predicted))

    def measure_total(self, measure: str) -> float | None:
        """A measure predicted for the whole sequence (summed over its actions); None where an action's model
        does not predict it."""
        if measure == DURATION:
            return self.predicted_total
        if not self.measures or any(measure not in m for m in self.measures):
            return None
        return float(sum(m[measure] for m in self.measures))


@dataclass(frozen=True)
class Violation:
    """A limit refinement could not keep: no choice within the action's free ranges keeps its predicted
    measure within the bound (the best choice found breaks it)."""

    index: int  # position of the action in the sequence
    step: int  # its plan step (ExecutableAction.step)
    action: str
    measure: str
    predicted: float
    bound: float

    def reason(self) -> str:
        return (f"step {self.step} {self.action}: no subgoal within its ranges keeps the predicted {self.measure} "
                f"<= {self.bound:g} (the best choice found: {self.predicted:.4g})")

    def to_json(self) -> dict:
        return {"step": self.step, "action": self.action, "measure": self.measure,
                "predicted": self.predicted, "bound": self.bound}


class LastBatch:
    """A row-wise function (here an action's features) that computes each distinct row of a batch once and
    reuses the rows of the batch before: the genetic algorithm's offspring keep many parents' values of the
    parameters one action reads, and a neighbourhood repeats the point for every free parameter that action
    does not read. Same output as the function itself; worth it where features are costly (a path planned
    per row). Rows are told apart by a 64-bit hash of their bits (sorting numbers is faster than sorting rows
    of bytes), and every row found alike is checked to be equal, bit for bit, before its value is reused."""

    def __init__(self, function):
        self.function = function
        self.keys = np.empty(0, dtype=np.uint64)  # the last batch's distinct rows' hashes (sorted) ...
        self.params: np.ndarray | None = None  # ... the rows themselves ...
        self.rows: np.ndarray | None = None  # ... and their values

    def __call__(self, params: np.ndarray) -> np.ndarray:
        params = np.ascontiguousarray(params, dtype=float)
        if params.ndim != 2 or not len(params):
            return self.function(params)
        keys, first, inverse = _distinct(_row_hashes(params))
        distinct = params[first]
        if not np.array_equal(distinct[inverse].view(np.uint64), params.view(np.uint64)):  # a hash collision
            self.keys, self.params, self.rows = np.empty(0, dtype=np.uint64), None, None
            distinct_rows = np.unique(params.view(np.dtype((np.void, params.itemsize * params.shape[1]))).ravel(),
                                      return_index=True, return_inverse=True)
            return np.asarray(self.function(params[distinct_rows[1]]))[distinct_rows[2].ravel()]
        rows = None
        if self.rows is not None and self.params.shape[1] == params.shape[1]:
            at = np.minimum(np.searchsorted(self.keys, keys), len(self.keys) - 1)
            known = (self.keys[at] == keys) & np.all(self.params[at].view(np.uint64) == distinct.view(np.uint64),
                                                      axis=1)
            if known.any():
                rows = np.empty((len(keys),) + self.rows.shape[1:], dtype=self.rows.dtype)
                rows[known] = self.rows[at[known]]
                if not known.all():
                    rows[~known] = self.function(distinct[~known])
        if rows is None:
            rows = np.asarray(self.function(distinct))
        self.keys, self.params, self.rows = keys, distinct, rows
        return rows[inverse]


def _distinct(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """np.unique(keys, return_index=True, return_inverse=True) without its stable sort: the index of some
    occurrence of each distinct key, not necessarily the first (rows alike are the same rows)."""
    order = np.argsort(keys)
    ordered = keys[order]
    new = np.empty(len(keys), dtype=bool)
    new[:1] = True
    np.not_equal(ordered[1:], ordered[:-1], out=new[1:])
    inverse = np.empty(len(keys), dtype=np.intp)
    inverse[order] = np.cumsum(new) - 1
    return ordered[new], order[new], inverse


_HASH_MULTIPLIERS = np.random.default_rng(0x5EED).integers(1, 2**63, size=64, dtype=np.uint64) * 2 + 1  # odd


def _row_hashes(params: np.ndarray) -> np.ndarray:
    """A 64-bit hash of each row's bits: rows differing in one value always differ; otherwise alike by chance
    (2^-64), which LastBatch checks."""
    bits = params.view(np.uint64)
    multipliers = np.resize(_HASH_MULTIPLIERS, bits.shape[1])
    with np.errstate(over="ignore"):
        hashes = (bits * multipliers).sum(axis=1, dtype=np.uint64)
        return hashes ^ (hashes >> np.uint64(29))


def action_term(action: ExecutableAction, model: ActionModel, free: tuple[FreeParameter, ...],
                assignment: Mapping[str, float], success_model=None, risk: float = 0.0,
                shared: dict | None = None) -> Term:
    """The predicted duration of one action as a function of the window's free parameters.

    Parameters already fixed (bound, or chosen in an earlier window) are baked in; the others are read from
    the columns of theta. With `risk` > 0 the term is the duration plus risk times the model's uncertainty
    (a ModelFileError if its file has none). With a `success_model` (the action's guard) the term is invalid
    where it predicts failure (Alg. 6), and its success leaves are the region the analytic optimizer
    intersects with. Terms built with the same `shared` dict and model share one feature batch and one
    duration model (Objective.cost evaluates them in one call each).
    """
    column = {p.id: j for j, p in enumerate(free)}
    base = np.empty(len(action.params))
    free_slots: list[tuple[int, int]] = []
    for k, param in enumerate(action.params):
        if not param.free:
            base[k] = param.value
        elif param.id in column:
            free_slots.append((k, column[param.id]))
            base[k] = np.nan
        else:
            base[k] = assignment[param.id]

    def params(theta: np.ndarray) -> np.ndarray:
        theta = np.atleast_2d(theta)
        out = np.repeat(base[None, :], len(theta), axis=0)
        for k, j in free_slots:
            out[:, k] = theta[:, j]
        return out

    if shared is None:
        shared = {}
    if id(model) not in shared:  # (the model kept too, so its id is not reused while the dict lives)
        shared[id(model)] = model, LastBatch(model.features), model.duration_with_risk(risk)
    _, derive, duration = shared[id(model)]

    def features(theta: np.ndarray) -> np.ndarray:
        return derive(params(theta))

    # the action's parameters over a box of theta: the fixed values, and each free slot's column of the box
    space_bounds, why = _bounds_of(model)
    enclosure = None if space_bounds is None else (lambda lo, hi: space_bounds(params(lo), params(hi)))
    reads = tuple(sorted({j for _, j in free_slots}))
    if success_model is None:
        return Term(model=duration, features=features, label=action.pddl, inputs=params, derive=derive,
                    feature_bounds=enclosure, no_bounds=why, reads=reads)
    margin = [0.0] * len(free)
    for _, j in free_slots:
        margin[j] = action.guard_margin * (free[j].high - free[j].low)

    def valid(theta: np.ndarray) -> np.ndarray:
        """Success predicted at theta and, with a margin, that far to either side of every free value used."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        ok = np.asarray(success_model.predict_success(params(theta)), dtype=bool)
        for _, j in free_slots if action.guard_margin else ():
            for sign in (-1.0, 1.0):
                moved = theta.copy()
                moved[:, j] = np.clip(moved[:, j] + sign * margin[j], free[j].low, free[j].high)
                ok &= np.asarray(success_model.predict_success(params(moved)), dtype=bool)
        return ok

    region_bounds, _ = _bounds_of(success_model)
    return Term(model=duration, features=features, label=action.pddl, valid=valid,
                region=success_model, region_features=lambda theta: success_model.features(params(theta)),
                region_margin=tuple(margin), inputs=params, derive=derive, feature_bounds=enclosure,
                region_bounds=None if region_bounds is None else (lambda lo, hi: region_bounds(params(lo), params(hi))),
                no_bounds=why, reads=reads)


def action_terms(action: ExecutableAction, model: ActionModel, free: tuple[FreeParameter, ...],
                 assignment: Mapping[str, float], success_model=None, risk: float = 0.0, shared: dict | None = None,
                 objective: WeightedObjective = DURATION_ONLY, limits: tuple[MeasureBound, ...] = ()
                 ) -> tuple[Term, ...]:
    """One action's share of a window's objective: a term per measure the objective weighs (its model, plus
    `risk` times its spread, scaled by the weight), sharing one feature batch; the first carries the validity
    (the guard's predicted success, and every limit kept). The duration alone is `action_term` itself."""
    base = action_term(action, model, free, assignment, success_model, risk, shared)
    if objective.plain and not limits:
        return (base,)
    terms = []
    for measure, weight in objective.weights:
        if weight > 0:
            term = replace(base, model=scaled(model.measure_with_risk(measure, risk), weight),
                           label=base.label if measure == DURATION else f"{base.label} {measure}")
            if terms:  # validity and the success region belong to the action, once
                term = replace(term, valid=None, region=None, region_features=None, region_margin=(),
                               region_bounds=None)
            terms.append(term)
    if limits:
        terms[0] = replace(terms[0], valid=_keeping(base, model, limits))
    return tuple(terms)


def _keeping(base: Term, model: ActionModel, limits: tuple[MeasureBound, ...]):
    """theta -> whether the action of term `base` keeps every limit at theta (and `base.valid` holds)."""
    trees = [(model.tree_of(limit.measure), limit.bound) for limit in limits]
    guard = base.valid

    def valid(theta: np.ndarray) -> np.ndarray:
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        if not len(theta):
            return np.ones(0, dtype=bool)
        features = base.derive(base.inputs(theta))
        ok = np.ones(len(theta), dtype=bool) if guard is None else np.asarray(guard(theta), dtype=bool)
        for tree, bound in trees:
            with np.errstate(over="ignore", invalid="ignore"):
                ok &= np.asarray(tree.predict(features), dtype=float) <= bound
        return ok

    return valid


def limit_term(action: ExecutableAction, model: ActionModel, free: tuple[FreeParameter, ...],
               assignment: Mapping[str, float], limits: tuple[MeasureBound, ...], success_model=None) -> Term:
    """Only the validity of an action beyond the horizon: its limits kept (and its guard's success)."""
    term = guard_term(action, model, free, assignment, success_model) if success_model is not None else None
    base = action_term(action, model, free, assignment, success_model)
    if term is None:
        term = replace(base, model=_NO_DURATION, features=lambda theta: np.zeros((len(np.atleast_2d(theta)), 1)),
                       inputs=None, derive=None, reads=(), no_bounds="",
                       feature_bounds=lambda lo, hi: (np.zeros((len(lo), 1)), np.zeros((len(lo), 1))))
    return replace(term, valid=_keeping(base, model, limits), label=f"limits of {action.pddl}")


def _bounds_of(model) -> tuple[object | None, str]:
    """The enclosure its feature space declares for a model's features (FeatureSpace.bounds: boxes of action
    parameters to boxes of features), or None and why not."""
    try:  # a model's own FeatureSpace where it offers one (a generated space carries its bounds), else its name
        space = getattr(model, "space", None)
    except DataError:
        space = None
    if not isinstance(space, FeatureSpace):
        space = getattr(model, "feature_space", None)
    if isinstance(space, str):
        try:
            space = feature_space(space)
        except DataError:
            return None, f"feature space {space!r} is not known here"
    if not isinstance(space, FeatureSpace):
        return None, f"the model of {getattr(model, 'action', 'the action')} names no feature space"
    if space.bounds is None:
        return None, f"feature space {space.name!r} declares no bounds"
    return space.bounds, ""


class _NoDuration:
    """A term that adds nothing to the predicted duration: one rule covering everything, zero linear model."""

    def predict(self, features: np.ndarray) -> np.ndarray:
        return np.zeros(len(np.atleast_2d(features)))

    def rules(self) -> list:
        from tailor.refinement.models.rules import Rule

        return [Rule(np.array([-np.inf]), np.array([np.inf]), np.zeros(1), 0.0)]


_NO_DURATION = _NoDuration()


def guard_term(action: ExecutableAction, model: ActionModel, free: tuple[FreeParameter, ...],
               assignment: Mapping[str, float], success_model) -> Term:
    """Only the validity of a guarded action beyond the horizon (its duration is not part of this window)."""
    term = action_term(action, model, free, assignment, success_model)
    return replace(term, model=_NO_DURATION, features=lambda theta: np.zeros((len(np.atleast_2d(theta)), 1)),
                   label=f"guard of {action.pddl}", inputs=None, derive=None, reads=(),
                   feature_bounds=lambda lo, hi: (np.zeros((len(lo), 1)), np.zeros((len(lo), 1))), no_bounds="")


def guard_for(action: ExecutableAction, success_models: Mapping[str, object] | None):
    """The success classifier an action's parameters must satisfy (Alg. 6), or None if it has no guard."""
    if not action.guard:
        return None
    if success_models is None or action.guard not in success_models:
        raise ModelFileError(f"step {action.step} {action.action} is guarded by success model {action.guard!r}, "
                             "which is not loaded")
    return success_models[action.guard]


def predicted_success(sequence: ActionSequence, success_models: Mapping[str, object] | None) -> tuple[bool, ...]:
    """Per action of a bound sequence: does its guard predict success (True where it has none)?"""
    out = []
    for action in sequence.actions:  # at the chosen values (the margin is the optimizers' concern)
        guard = guard_for(action, success_models)
        out.append(True if guard is None else bool(guard.predict_success(action.values()[None, :])[0]))
    return tuple(out)


def resolve_risk(risk: float | None, models) -> float:
    """The risk lambda to refine with. None asks for DEFAULT_RISK, which applies only where every one of
    `models` stores its uncertainty (else 0, with a warning naming the file: an old model folder still refines,
    plainly); an explicit lambda > 0 needs the uncertainty (a ModelFileError naming the file otherwise)."""
    models = list(models)
    if risk is None:
        lacking = [m for m in models if getattr(m, "uncertainty", None) is None]
        if DEFAULT_RISK and lacking:
            where = getattr(lacking[0], "source", None) or lacking[0].action
            logging.getLogger(__name__).warning(
                "%s: no uncertainty stored (trained before it was): refining without the default risk %g, i.e. "
                "with --risk 0 (retrain with `tailor train`)", where, DEFAULT_RISK)
            return 0.0
        return DEFAULT_RISK
    check_risk(risk)
    if risk:
        for model in models:
            model.require_uncertainty()
    return float(risk)


def is_neighbourhood(share) -> bool:
    """Whether `share` is a neighbourhood: a number, a share of each free range in [0, 0.5)."""
    return not isinstance(share, bool) and isinstance(share, (int, float)) and 0.0 <= share < 0.5


def check_neighbourhood(share: float) -> None:
    """An ArgumentValueError unless `share` is a neighbourhood (is_neighbourhood)."""
    if not is_neighbourhood(share):
        raise ArgumentValueError(f"the neighbourhood must be a share of each free range in [0, 0.5), not {share!r}")


def check_risk(risk: float) -> None:
    """A risk lambda must be a number from 0 (plain expected duration) to MAX_RISK."""
    if isinstance(risk, bool) or not isinstance(risk, (int, float)) or not 0.0 <= risk <= MAX_RISK:
        raise ArgumentValueError(f"the risk lambda must be a number from 0 to {MAX_RISK:g}, not {risk!r}")


def model_for(action: ExecutableAction, models: Mapping[str, ActionModel]) -> ActionModel:
    try:
        return models[action.action]
    except KeyError:
        raise ModelFileError(f"no action model for executable action {action.action!r} "
                             f"(step {action.step}, {action.pddl})") from None


def _predicted(action: ExecutableAction, model: ActionModel) -> float:
    """The model's prediction for the bound action, checked: an absurd model (not finite, far outside the
    durations seen in training) stops here with a ModelFileError naming its file; below 0 s is clipped."""
    value = float(model.predict_duration(action.values()[None, :])[0])
    check = getattr(model, "check_duration", None)  # duck-typed models (tests, plug-ins) may not check
    return check(value, f"step {action.step} {action.action}") if check else value


def predicted_durations(sequence: ActionSequence, models: Mapping[str, ActionModel]) -> tuple[float, ...]:
    """The checked predicted duration (s) of each action of a fully bound sequence."""
    return tuple(_predicted(a, model_for(a, models)) for a in sequence.actions)


def predicted_spreads(sequence: ActionSequence, models: Mapping[str, ActionModel]) -> tuple[float, ...] | None:
    """Each action's uncertainty (s) at its bound values, or None if a model stores none."""
    spreads = []
    for action in sequence.actions:
        model = model_for(action, models)
        if getattr(model, "uncertainty", None) is None:
            return None
        spreads.append(float(model.predict_spread(action.values()[None, :])[0]))
    return tuple(spreads)


def refine(sequence: ActionSequence, models: Mapping[str, ActionModel], horizon: int = 2,
           method: str = DEFAULT_OPTIMIZER, seed: int = 0, success_models: Mapping[str, object] | None = None,
           risk: float = 0.0, margin_share: float = MARGIN_SHARE, neighbourhood: float = 0.0,
           compare: str | None = None, objective: WeightedObjective = DURATION_ONLY,
           limits: tuple[MeasureBound, ...] = ()) -> RefinedSequence:
    """Bind every free parameter of `sequence`, h actions at a time, minimizing summed predicted duration
    (plus `risk` times the summed uncertainty), each choice `margin_share` of its range from the models' splits;
    with `neighbourhood` > 0, the worst of that sum within that share of each free range around a choice.

    Guarded actions (subgoal assertion) take their success classifier from `success_models` by name: the
    optimizers consider only parameterizations it predicts to succeed (Alg. 6). With `compare` (an optimizer's
    name), each window's objective is also minimized by that optimizer (`RefinedSequence.compared`; the windows
    still take `method`'s choices): two optimizers judged on the same windows. `objective` weighs the measures
    summed (default: the duration alone); `limits` bound every action's predicted measures (a ModelFileError
    naming the file where an action's model lacks a measure either names). A limit no choice keeps is reported
    in `violations`.
    """
    if horizon < 1:
        raise ValueError("the horizon must be at least 1")
    check_risk(risk)
    if not 0.0 <= margin_share < 0.5:
        raise ValueError(f"the margin must be a share of a free range in [0, 0.5), not {margin_share!r}")
    check_neighbourhood(neighbourhood)
    actions = sequence.actions
    if risk:  # every model the sequence uses must know its uncertainty: say so before any work
        for action in actions:
            model_for(action, models).require_uncertainty()
    limits = tuple(limits)
    check_measures(actions, models, objective, limits)
    assignment: dict[str, float] = {}
    windows: list[OptimizationResult] = []
    acted: list[int] = []
    compared: list[OptimizationResult] = []
    steps = progress_bar(iterable=range(len(actions)), desc=f"refining (h={horizon})", unit="action", leave=False)
    for i in steps:
        window = optimize_window(actions, i, horizon, assignment, models, method, seed, success_models, risk,
                                 margin_share, neighbourhood, objective, limits)
        if window is None:
            continue  # action i's subgoal is already fixed; nothing of it to choose in this window
        window_objective, result = window
        windows.append(result)
        acted.append(i)
        if compare is not None:
            compared.append(result if result.method == compare
                            else optimize(window_objective, method=compare, seed=seed + i))
        chosen = dict(zip((p.id for p in window_objective.free), result.values))
        for p in actions[i].params:  # fix what action i uses; later subgoals are optimized again
            if p.id in chosen:
                assignment[p.id] = float(chosen[p.id])
    bound = sequence.bind(assignment)
    measures = predicted_measures(bound, models)
    return RefinedSequence(sequence=bound, predicted=predicted_durations(bound, models), windows=tuple(windows),
                           horizon=horizon, risk=float(risk), spread=predicted_spreads(bound, models),
                           neighbourhood=float(neighbourhood), window_actions=tuple(acted), compared=tuple(compared),
                           objective=objective, limits=limits, measures=measures,
                           violations=limit_violations(bound, models, limits))


def check_measures(actions, models: Mapping[str, ActionModel], objective: WeightedObjective = DURATION_ONLY,
                   limits: tuple[MeasureBound, ...] = ()) -> None:
    """A ModelFileError naming the file of the first action model that lacks a measure the objective weighs or
    a limit bounds (before any work: the models of every action of the sequence)."""
    if not isinstance(objective, WeightedObjective):
        raise ArgumentValueError(f"the objective must be a WeightedObjective, not {type(objective).__name__}")
    named = [m for m in (*objective.measures, *(limit.measure for limit in limits)) if m != DURATION]
    for action in actions:
        model = model_for(action, models)
        for measure in named:
            model.tree_of(measure)


def predicted_measures(sequence: ActionSequence, models: Mapping[str, ActionModel]
                       ) -> tuple[Mapping[str, float], ...]:
    """Per action of a bound sequence, every measure its model predicts (duration first), each checked as a
    duration is (an absurd prediction is a ModelFileError naming the file); () where a model is duck-typed
    without measures (tests, plug-ins)."""
    out = []
    for action in sequence.actions:
        model = model_for(action, models)
        names = getattr(model, "measure_names", None)
        if names is None:
            return ()
        values = action.values()[None, :]
        where = f"step {action.step} {action.action}"
        out.append({name: model.check_measure(name, float(model.predict_measure(name, values)[0]), where)
                    for name in names})
    return tuple(out)


def limit_violations(sequence: ActionSequence, models: Mapping[str, ActionModel],
                     limits: tuple[MeasureBound, ...]) -> tuple[Violation, ...]:
    """The limits a bound sequence breaks, per action, at its (unchecked, unclipped) predictions: what the
    optimizers' validity tests too."""
    out = []
    for index, action in enumerate(sequence.actions):
        model = model_for(action, models)
        for limit in limits:
            value = float(model.predict_measure(limit.measure, action.values()[None, :])[0])
            if not value <= limit.bound:
                out.append(Violation(index, action.step, action.action, limit.measure, value, limit.bound))
    return tuple(out)


def optimize_window(actions: tuple[ExecutableAction, ...], i: int, horizon: int, assignment: Mapping[str, float],
                    models: Mapping[str, ActionModel], method: str = DEFAULT_OPTIMIZER, seed: int = 0,
                    success_models: Mapping[str, object] | None = None, risk: float = 0.0,
                    margin_share: float = MARGIN_SHARE, neighbourhood: float = 0.0,
                    objective: WeightedObjective = DURATION_ONLY, limits: tuple[MeasureBound, ...] = ()
                    ) -> tuple[Objective, OptimizationResult] | None:
    """The window of `horizon` actions from action i, its free parameters not in `assignment` optimized (seed
    `seed + i`): the objective and its optimum; None where action i has nothing left to choose. One step of
    `refine`, and what closed-loop execution re-optimizes from a measured state (receding horizon). With
    `limits`, an action beyond the horizon that shares a free parameter joins as a validity-only term, as a
    guarded one does: a choice must leave it a way to keep its limits."""
    window = actions[i:i + horizon]
    free: list[FreeParameter] = []
    seen: set[str] = set()

    def take(action: ExecutableAction) -> None:
        for p in action.params:
            if p.free and p.id not in assignment and p.id not in seen:
                seen.add(p.id)
                free.append(FreeParameter(p.id, p.low, p.high))

    for action in window:
        take(action)
    if not any(p.free and p.id not in assignment for p in actions[i].params):
        return None
    # a guarded action beyond the horizon that shares a free parameter still constrains it (Alg. 6): it joins as
    # a validity-only term, its other open parameters chosen with the window's (not fixed yet)
    beyond = [a for a in actions[i + horizon:]
              if (a.guard or limits) and any(p.id in seen for p in a.params if p.free)]
    for action in beyond:
        take(action)
    free_t = tuple(free)
    margin = tuple(margin_share * (p.high - p.low) for p in free_t)
    radius = tuple(neighbourhood * (p.high - p.low) for p in free_t) if neighbourhood else ()

    def objective_with(kept: Mapping[int, tuple[MeasureBound, ...]]) -> Objective:
        """The window's objective, each action k (of window + beyond) keeping the limits kept[k]."""
        shared: dict = {}  # one feature batch and duration model per action model of the window
        terms = tuple(term for k, a in enumerate(window)
                      for term in action_terms(a, model_for(a, models), free_t, assignment,
                                               guard_for(a, success_models), risk, shared, objective, kept[k]))
        terms += tuple(limit_term(a, model_for(a, models), free_t, assignment, kept[k], guard_for(a, success_models))
                       if kept[k] else guard_term(a, model_for(a, models), free_t, assignment,
                                                  guard_for(a, success_models))
                       for k, a in enumerate(beyond, start=len(window)))
        return Objective(free=free_t, terms=terms, margin=margin, neighbourhood=radius)

    everyone = dict.fromkeys(range(len(window) + len(beyond)), tuple(limits))
    summed = objective_with(everyone)
    result = optimize(summed, method=method, seed=seed + i)
    if limits and not summed.valid(np.array([result.values]))[0]:
        relaxed, notes = _attainable_limits((*window, *beyond), models, free_t, assignment, limits, method, seed + i)
        if notes:  # a limit no choice keeps: keep the least of that measure attainable, minimize the rest
            summed = objective_with(relaxed)
            result = optimize(summed, method=method, seed=seed + i)
            result = replace(result, note="; ".join([*notes, result.note]))
    return summed, result


RELAXED_SHARE = 0.05  # a limit no choice keeps is relaxed to the least attainable value plus this share of the
# measure's spread over the window's choices (a bound at the least alone leaves a sliver the optimizers miss)
SPREAD_SAMPLES = 256  # seeded uniform choices the spread is estimated on


def _attainable_limits(actions, models: Mapping[str, ActionModel], free: tuple[FreeParameter, ...],
                       assignment: Mapping[str, float], limits: tuple[MeasureBound, ...], method: str, seed: int
                       ) -> tuple[dict[int, tuple[MeasureBound, ...]], list[str]]:
    """Per action (by position), its limits with each one no choice of the window's free values keeps raised to
    the least value of its measure the window can attain (plus RELAXED_SHARE of its spread), and a note per raised
    one: the window then chooses as precisely as it can there, instead of among choices that all break a limit."""
    kept, notes = {}, []
    low, high = np.array([p.low for p in free]), np.array([p.high for p in free])
    sample = np.random.default_rng(seed).uniform(low, high, size=(SPREAD_SAMPLES, len(free)))
    for k, action in enumerate(actions):
        model = model_for(action, models)
        base = action_term(action, model, free, assignment)
        own = []
        for limit in limits:
            tree = model.tree_of(limit.measure)
            least = optimize(Objective(free, (replace(base, model=tree),)), method=method, seed=seed).cost
            if least > limit.bound:
                with np.errstate(over="ignore", invalid="ignore"):
                    values = np.asarray(tree.predict(base.derive(base.inputs(sample))), dtype=float)
                spread = float(np.nanmax(values) - least) if np.isfinite(values).any() else 0.0
                bound = least + RELAXED_SHARE * max(spread, 0.0) + 1e-12 * (1.0 + abs(least))
                notes.append(f"no choice keeps step {action.step}'s {limit.measure} <= {limit.bound:g}: kept at "
                             f"<= {bound:.4g}, near the least attainable {least:.4g}")
                own.append(MeasureBound(limit.measure, bound))
            else:
                own.append(limit)
        kept[k] = tuple(own)
    return kept, notes
