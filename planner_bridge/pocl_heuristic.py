"""Heuristics of the POCL planner: VHPOP's additive cost of a partial plan's open conditions (Younes & Simmons
2003, after Bonet & Geffner's h_add), with and without counting the steps already in the plan."""

from __future__ import annotations

import math
from collections.abc import Callable

from tailor.planner_bridge.pocl_ground import GroundTask


def additive_costs(task: GroundTask) -> list[float]:
    """h_add of every literal from the initial state: 0 if it holds there, else the cheapest achiever's
    1 + the summed costs of its preconditions (deletes ignored); infinite when unreachable."""
    cost = [0.0 if task.initially(literal) else math.inf for literal in range(2 * len(task.facts))]
    changed = True
    while changed:  # Bellman-Ford style: the tasks are small, a few sweeps settle every cost
        changed = False
        for action in task.actions:
            total = 1.0 + sum(cost[p] for p in action.preconditions)
            if total == math.inf:
                continue
            for literal in action.effects:
                if total < cost[literal]:
                    cost[literal] = total
                    changed = True
    return cost


def reusable(plan, achieves: Callable[[int, int], bool], literal: int, consumer: int) -> bool:
    """Whether a step already in `plan` (not the initial state) achieves `literal` and may precede `consumer`."""
    return any(
        achieves(step, literal) and step != consumer and not plan.precedes(consumer, step)
        for step in range(2, len(plan.steps))
    )


def add(plan, costs: list[float], achieves) -> float:
    """ADD: the additive costs of the distinct open-condition literals."""
    return sum(costs[literal] for literal in {literal for literal, _ in plan.open_conditions})


def add_reuse(plan, costs: list[float], achieves) -> float:
    """ADDR: as ADD, but an open condition an existing step could support costs nothing."""
    needed = {literal for literal, consumer in plan.open_conditions if not reusable(plan, achieves, literal, consumer)}
    return sum(costs[literal] for literal in needed)


HEURISTICS = {"add": add, "addr": add_reuse}
