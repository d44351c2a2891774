"""The abstract plan: steps, causal links and orderings of a partial-order plan (Sec. 5.2, Fig. 5.6).

Step ids are 1..n in a valid sequential order; producer 0 is the initial state; consumer "goal" is the goal.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Union

INITIAL = 0
GOAL = "goal"

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
        """The VHPOP-like text rendering of Fig. 5.6 (see planner_bridge.text)."""
        from tailor.planner_bridge.text import render_text

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
