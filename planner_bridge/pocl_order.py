"""Least commitment for a finished POCL plan: the fewest orderings its steps need (a post-pass, documented).

The search commits early: it picks each causal link's producer, and each threat's side (promotion or
demotion), when the partial plan is still small, so the finished plan may order steps that need no order.
This post-pass keeps the plan's steps and chooses again, over the whole plan at once, the producer of every
precondition and goal literal (any step that achieves it, or the initial state) and the side of every threat
those links have. Among the choices whose orderings are acyclic it finds the one with the fewest ordered pairs
of steps (the transitive closure; ties: the fewest orderings after transitive reduction): a depth-first
branch and bound with propagation (a choice with one option left is made at once, as VHPOP's flaw selection
delays threats that may resolve themselves; the choice with the fewest options is branched on; options are
tried cheapest first), starting from the search's own choices as the incumbent, so the result is never more
ordered than the search's plan. A node limit (not a clock) bounds it, so the same plan gives the same result.
Steps that then support no causal link are dropped (plan justification) and the pass is repeated.

Every orderings set it returns keeps each producer before its consumer and each threatening step outside the
link, so every linearization is a valid plan: the same soundness argument as the search's, checked again
by pocl.flaws_of.
"""

from __future__ import annotations

from tailor.planner_bridge.pocl import GOAL, INIT, PartialPlan, _ordered
from tailor.planner_bridge.pocl_ground import GroundTask

NODE_LIMIT = 4000  # branch-and-bound nodes per pass; the first dive (cheapest options first) is already greedy


def pairs(before: tuple[int, ...]) -> int:
    """The ordered pairs of steps (the initial state and the goal left out) in the closure `before`."""
    return sum((before[s] >> 2).bit_count() for s in range(2, len(before)))


def reduced_orderings(before: tuple[int, ...]) -> int:
    """How many orderings between steps the transitive reduction of the closure `before` has."""
    count = 0
    for later in range(2, len(before)):
        earlier = before[later] >> 2 << 2
        implied = 0
        for step in range(2, len(before)):
            if earlier >> step & 1:
                implied |= before[step]
        count += (earlier & ~implied).bit_count()
    return count


class _Reorder:
    """One branch-and-bound pass over the steps of a plan; `best` holds (pairs, reduced, before, links)."""

    def __init__(self, task: GroundTask, steps: tuple[int, ...], node_limit: int):
        self.steps = steps
        self.node_limit = node_limit
        self.nodes = 0
        count = len(steps)
        self.needs = [(literal, GOAL) for literal in task.goal]
        self.needs += [(p, s) for s in range(2, count) for p in task.actions[steps[s]].preconditions]
        self.options = []
        for literal, consumer in self.needs:
            producers = [INIT] if task.initially(literal) else []
            producers += [s for s in range(2, count) if s != consumer and literal in task.actions[steps[s]].effects]
            self.options.append(producers)
        self.negators: dict[int, list[int]] = {}
        for literal, _ in self.needs:
            self.negators.setdefault(
                literal, [t for t in range(2, count) if literal ^ 1 in task.actions[steps[t]].effects])
        self.best: tuple | None = None

    def base(self) -> tuple[int, ...]:
        """The closure with only the initial state before every step and every step before the goal."""
        count = len(self.steps)
        everything = sum(1 << s for s in range(2, count)) | 1 << INIT
        return tuple(0 if s == INIT else everything if s == GOAL else 1 << INIT for s in range(count))

    # --- one choice --------------------------------------------------------------------------------------
    def link(self, before, need: int, producer: int, threats: tuple):
        """The closure and pending threats after linking need `need` from `producer`; None if cyclic."""
        literal, consumer = self.needs[need]
        if producer != INIT and consumer != GOAL:
            before = _ordered(before, producer, consumer)
            if before is None:
                return None
        new = tuple((producer, consumer, t) for t in self.negators[literal] if t not in (producer, consumer))
        return before, threats + new

    @staticmethod
    def sides(before, threat) -> list[tuple[int, int]] | None:
        """The orderings that would resolve a threat (producer, consumer, threat step); None when resolved."""
        producer, consumer, step = threat
        if before[producer] >> step & 1 or before[step] >> consumer & 1:
            return None
        options = []
        if producer != INIT and not before[step] >> producer & 1:
            options.append((step, producer))  # demotion
        if consumer != GOAL and not before[consumer] >> step & 1:
            options.append((consumer, step))  # promotion
        return options

    def feasible_producers(self, before, need: int) -> list[int]:
        """Producers of the need that can precede its consumer and whose threats each keep a side open."""
        literal, consumer = self.needs[need]
        found = []
        for producer in self.options[need]:
            if producer != INIT and consumer != GOAL and before[producer] >> consumer & 1:
                continue  # the consumer already precedes the producer
            if all(self.sides(before, (producer, consumer, t)) != [] for t in self.negators[literal]
                   if t not in (producer, consumer)):
                found.append(producer)
        return found

    # --- search ------------------------------------------------------------------------------------------
    def offer(self, before, chosen) -> None:
        """Keep a complete choice if it is strictly less committed than the best so far."""
        score = (pairs(before), reduced_orderings(before))
        if self.best is None or score < self.best[:2]:
            links = tuple((producer, *self.needs[need]) for need, producer in enumerate(chosen))
            self.best = (*score, before, links)

    def run(self, before, chosen: tuple, threats: tuple) -> None:
        """Depth-first branch and bound from a partial choice (`chosen[k]` is -1 while need k is open)."""
        self.nodes += 1
        if self.nodes > self.node_limit:
            return
        while True:  # propagation: make every choice that has one option left
            branch, branch_options, changed = None, None, False
            pending = []
            for threat in threats:
                options = self.sides(before, threat)
                if options is None:
                    continue
                if not options:
                    return
                if len(options) == 1:
                    before = _ordered(before, *options[0])
                    if before is None:
                        return
                    changed = True
                    continue
                pending.append(threat)
                if branch_options is None or len(options) < len(branch_options):
                    branch, branch_options = ("threat", threat), options
            threats = tuple(pending)
            for need, producer in enumerate(chosen):
                if producer != -1:
                    continue
                options = self.feasible_producers(before, need)
                if not options:
                    return
                if len(options) == 1:
                    result = self.link(before, need, options[0], threats)
                    if result is None:
                        return
                    before, threats = result
                    chosen = chosen[:need] + (options[0],) + chosen[need + 1:]
                    changed = True
                    continue
                if branch_options is None or len(options) < len(branch_options):
                    branch, branch_options = ("need", need), options
            if not changed:
                break
        if self.best is not None and pairs(before) > self.best[0]:
            return  # the closure only grows below this node
        if branch is None:
            self.offer(before, chosen)
            return
        children = []
        for option in branch_options:
            if branch[0] == "threat":
                child = _ordered(before, *option)
                if child is not None:
                    children.append((pairs(child), child, chosen, tuple(t for t in threats if t != branch[1])))
            else:
                result = self.link(before, branch[1], option, threats)
                if result is not None:
                    grown = chosen[:branch[1]] + (option,) + chosen[branch[1] + 1:]
                    children.append((pairs(result[0]), result[0], grown, result[1]))
        for _, child, grown, pending in sorted(children, key=lambda c: c[0]):  # stable: earlier options first
            self.run(child, grown, pending)


def reorder(task: GroundTask, plan: PartialPlan, node_limit: int = NODE_LIMIT,
            stats: dict | None = None) -> PartialPlan:
    """The plan's steps with every causal link's producer and every threat's side chosen again for the fewest
    ordered pairs of steps (then the fewest reduced orderings); `plan`'s own choices are the first incumbent,
    so the result is never more ordered (and is `plan`'s links and orderings when nothing is less ordered).
    `stats`, if given, receives the nodes searched and whether the search finished (the result is optimal)."""
    search = _Reorder(task, plan.steps, node_limit)
    by_need = {(literal, consumer): producer for producer, literal, consumer in plan.links}
    search.offer(plan.before, tuple(by_need[need] for need in search.needs))
    search.run(search.base(), (-1,) * len(search.needs), ())
    if stats is not None:
        stats.update(nodes=search.nodes, exact=search.nodes <= node_limit)
    _, _, before, links = search.best
    return PartialPlan(plan.steps, before, links, (), ())


def least_commitment(task: GroundTask, plan: PartialPlan, node_limit: int = NODE_LIMIT,
                     stats: dict | None = None) -> PartialPlan:
    """`reorder`, then without the steps that support no causal link, repeated until every step does;
    `stats` as for reorder (nodes summed over the passes, exact when every pass finished)."""
    if stats is not None:
        stats.update(nodes=0, exact=True)
    while True:
        one: dict = {}
        plan = reorder(task, plan, node_limit, one)
        if stats is not None:
            stats.update(nodes=stats["nodes"] + one["nodes"], exact=stats["exact"] and one["exact"])
        useless = {s for s in range(2, len(plan.steps)) if not any(link[0] == s for link in plan.links)}
        if not useless:
            return plan
        plan = _without(plan, useless)


def _without(plan: PartialPlan, dropped: set[int]) -> PartialPlan:
    """The plan without the `dropped` steps (which produce no link): their links and orderings go, the
    closure restricted to the other steps stays transitive and keeps every other link safe."""
    kept = [s for s in range(len(plan.steps)) if s not in dropped]
    number = {old: new for new, old in enumerate(kept)}

    def renumbered(mask: int) -> int:
        return sum(1 << number[old] for old in kept if mask >> old & 1)

    before = tuple(renumbered(plan.before[old]) for old in kept)
    links = tuple((number[p], literal, number[c]) for p, literal, c in plan.links if c in number)
    return PartialPlan(tuple(plan.steps[s] for s in kept), before, links, (), ())


def sequence_plan(task: GroundTask, actions: list[int]) -> PartialPlan:
    """A valid sequence of ground actions as a totally ordered PartialPlan, each need linked from the latest
    earlier step achieving it (else the initial state): what deordering starts from, so that least_commitment
    can be applied to another planner's sequence for comparison (planner_bridge.benchmark)."""
    steps = (-1, -1, *actions)
    count = len(steps)
    before = [0, sum(1 << s for s in range(count)) & ~(1 << GOAL)]
    before += [(1 << s) - 1 & ~(1 << GOAL) for s in range(2, count)]
    links = []
    for consumer in [*range(2, count), GOAL]:
        needs = task.goal if consumer == GOAL else task.actions[steps[consumer]].preconditions
        last = count if consumer == GOAL else consumer
        for literal in needs:
            producer = next((s for s in range(last - 1, 1, -1) if literal in task.actions[steps[s]].effects), INIT)
            links.append((producer, literal, consumer))
    return PartialPlan(steps, tuple(before), tuple(links), (), ())
