"""What a binding and a belief file make of a planned problem, said before anything moves (`tailor check`, and
the warnings `tailor refine` prints): the free parameters with their ranges, every belief value and whether
anything reads it, and what looks like a mistake.

A binding reads a quantity from the belief only through a fact that holds in the initial state (Alg. 3): a
`read` on a predicate that is not true initially reads nothing, the belief's value goes unused, and the
object's position becomes a free parameter that refinement will choose (a shelf moved onto the robot's path).
"""

from __future__ import annotations

from dataclasses import dataclass

from tailor.planner_bridge import INITIAL, AbstractPlan
from tailor.refinement.action_sequence import ActionSequence
from tailor.refinement.belief import BeliefState
from tailor.refinement.binding import Binding
from tailor.refinement.instantiate import instantiate


@dataclass(frozen=True)
class BeliefUse:
    """One value of the belief file and whether instantiation read it."""

    object: str
    quantity: str
    value: float
    read: bool


@dataclass(frozen=True)
class TaskCheck:
    """The instantiated sequence of a planned problem, the belief values it read, and the warnings."""

    sequence: ActionSequence
    belief: tuple[BeliefUse, ...]
    warnings: tuple[str, ...]

    def to_json(self) -> dict:
        return {"free_parameters": [{"id": p.id, "low": p.low, "high": p.high}
                                    for p in self.sequence.free_parameters()],
                "belief": [{"object": b.object, "quantity": b.quantity, "value": b.value, "read": b.read}
                           for b in self.belief],
                "warnings": list(self.warnings)}


class _RecordingBelief:
    """A belief state that notes every value instantiation asks it for."""

    def __init__(self, belief: BeliefState):
        self.belief, self.file, self.objects, self.read = belief, belief.file, belief.objects, set()

    def value(self, obj: str, quantity: str, needed_by: str = "") -> float:
        self.read.add((obj.lower(), quantity))
        return self.belief.value(obj, quantity, needed_by)


def check_task(plan: AbstractPlan, binding: Binding, belief: BeliefState) -> TaskCheck:
    """Instantiate `plan` (Alg. 3) noting what it reads from `belief`, and say what looks wrong: a belief value
    nothing reads, a quantity the belief gives that is left free, a `read` on a fact that is not initially true."""
    recording = _RecordingBelief(belief)
    sequence = instantiate(plan, binding, recording)
    uses = tuple(BeliefUse(obj, quantity, value, (obj, quantity) in recording.read)
                 for obj, values in sorted(belief.objects.items()) for quantity, value in values.items())
    where = belief.file or "the belief"
    warnings = []
    if not plan.steps:  # the goal holds initially: nothing runs, nothing needs the belief
        return TaskCheck(sequence, uses, ())
    free = {p.id.lower(): p for p in sequence.free_parameters()}
    for use in uses:
        if use.read:
            continue
        parameter = free.get(f"{use.object}.{use.quantity}")
        if parameter is not None:
            warnings.append(f"{use.object}.{use.quantity} is free in [{parameter.low:g}, {parameter.high:g}] and "
                            f"refinement will choose it, although {where} gives {use.quantity} = {use.value:g}: no "
                            f"fact true initially reads it (see [predicates] read in {binding.file})")
        else:
            warnings.append(f"[objects.{use.object}] {use.quantity} = {use.value:g} in {where} is never read")
    initially = {fact[0].lower() for fact in plan.initial}
    initially |= {link.fact[0].lower() for link in plan.links if link.producer == INITIAL}
    achieved: dict[str, str] = {}  # predicate -> a fact of it a step achieves, where none holds initially
    for link in plan.links:
        predicate = binding.predicate(link.fact[0])
        if predicate is not None and predicate.read and predicate.name not in initially:
            achieved.setdefault(predicate.name, f"({' '.join(link.fact)}), achieved by step {link.producer}")
    for name, example in achieved.items():
        warnings.append(f"[predicates.{name}] read = {list(binding.predicate(name).read)} reads nothing: no "
                        f"({name} ...) fact is true initially (e.g. {example}), so the quantities it would read "
                        f"are free ({binding.file})")
    return TaskCheck(sequence, uses, tuple(warnings))
