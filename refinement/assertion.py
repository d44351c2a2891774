"""Subgoal assertion (Ch. 6, Algorithm 5): where an action's learned success classifier predicts failure from
the start state, insert a subgoal and a second action, so the action starts where it is predicted to succeed.

An action whose binding names a `success_model` (the executable action reused for a refined goal, e.g.
navigating to an object's pose without bumping it) is checked with that classifier from its start state:
- predicted to succeed (for some value of its free parameters): it is kept as it is, guarded (Alg. 6:
  refinement keeps its free parameters inside the predicted-success region);
- predicted to fail: the same executable action is used twice, start -> subgoal -> goal; the subgoal's
  parameters are free within the binding's default ranges of the goal object's type, and the second action
  is guarded, so refinement chooses the subgoal inside the predicted-success region (Sec. 6.2).
Given the duration models (`Detour`), a predicted failure is weighed against the detour before a subgoal is
asserted: the subgoal is asserted only where the predicted cost of failing (the failure probability times a
second attempt through the subgoal) exceeds the predicted cost of the detour (the two actions through the
subgoal, refined, against the plain action); elsewhere the plain action is kept (`Weighing`).
Every decision is kept as an `Assertion` (which plan step, which classifier, which leaf, why), and both new
actions carry the plan step they serve and their origin, so every transformed step leads back to the plan.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np

from tailor.errors import BindingError, ModelFileError
from tailor.refinement.action_sequence import ActionSequence, ExecutableAction, Parameter
from tailor.refinement.binding import Binding
from tailor.refinement.instantiate import ObjectTypes, type_chain
from tailor.refinement.optimizers import DEFAULT_OPTIMIZER
from tailor.refinement.refine import refine

GRID_POINTS = 4096  # at most this many points over an action's free parameters decide "predicted to succeed"
SUBGOAL = "subgoal"  # asserted subgoals are objects named subgoal<step> (subgoal<step>_<k> if that is taken)


@dataclass(frozen=True)
class Detour:
    """What weighing the detour needs: the duration models, and how the refine stage will choose the free values
    (the same optimizer, seed, risk lambda and neighbourhood), so the detour is predicted as it will be taken."""

    models: Mapping[str, object]
    optimizer: str = DEFAULT_OPTIMIZER
    seed: int = 0
    risk: float = 0.0
    neighbourhood: float = 0.0


@dataclass(frozen=True)
class Weighing:
    """A predicted failure weighed against the detour through a subgoal. Without the subgoal the plain action
    takes `plain` s and fails with `failure_probability`, and a failure costs a second attempt, through the
    subgoal (`asserted` s); with it the two actions take `asserted` s. The subgoal pays where
    failure_probability * asserted > asserted - plain (the expected cost of failing above the detour)."""

    failure_probability: float
    probability_source: str  # where the probability comes from (the classifier's leaf, its fresh episodes, ...)
    plain: float  # s, the plain action predicted (its free parameters refined)
    asserted: float  # s, the two actions through the subgoal predicted (refined, the second guarded)

    @property
    def detour(self) -> float:
        """s, what the subgoal adds to the predicted time (negative: the detour is predicted to be faster)."""
        return self.asserted - self.plain

    @property
    def failure_cost(self) -> float:
        """s, what a failure costs: the action made again, through the subgoal."""
        return self.asserted

    @property
    def expected_failure_cost(self) -> float:
        return self.failure_probability * self.failure_cost

    @property
    def pays(self) -> bool:
        return self.expected_failure_cost > self.detour

    def text(self) -> str:
        relation = ">" if self.pays else "<="
        return (f"expected cost of failing {self.failure_probability:.2f} x {self.failure_cost:.2f} s = "
                f"{self.expected_failure_cost:.2f} s {relation} detour {self.detour:+.2f} s ({self.asserted:.2f} s "
                f"through a subgoal against {self.plain:.2f} s plain; failure probability from "
                f"{self.probability_source})")

    def to_json(self) -> dict:
        return {"failure_probability": round(self.failure_probability, 4),
                "failure_probability_source": self.probability_source,
                "predicted_plain": round(self.plain, 4), "predicted_with_subgoal": round(self.asserted, 4),
                "detour": round(self.detour, 4), "failure_cost": round(self.failure_cost, 4),
                "expected_failure_cost": round(self.expected_failure_cost, 4), "subgoal_pays": self.pays}


@dataclass(frozen=True)
class Assertion:
    """One check of Algorithm 5: did the classifier predict failure for plan step `step`, and what was done."""

    step: int
    pddl: str
    action: str
    success_model: str
    predicted_success: bool  # from the start state, for some value of the free parameters
    success_share: float  # share of the free-parameter grid predicted to succeed (0 or 1 when all are bound)
    leaf: int  # the classifier's leaf reached by the instantiated parameters (the grid's first point if free)
    leaf_samples: int  # training episodes in that leaf
    subgoal: str = ""  # the asserted subgoal object ("" when none was inserted)
    weighing: Weighing | None = None  # failure against detour, where predicted to fail and the models were given

    @property
    def inserted(self) -> bool:
        return bool(self.subgoal)

    def reason(self) -> str:
        """One line: what the classifier predicted and what assertion did about it (and why)."""
        where = f"leaf {self.leaf} ({self.leaf_samples} training episodes)"
        if not self.predicted_success:
            fails = (f"{self.success_model} predicts failure from the start state ({where}, success predicted for "
                     "none of the free values)")
            weighed = "" if self.weighing is None else f"; {self.weighing.text()}"
            if self.inserted:
                return f"{fails}{weighed}: subgoal {self.subgoal} asserted"
            return f"{fails}{weighed}: no subgoal, the detour costs more than the predicted failure; plain action kept"
        share = "" if self.success_share in (0.0, 1.0) else f" for {100 * self.success_share:.0f}% of the free values"
        return f"{self.success_model} predicts success{share} ({where}): no subgoal; kept in the success region"

    def to_json(self) -> dict:
        return {"step": self.step, "pddl": self.pddl, "action": self.action, "success_model": self.success_model,
                "predicted_success": self.predicted_success, "success_share": round(self.success_share, 4),
                "leaf": self.leaf, "leaf_samples": self.leaf_samples, "inserted": self.inserted,
                "subgoal": self.subgoal or None,
                "weighing": None if self.weighing is None else self.weighing.to_json(), "reason": self.reason()}


@dataclass(frozen=True)
class AssertedSequence:
    """The sequence with asserted subgoals, and one Assertion per guarded plan step."""

    sequence: ActionSequence
    assertions: tuple[Assertion, ...]


def success_grid(action: ExecutableAction, points: int = GRID_POINTS) -> np.ndarray:
    """Parameter rows covering the action's free parameters with a regular grid (one row if none is free)."""
    free = action.free_parameters()
    per_axis = max(2, int(points ** (1.0 / len(free)))) if free else 1
    axes = [np.linspace(p.low, p.high, per_axis) for p in free]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(free)) if free else np.zeros((1, 0))
    rows = np.repeat(np.array([np.nan if p.free else p.value for p in action.params], dtype=float)[None], len(grid), 0)
    columns = [k for k, p in enumerate(action.params) if p.free]
    rows[:, columns] = grid
    return rows


def _subgoal_name(sequence: ActionSequence, step: int) -> str:
    taken = {p.id.split(".", 1)[0].lower() for a in sequence.actions for p in a.params}
    name, k = f"{SUBGOAL}{step}", 1
    while name.lower() in taken:
        k += 1
        name = f"{SUBGOAL}{step}_{k}"
    return name


def assert_subgoals(sequence: ActionSequence, binding: Binding, success_models: Mapping[str, object],
                    object_types: ObjectTypes | None = None, detour: Detour | None = None) -> AssertedSequence:
    """Algorithm 5 over every action of `sequence` whose PDDL action's binding names a success model; with
    `detour`, a subgoal only where the predicted failure costs more than the detour (Weighing), else every
    action predicted to fail gets one (Alg. 5 as the dissertation has it)."""
    actions: list[ExecutableAction] = []
    assertions: list[Assertion] = []
    current = sequence
    for action in sequence.actions:
        bound = binding.action(action.pddl.strip("()").split()[0], step=f"{action.step} {action.pddl}")
        if bound.success_model is None:
            actions.append(action)
            continue
        try:
            classifier = success_models[bound.success_model]
        except KeyError:
            raise ModelFileError(f"no success classifier {bound.success_model!r} loaded for step {action.step} "
                                 f"{action.pddl}") from None
        rows = success_grid(action)
        success = np.asarray(classifier.predict_success(rows), dtype=bool)
        leaf = int(classifier.leaf(rows[:1])[0])
        samples = int(classifier.tree.samples[leaf])
        check = Assertion(action.step, action.pddl, action.action, bound.success_model, bool(success.any()),
                          float(success.mean()), leaf, samples)
        if check.predicted_success:
            actions.append(replace(action, guard=bound.success_model, guard_margin=bound.success_margin))
        else:
            name = _subgoal_name(current, action.step)
            first, second = _split(action, bound, name, binding, object_types)
            second = replace(second, guard=bound.success_model, guard_margin=bound.success_margin)
            if detour is not None:
                check = replace(check, weighing=weigh(sequence, action, (first, second), classifier,
                                                      success_models, detour))
            if check.weighing is None or check.weighing.pays:
                check = replace(check, subgoal=name)
                why = f"asserted for step {action.step} {action.pddl}: {check.reason()}"
                first = replace(first, origin=f"to the subgoal; {why}")
                actions += [first, replace(second, origin=f"from the subgoal; {why}")]
                current = replace(current, actions=(*current.actions, first))  # the name is now taken
            else:  # the plain action, unguarded (its classifier predicts failure for all of its values)
                actions.append(action)
        assertions.append(check)
    return AssertedSequence(replace(sequence, actions=tuple(actions)), tuple(assertions))


def failure_probability(classifier, row: np.ndarray) -> tuple[float, str]:
    """The probability that the action fails with parameters `row`, and where it comes from: the classifier's own
    estimate where it makes one (a `failure_probability(params)` method, e.g. its leaf's share of failed training
    episodes tempered by the fresh ones there, CollisionModel); else the share that failed of the fresh episodes it
    predicted to fail (its report's confusion, Table 4.4); else 1, a failure taken as certain (every predicted
    failure then gets its subgoal, as in Alg. 5).
    The classifier's method returns the probabilities per row, or (probabilities, sources), or None where it has no
    estimate (a file without its leaves' counts)."""
    own = getattr(classifier, "failure_probability", None)
    estimate = own(row[None, :]) if callable(own) else None
    if estimate is not None:
        probability, source = estimate if isinstance(estimate, tuple) else (estimate, ("the classifier's leaf",))
        return float(np.asarray(probability, dtype=float)[0]), str(source[0])
    counts = ((getattr(classifier, "report", None) or {}).get("confusion") or {}).get("counts") or {}
    failed, succeeded = counts.get("predicted_fail_observed_fail"), counts.get("predicted_fail_observed_success")
    if isinstance(failed, int) and isinstance(succeeded, int) and failed + succeeded > 0:
        return (failed / (failed + succeeded),
                f"the classifier's fresh episodes ({failed} of the {failed + succeeded} predicted to fail failed)")
    return 1.0, "nowhere (no failure rate known: a failure taken as certain)"


def weigh(sequence: ActionSequence, action: ExecutableAction, pair: tuple[ExecutableAction, ExecutableAction],
          classifier, success_models: Mapping[str, object], detour: Detour) -> Weighing:
    """The plain `action` against the `pair` through a subgoal (its second action guarded), each refined alone as
    the refine stage will (the pair with h = 2, the subgoal in the predicted-success region), and the failure
    probability at the plain action's refined values."""
    options = {"method": detour.optimizer, "seed": detour.seed, "risk": detour.risk,
               "neighbourhood": detour.neighbourhood}
    plain = refine(replace(sequence, actions=(action,)), detour.models, horizon=1, **options)
    through = refine(replace(sequence, actions=pair), detour.models, horizon=2, success_models=success_models,
                     **options)
    probability, source = failure_probability(classifier, plain.sequence.actions[0].values())
    return Weighing(min(max(probability, 0.0), 1.0), source, plain.predicted_total, through.predicted_total)


def _split(action: ExecutableAction, bound, name: str, binding: Binding, object_types: ObjectTypes | None,
           ) -> tuple[ExecutableAction, ExecutableAction]:
    """start -> subgoal `name` -> goal: the subgoal's quantities free in the goal object's default ranges
    (or the ranges the action's binding gives for subgoals)."""
    spec = bound.spec
    n_observed = len(spec.observed)
    observed, internal = action.params[:n_observed], action.params[n_observed:]
    goal_object = internal[0].id.split(".", 1)[0] if internal else name
    types = type_chain(goal_object, binding, object_types)
    subgoal: dict[str, Parameter] = {}
    for quantity in spec.internal_quantities:
        default = binding.type_range(types, quantity)
        if quantity in bound.subgoal:
            default = bound.subgoal[quantity], f"[actions.{bound.pddl}] subgoal"
        if default is None:
            raise BindingError(f"subgoal assertion for step {action.step} {action.pddl}: no default range of "
                               f"'{quantity}' for the asserted subgoal (add it to [types.{types[0]}])",
                               file=binding.file)
        (low, high), _ = default
        if not (math.isfinite(low) and math.isfinite(high)):
            raise BindingError(f"subgoal assertion: the default range of '{quantity}' is unbounded", file=binding.file)
        subgoal[quantity] = Parameter(f"{name}.{quantity}", "", None, low, high)
    reaching = tuple(replace(subgoal[q], name=n) for n, q in zip(spec.internal, spec.internal_quantities))
    leaving = tuple(replace(subgoal[q], name=n) for n, q in zip(spec.observed, spec.observed_quantities))
    return replace(action, params=(*observed, *reaching)), replace(action, params=(*leaving, *internal))
