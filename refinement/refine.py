"""Subgoal refinement (Sec. 5.4): choose the free parameters so the summed predicted duration is minimal.

The sequence is refined h actions at a time (the horizon): at action i the still-free parameters of
actions i..i+h-1 are optimized for the sum of their predicted durations, then the ones action i uses are
fixed and the window moves on. h = 1 is the greedy baseline of Sec. 5.5.1: each subgoal is chosen for the
action that reaches it only.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Mapping

import numpy as np

from tailor.refinement.action_sequence import ActionSequence, ExecutableAction
from tailor.errors import ModelFileError
from tailor.refinement.optimizers import FreeParameter, Objective, OptimizationResult, Term, optimize
from tailor.refinement.progress import progress_bar

if TYPE_CHECKING:  # the models' module imports scikit-learn; refining needs only their methods
    from tailor.refinement.models.action_models import ActionModel


@dataclass(frozen=True)
class RefinedSequence:
    """A fully bound action sequence with its predicted durations and how each window was optimized."""

    sequence: ActionSequence
    predicted: tuple[float, ...]  # per action, seconds
    windows: tuple[OptimizationResult, ...]
    horizon: int

    @property
    def predicted_total(self) -> float:
        return float(sum(self.predicted))


def action_term(action: ExecutableAction, model: ActionModel, free: tuple[FreeParameter, ...],
                assignment: Mapping[str, float]) -> Term:
    """The predicted duration of one action as a function of the window's free parameters.

    Parameters already fixed (bound, or chosen in an earlier window) are baked in; the others are read from
    the columns of theta.
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

    def features(theta: np.ndarray) -> np.ndarray:
        theta = np.atleast_2d(theta)
        params = np.repeat(base[None, :], len(theta), axis=0)
        for k, j in free_slots:
            params[:, k] = theta[:, j]
        return model.features(params)

    return Term(model=model.duration, features=features, label=action.pddl)


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


def refine(sequence: ActionSequence, models: Mapping[str, ActionModel], horizon: int = 2,
           method: str = "analytic", seed: int = 0) -> RefinedSequence:
    """Bind every free parameter of `sequence`, h actions at a time, minimizing summed predicted duration."""
    if horizon < 1:
        raise ValueError("the horizon must be at least 1")
    actions = sequence.actions
    assignment: dict[str, float] = {}
    windows: list[OptimizationResult] = []
    steps = progress_bar(iterable=range(len(actions)), desc=f"refining (h={horizon})", unit="action", leave=False)
    for i in steps:
        window = actions[i:i + horizon]
        free: list[FreeParameter] = []
        seen: set[str] = set()
        for action in window:
            for p in action.params:
                if p.free and p.id not in assignment and p.id not in seen:
                    seen.add(p.id)
                    free.append(FreeParameter(p.id, p.low, p.high))
        if not any(p.free and p.id not in assignment for p in actions[i].params):
            continue  # action i's subgoal is already fixed; nothing of it to choose in this window
        free_t = tuple(free)
        terms = tuple(action_term(a, model_for(a, models), free_t, assignment) for a in window)
        result = optimize(Objective(free=free_t, terms=terms), method=method, seed=seed + i)
        windows.append(result)
        chosen = dict(zip((p.id for p in free_t), result.values))
        for p in actions[i].params:  # fix what action i uses; later subgoals are optimized again
            if p.id in chosen:
                assignment[p.id] = float(chosen[p.id])
    bound = sequence.bind(assignment)
    return RefinedSequence(sequence=bound, predicted=predicted_durations(bound, models), windows=tuple(windows),
                           horizon=horizon)
