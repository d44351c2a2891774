"""A partial-order causal-link planner in the spirit of VHPOP (Younes & Simmons 2003), on ground actions.

A partial plan holds steps, causal links, ordering constraints and its flaws: open conditions (a precondition
or goal literal with no causal link yet) and threats (a step that may fall inside a causal link and negate
its literal). Refinements close an open condition with a causal link from an existing step or a new step,
and resolve a threat by demotion (threat before the producer) or promotion (threat after the consumer).
Best-first search (weighted A*: f = steps + w * h) with the additive heuristic orders the partial plans;
a flaw selection strategy picks the one flaw refined at each node. Pruned: plans whose orderings would be
cyclic (never generated), plans with an open condition no step can ever achieve, and duplicate plans.
Least commitment: the engine (pocl_engine) lets the search look on past its first plan for others of no more
steps, puts each through the post-pass of planner_bridge.pocl_order and keeps the least ordered.
Every step id is a number: 0 is the initial state, 1 the goal, steps are 2, 3, ... in order of addition.
"""

from __future__ import annotations

import heapq
import itertools
import math
import time
from collections.abc import Callable
from dataclasses import dataclass

from tailor.planner_bridge.pocl_ground import GroundTask
from tailor.planner_bridge.pocl_heuristic import HEURISTICS, additive_costs

INIT, GOAL = 0, 1
Link = tuple[int, int, int]  # (producer step, literal, consumer step)


@dataclass(frozen=True, slots=True)
class PartialPlan:
    """Steps (ground action numbers; -1 for the initial state and the goal), the transitive closure of the
    orderings as bit masks (bit t of before[s] set: step t precedes step s), causal links and flaws."""

    steps: tuple[int, ...]
    before: tuple[int, ...]
    links: tuple[Link, ...]
    open_conditions: tuple[tuple[int, int], ...]  # (literal, consumer), oldest first
    threats: tuple[tuple[int, int], ...]  # (link index, threatening step)

    def precedes(self, first: int, second: int) -> bool:
        return bool(self.before[second] >> first & 1)

    def key(self) -> tuple:
        """Equal for plans with the same steps, orderings, causal links and open conditions (duplicates)."""
        return self.steps, self.before, frozenset(self.links), frozenset(self.open_conditions)


def _ordered(before: tuple[int, ...], first: int, second: int) -> tuple[int, ...] | None:
    """The closure with `first` before `second` added; None when that would make a cycle."""
    if first == second or before[first] >> second & 1:
        return None
    if before[second] >> first & 1:
        return before
    earlier, bit = before[first] | 1 << first, 1 << second
    return tuple(b | earlier if (s == second or b & bit) else b for s, b in enumerate(before))


class Planner:
    """Plan-space search over one ground task; `resolve_threats=False` exists only to show that it matters."""

    def __init__(self, task: GroundTask, heuristic: str = "addr", strategy: str = "lcfr", weight: float = 1.0,
                 resolve_threats: bool = True):
        self.task = task
        self.heuristic = HEURISTICS[heuristic]
        self.select = STRATEGIES[strategy]
        self.weight = weight
        self.resolve_threats = resolve_threats
        self.costs = additive_costs(task)
        self.achievers: dict[int, list[int]] = {}
        for number, action in enumerate(task.actions):
            for literal in sorted(action.effects):
                self.achievers.setdefault(literal, []).append(number)
        self.expanded = self.generated = 0

    # --- facts about steps -------------------------------------------------------------------------------
    def achieves(self, plan: PartialPlan, step: int, literal: int) -> bool:
        if step == INIT:
            return self.task.initially(literal)
        return step != GOAL and literal in self.task.actions[plan.steps[step]].effects

    def negates(self, plan: PartialPlan, step: int, literal: int) -> bool:
        return step > GOAL and literal ^ 1 in self.task.actions[plan.steps[step]].effects

    @staticmethod
    def threatens(plan: PartialPlan, step: int, link: Link) -> bool:
        """Whether `step` may fall between the link's producer and consumer (it negates the literal)."""
        producer, _, consumer = link
        if step in (producer, consumer):
            return False
        return not plan.precedes(step, producer) and not plan.precedes(consumer, step)

    # --- refinements -------------------------------------------------------------------------------------
    def initial_plan(self) -> PartialPlan:
        goal = tuple((literal, GOAL) for literal in self.task.goal)
        return PartialPlan((-1, -1), (0, 1 << INIT), (), goal, ())

    def _with_link(self, plan: PartialPlan, producer: int, literal: int, consumer: int, new_step: bool):
        """`plan` (its open condition already removed) with the causal link, its ordering and new threats."""
        before = _ordered(plan.before, producer, consumer) if producer != INIT else plan.before
        if before is None:
            return None
        link = (producer, literal, consumer)
        plan = PartialPlan(plan.steps, before, plan.links + (link,), plan.open_conditions, plan.threats)
        threats = plan.threats if new_step else self._live(plan, plan.threats)
        if self.resolve_threats:
            index = len(plan.links) - 1
            threats += tuple((index, s) for s in range(2, len(plan.steps)) if self.negates(plan, s, literal)
                             and self.threatens(plan, s, link))
            if new_step:
                threats += tuple((k, producer) for k, other in enumerate(plan.links[:-1])
                                 if self.negates(plan, producer, other[1]) and self.threatens(plan, producer, other))
        return PartialPlan(plan.steps, before, plan.links, plan.open_conditions, threats)

    def _live(self, plan: PartialPlan, threats) -> tuple[tuple[int, int], ...]:
        """The threats that orderings have not resolved yet."""
        return tuple((k, s) for k, s in threats if self.threatens(plan, s, plan.links[k]))

    def close(self, plan: PartialPlan, index: int) -> list[PartialPlan]:
        """Refinements of open condition `index`: a causal link from each existing step that can achieve it
        and precede its consumer, then from each new step whose action achieves it."""
        literal, consumer = plan.open_conditions[index]
        rest = plan.open_conditions[:index] + plan.open_conditions[index + 1:]
        base = PartialPlan(plan.steps, plan.before, plan.links, rest, plan.threats)
        children = [
            self._with_link(base, step, literal, consumer, new_step=False)
            for step in range(len(plan.steps))
            if self.achieves(plan, step, literal) and step != consumer and not plan.precedes(consumer, step)
        ]
        for number in self.achievers.get(literal, ()):
            step = len(plan.steps)
            before = plan.before + (1 << INIT,)
            before = before[:GOAL] + (before[GOAL] | 1 << step,) + before[GOAL + 1:]
            needs = tuple((p, step) for p in self.task.actions[number].preconditions)
            grown = PartialPlan(plan.steps + (number,), before, plan.links, rest + needs, plan.threats)
            children.append(self._with_link(grown, step, literal, consumer, new_step=True))
        return [child for child in children if child is not None]

    def resolve(self, plan: PartialPlan, index: int) -> list[PartialPlan]:
        """Refinements of threat `index`: demotion (the threat before the producer), promotion (after the consumer)."""
        link_index, step = plan.threats[index]
        producer, _, consumer = plan.links[link_index]
        children = []
        for first, second in ((step, producer), (consumer, step)):
            if INIT in (first, second) or GOAL in (first, second):
                continue
            before = _ordered(plan.before, first, second)
            if before is not None:
                ordered = PartialPlan(plan.steps, before, plan.links, plan.open_conditions, ())
                children.append(PartialPlan(plan.steps, before, plan.links, plan.open_conditions,
                                            self._live(ordered, plan.threats)))
        return children

    def refinements_of_open(self, plan: PartialPlan, literal: int, consumer: int) -> int:
        """How many refinements an open condition has (for least-cost flaw repair)."""
        reuse = sum(1 for s in range(len(plan.steps)) if self.achieves(plan, s, literal) and s != consumer
                    and not plan.precedes(consumer, s))
        return reuse + len(self.achievers.get(literal, ()))

    def refinements_of_threat(self, plan: PartialPlan, link_index: int, step: int) -> int:
        producer, _, consumer = plan.links[link_index]
        demote = producer != INIT and not plan.precedes(producer, step)
        promote = consumer != GOAL and not plan.precedes(step, consumer)
        return int(demote) + int(promote)

    # --- search ------------------------------------------------------------------------------------------
    def h(self, plan: PartialPlan) -> float:
        if any(self.costs[literal] == math.inf for literal, _ in plan.open_conditions):
            return math.inf
        return self.heuristic(plan, self.costs, lambda step, literal: self.achieves(plan, step, literal))

    def search(self, timeout: float | None = None, node_limit: int | None = None, alternatives: int = 0,
               improve: Callable[[PartialPlan], tuple[tuple, PartialPlan]] | None = None) -> SearchResult:
        """Weighted A* over partial plans (ties: the lower h, then the older plan). Without
        `improve` the first plan without flaws is returned. With it, the search goes on for `alternatives` more
        expansions (fewer if the time or node limit comes first), and every flawless plan of no more steps than
        the first goes through `improve` (a plan -> (score, improved plan)): the least score wins, the earliest
        plan on ties. The first plan's length is no bound on the others' f, as the heuristic is inadmissible."""
        start = time.monotonic()
        root = self.initial_plan()
        if self.h(root) == math.inf:
            return SearchResult("unsolvable", None, 0, 1)
        serial = itertools.count()
        frontier = [(self.weight * self.h(root), 0.0, next(serial), root)]
        seen = {root.key()}
        self.expanded, self.generated = 0, 1
        best, bound, stop, solutions = None, math.inf, math.inf, 0  # bound: the first plan's steps
        while frontier:
            if self.expanded >= stop:
                break  # no plan of no more steps than the first is left within the budget
            if timeout is not None and self.expanded % 64 == 0 and time.monotonic() - start > timeout:
                if best is not None:
                    break
                return SearchResult("timeout", None, self.expanded, self.generated)
            if node_limit is not None and self.generated > node_limit:
                if best is not None:
                    break
                return SearchResult("limit", None, self.expanded, self.generated)
            *_, plan = heapq.heappop(frontier)
            self.expanded += 1
            flaw = self.select(self, plan)
            if flaw is None:
                if improve is None:
                    return SearchResult("solved", plan, self.expanded, self.generated, 1)
                if len(plan.steps) - 2 <= bound:
                    solutions += 1
                    scored = improve(plan)
                    if best is None or scored[0] < best[0]:
                        best = scored
                    if bound == math.inf:
                        bound, stop = len(plan.steps) - 2, self.expanded + alternatives
                continue
            kind, index = flaw
            for child in self.close(plan, index) if kind == "open" else self.resolve(plan, index):
                key = child.key()
                if key in seen:
                    continue
                seen.add(key)
                h = self.h(child)
                if h == math.inf:
                    continue
                self.generated += 1
                g = len(child.steps) - 2
                heapq.heappush(frontier, (g + self.weight * h, h, next(serial), child))
        if best is not None:
            return SearchResult("solved", best[1], self.expanded, self.generated, solutions)
        return SearchResult("unsolvable", None, self.expanded, self.generated)


@dataclass(frozen=True)
class SearchResult:
    """The outcome of a search: status "solved", "unsolvable", "timeout" or "limit", the plan when solved."""

    status: str
    plan: PartialPlan | None
    expanded: int
    generated: int
    solutions: int = 0  # flawless plans the search met (more than 1 only when it looked for alternatives)


def least_cost_flaw_repair(planner: Planner, plan: PartialPlan):
    """LCFR (Joslin & Pollack 1994): the flaw with the fewest refinements; ties go to threats, then to the
    newest flaw. A flaw with none is chosen at once: the plan is a dead end."""
    best, best_key = None, None
    for index, (link_index, step) in enumerate(plan.threats):
        key = (planner.refinements_of_threat(plan, link_index, step), 0, -index)
        if best_key is None or key < best_key:
            best, best_key = ("threat", index), key
    for index, (literal, consumer) in enumerate(plan.open_conditions):
        if best_key is not None and best_key[0] == 0:
            break  # a dead end: nothing beats it
        key = (planner.refinements_of_open(plan, literal, consumer), 1, -index)
        if best_key is None or key < best_key:
            best, best_key = ("open", index), key
    return best


def lifo(planner: Planner, plan: PartialPlan):
    """VHPOP's UCPOP-like order: the newest threat first, else the newest open condition."""
    if plan.threats:
        return "threat", len(plan.threats) - 1
    if plan.open_conditions:
        return "open", len(plan.open_conditions) - 1
    return None


STRATEGIES = {"lcfr": least_cost_flaw_repair, "lifo": lifo}


def linearization(plan: PartialPlan) -> list[int]:
    """The steps (without the initial state and goal) in one order the orderings allow: the oldest ready first."""
    order: list[int] = []
    placed = 1 << INIT | 1 << GOAL
    remaining = list(range(2, len(plan.steps)))
    while remaining:
        step = next(s for s in remaining if plan.before[s] & ~placed == 0)
        order.append(step)
        placed |= 1 << step
        remaining.remove(step)
    return order


def flaws_of(task: GroundTask, plan: PartialPlan) -> list[str]:
    """Check a finished plan independently of the search: every precondition and goal literal has one causal
    link from a step achieving it and ordered before; no step can fall inside a link and negate its literal.
    Then every linearization is a valid plan (the POCL soundness argument). Empty when the plan is sound."""
    problems = []
    needs = [(literal, GOAL) for literal in task.goal]
    needs += [(p, s) for s in range(2, len(plan.steps)) for p in task.actions[plan.steps[s]].preconditions]
    linked = sorted((literal, consumer) for _, literal, consumer in plan.links)
    if linked != sorted(needs):
        problems.append("the causal links do not support exactly the preconditions and goals")
    for producer, literal, consumer in plan.links:
        effects = task.actions[plan.steps[producer]].effects if producer > GOAL else None
        if (producer == INIT and not task.initially(literal)) or (effects is not None and literal not in effects):
            problems.append(f"step {producer} does not achieve {task.literal_text(literal)}")
        if producer != INIT and consumer != GOAL and not plan.precedes(producer, consumer):
            problems.append(f"step {producer} is not ordered before step {consumer}")
        for step in range(2, len(plan.steps)):
            negates = literal ^ 1 in task.actions[plan.steps[step]].effects
            if negates and Planner.threatens(plan, step, (producer, literal, consumer)):
                problems.append(f"step {step} threatens {producer} -> {task.literal_text(literal)} -> {consumer}")
    return problems
