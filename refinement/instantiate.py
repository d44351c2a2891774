"""Action instantiation (Algorithm 3): the abstract plan's steps become executable actions.

Each step's executable action comes from the binding; each parameter group takes the PDDL object of its bound
argument. An object's value per quantity is composed from every causal link whose fact mentions it: facts
that hold in the initial state (producer 0) read values from the belief state, all bound facts contribute
ranges (intersected), and the binding's type defaults apply where no predicate gives a range. A quantity with
a value is BOUND, otherwise FREE in its range, with id "object.quantity", shared by every action using it.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType

from tailor.planner_bridge.abstract_plan import INITIAL, AbstractPlan
from tailor.refinement.action_sequence import RANGE_TOLERANCE, ActionSequence, ExecutableAction, Parameter
from tailor.refinement.belief import BeliefState
from tailor.refinement.binding import DEFAULT_TYPE, Binding, PredicateBinding
from tailor.sims.protocol import GROUPS
from tailor.errors import BindingError, EmptyRangeError

OBJECT_PLACEHOLDER = "{object}"  # in a predicate's `scene`: one scene object per PDDL object it places
ObjectTypes = Mapping[str, "str | Sequence[str]"]  # object -> its type, or its type and ancestors


@dataclass(frozen=True)
class _Fact:
    """A fact on a causal link, with the binding of its predicate."""

    producer: int
    fact: tuple[str, ...]
    binding: PredicateBinding

    @property
    def text(self) -> str:
        return f"({' '.join(self.fact)})"


def instantiate(plan: AbstractPlan, binding: Binding, belief: BeliefState,
                object_types: ObjectTypes | None = None,
                initial_state: Iterable[Sequence[str]] = ()) -> ActionSequence:
    """Algorithm 3: the ActionSequence of `plan`, parameters bound from `belief` or free in composed ranges.

    `object_types` gives PDDL object types for the type defaults (default: those the plan carries, else the
    binding's only type); `initial_state` adds initial facts not on any causal link to those that place scene
    objects (default: the plan's initial facts).
    """
    if object_types is None and plan.objects:
        object_types = plan.object_types
    if not initial_state:
        initial_state = plan.initial
    facts = _facts_by_object(plan, binding)
    composed: dict[tuple[str, str], tuple[float | None, float, float]] = {}
    actions = []
    for step in sorted(plan.steps, key=lambda s: s.id):
        pddl = f"({' '.join((step.action, *step.args))})"
        bound = binding.action(step.action, step=f"{step.id} {pddl}")
        spec = bound.spec
        params = []
        for group in GROUPS:
            names, quantities = spec.group(group)
            if not names:
                continue
            index = bound.args[group]
            if index >= len(step.args):
                raise BindingError(f"[actions.{bound.pddl}] {group} = {index} is out of range for step "
                                   f"{step.id} {pddl} with {len(step.args)} argument(s)", file=binding.file)
            obj = step.args[index]
            for name, quantity in zip(names, quantities):
                key = (obj.lower(), quantity)
                if key not in composed:
                    types = type_chain(obj, binding, object_types)
                    on_links = facts.get(obj.lower(), ())
                    composed[key] = _compose(obj, quantity, on_links, types, binding, belief)
                value, low, high = composed[key]
                params.append(Parameter(f"{obj}.{quantity}", name, value, low, high))
        actions.append(ExecutableAction(step.id, pddl, bound.executable, tuple(params)))
    scene = _scene(plan, binding, belief, initial_state, object_types)
    return ActionSequence(plan.domain, plan.problem, tuple(actions), scene, binding.simulator)


def _facts_by_object(plan: AbstractPlan, binding: Binding) -> dict[str, list[_Fact]]:
    """Per object (lower case), the distinct bound facts on causal links that mention it."""
    out: dict[str, list[_Fact]] = {}
    for link in plan.links:
        predicate = binding.predicate(link.fact[0])
        if predicate is None:  # static or unbound predicates (next, visited) constrain nothing
            continue
        fact = _Fact(link.producer, tuple(link.fact), predicate)
        for obj in predicate.objects(link.fact, binding.file):
            entries = out.setdefault(obj.lower(), [])
            if fact not in entries:
                entries.append(fact)
    return out


def type_chain(obj: str, binding: Binding, object_types: ObjectTypes | None) -> tuple[str, ...]:
    """The type names whose defaults apply to `obj`, most specific first, ending with `default`."""
    declared = None if object_types is None else object_types.get(obj)
    if declared is None:
        named = [name for name in binding.types if name != DEFAULT_TYPE]
        chain: tuple[str, ...] = tuple(named) if len(named) == 1 else ()
    else:
        chain = (declared,) if isinstance(declared, str) else tuple(declared)
    return (*chain, DEFAULT_TYPE)


def _compose(obj: str, quantity: str, facts: Sequence[_Fact], types: Sequence[str], binding: Binding,
             belief: BeliefState) -> tuple[float | None, float, float]:
    """(value or None, low, high) of one quantity of one object, composed from the facts that mention it."""
    value, read_by = None, None
    low, high = float("-inf"), float("inf")
    sources = []
    for f in facts:
        if quantity in f.binding.ranges:
            lo, hi = f.binding.ranges[quantity]
            low, high = max(low, lo), min(high, hi)
            sources.append(f"{f.text} [{lo:g}, {hi:g}]")
        if f.producer == INITIAL and quantity in f.binding.read and value is None:
            # every read of an object's quantity comes from the same belief entry, so all reads agree
            value, read_by = belief.value(obj, quantity, needed_by=f"{f.text} in the initial state"), f.text
    if not sources:
        default = binding.type_range(types, quantity)
        if default is None:
            tried = ", ".join(f"[types.{t}]" for t in types)
            raise BindingError(f"no range for {obj}.{quantity}: no predicate on its causal links bounds "
                               f"'{quantity}' and none of {tried} defines it", file=binding.file)
        (low, high), where = default
        sources.append(f"{where} [{low:g}, {high:g}]")
    if low > high:
        raise EmptyRangeError(f"{obj}.{quantity}: the ranges {', '.join(sources)} do not intersect",
                              file=binding.file)
    if value is not None:
        _check_read(obj, quantity, value, read_by, (low, high), ", ".join(sources), belief)
        value = min(max(value, low), high)
    elif low == high:  # a degenerate range determines the value
        value = low
    return value, low, high


def _check_read(obj: str, quantity: str, value: float, read_by: str, bounds: tuple[float, float], where: str,
                belief: BeliefState) -> None:
    """An EmptyRangeError naming the belief file where a value read from it lies outside its range."""
    low, high = bounds
    if not (low - RANGE_TOLERANCE <= value <= high + RANGE_TOLERANCE):
        raise EmptyRangeError(f"{obj}.{quantity} = {value:g} read for {read_by} lies outside its range "
                              f"[{low:g}, {high:g}] from {where}", file=belief.file)


def scene_name(template: str, obj: str) -> str:
    """The scene object a fact places: the binding's `scene` name, or, for a template with "{object}" (one
    scene object per PDDL object, e.g. "crate {object}"), that name with the fact's object filled in."""
    return template.replace(OBJECT_PLACEHOLDER, obj)


def _scene(plan: AbstractPlan, binding: Binding, belief: BeliefState, initial_state: Iterable[Sequence[str]],
           object_types: ObjectTypes | None = None) -> Mapping[str, tuple[float, ...]]:
    """The scene objects placed by initial facts (robot pose, object positions), read from the belief state;
    each value within its object's type range where the binding gives one (a table placed a million metres
    away is a belief error, not a scene for the simulator)."""
    initial = [tuple(link.fact) for link in plan.links if link.producer == INITIAL]
    initial += [tuple(fact) for fact in initial_state]
    scene: dict[str, tuple[float, ...]] = {}
    placed_by: dict[str, str] = {}
    for fact in initial:
        predicate = binding.predicate(fact[0])
        if predicate is None or predicate.scene is None:
            continue
        text = f"({' '.join(fact)})"
        objects = predicate.objects(fact, binding.file)
        if len(objects) != 1:
            raise BindingError(f"[predicates.{predicate.name}] places scene object '{predicate.scene}' but "
                               f"{text} names {len(objects)} objects (set args to one index)",
                               file=binding.file)
        values = tuple(belief.value(objects[0], q, needed_by=f"{text} in the initial state")
                       for q in predicate.read)
        name = scene_name(predicate.scene, objects[0])
        if placed_by.get(name, text) != text:
            raise BindingError(f"scene object '{name}' placed twice in the initial state: "
                               f"{placed_by[name]} and {text}", file=binding.file)
        types = type_chain(objects[0], binding, object_types)
        for quantity, value in zip(predicate.read, values):
            default = binding.type_range(types, quantity)
            if default is None:
                continue
            _check_read(objects[0], quantity, value, text, *default, belief)
        scene.setdefault(name, values)
        placed_by.setdefault(name, text)
    return MappingProxyType(scene)
