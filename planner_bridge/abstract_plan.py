"""The abstract plan: steps, causal links and orderings of a partial-order plan (Sec. 5.2, Fig. 5.6).

Step ids are 1..n in a valid sequential order; producer 0 is the initial state; consumer "goal" is the goal.
The plan's two forms: JSON (to_json, from_json) and text that reads like VHPOP's output (render_text).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Union

INITIAL = 0
GOAL = "goal"
LINK_INDENT = "    "

Consumer = Union[int, str]  # a step id, or GOAL


@dataclass(frozen=True)
class Step:
    """One ground action of the plan, names as in the PDDL."""

    id: int
    action: str
    args: tuple[str, ...]


@dataclass(frozen=True)
class CausalLink:
    """`producer` achieves `fact` (predicate name, then arguments) for `consumer`."""

    producer: int
    fact: tuple[str, ...]
    consumer: Consumer


@dataclass(frozen=True)
class AbstractPlan:
    """A validated partial-order plan with its causal links, and what refinement needs of the problem it
    solves (so no later stage parses the PDDL again): each object with its type chain (most specific type
    first), and the facts that hold initially; and the chain of compilations the engine needed (if any)."""

    domain: str
    problem: str
    planner: str
    steps: tuple[Step, ...]
    links: tuple[CausalLink, ...]
    orderings: tuple[tuple[int, int], ...]
    objects: tuple[tuple[str, tuple[str, ...]], ...] = ()
    initial: tuple[tuple[str, ...], ...] = ()
    compilations: tuple[str, ...] = ()  # unified-planning compilations the problem went through, in order

    @property
    def object_types(self) -> dict[str, tuple[str, ...]]:
        """Object -> its type and the type's ancestors."""
        return {name: chain for name, chain in self.objects}

    def step(self, step_id: int) -> Step:
        return self.steps[step_id - 1]

    def links_to(self, consumer: Consumer) -> tuple[CausalLink, ...]:
        return tuple(link for link in self.links if link.consumer == consumer)

    def to_text(self) -> str:
        """The VHPOP-like text rendering of Fig. 5.6 (see render_text)."""
        return render_text(self)

    def to_json(self, facts: bool = False) -> dict:
        """The plan as JSON; with `facts`, also the problem's objects (with type chains) and initial facts."""
        data = {
            "domain": self.domain,
            "problem": self.problem,
            "planner": self.planner,
            "steps": [{"id": s.id, "action": s.action, "args": list(s.args)} for s in self.steps],
            "links": [{"from": k.producer, "fact": list(k.fact), "to": k.consumer} for k in self.links],
            "orderings": [list(o) for o in self.orderings],
        }
        if self.compilations:  # only when there were any: plans that needed none keep their JSON form
            data["compilations"] = list(self.compilations)
        if facts:
            data["objects"] = [{"name": name, "types": list(chain)} for name, chain in self.objects]
            data["initial"] = [list(fact) for fact in self.initial]
        return data

    @classmethod
    def from_json(cls, data: dict) -> "AbstractPlan":
        return cls(
            domain=data["domain"],
            problem=data["problem"],
            planner=data["planner"],
            steps=tuple(Step(int(s["id"]), s["action"], tuple(s["args"])) for s in data["steps"]),
            links=tuple(
                CausalLink(int(k["from"]), tuple(k["fact"]), k["to"] if k["to"] == GOAL else int(k["to"]))
                for k in data["links"]
            ),
            orderings=tuple((int(a), int(b)) for a, b in data["orderings"]),
            objects=tuple((o["name"], tuple(o["types"])) for o in data.get("objects", ())),
            initial=tuple(tuple(fact) for fact in data.get("initial", ())),
            compilations=tuple(data.get("compilations", ())),
        )


def _atom(words: tuple[str, ...]) -> str:
    return "(" + " ".join(words) + ")"


def render_text(plan: AbstractPlan) -> str:
    """The plan as text that reads like VHPOP's output (Fig. 5.6): each step with the causal links that support
    it, then the goal's links, then the ordering constraints of the partial order. The initial line lists the
    initial facts the plan uses (those linked from step 0)."""
    used: list[tuple[str, ...]] = []
    for link in plan.links:
        if link.producer == INITIAL and link.fact not in used:
            used.append(link.fact)
    lines = [f";; domain {plan.domain}, problem {plan.problem}, planner {plan.planner}"]
    if plan.compilations:
        lines[0] += ", compiled by " + " then ".join(plan.compilations)
    lines.append(f"Initial {INITIAL} : " + " ".join(_atom(f) for f in used))
    for step in plan.steps:
        lines.append(f"Step {step.id} : {_atom((step.action, *step.args))}")
        lines += [f"{LINK_INDENT}{link.producer} -> {_atom(link.fact)}" for link in plan.links_to(step.id)]
    lines.append("Goal :")
    lines += [f"{LINK_INDENT}{link.producer} -> {_atom(link.fact)}" for link in plan.links_to(GOAL)]
    lines.append("Orderings : " + (" ".join(f"{a}<{b}" for a, b in plan.orderings) or "none"))
    return "\n".join(lines) + "\n"
