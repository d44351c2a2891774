"""The plan as text that reads like VHPOP's output (Fig. 5.6): each step with the causal links that support
it, then the goal's links, then the ordering constraints of the partial order."""

from __future__ import annotations

from tailor.planner_bridge.abstract_plan import GOAL, INITIAL, AbstractPlan

LINK_INDENT = "    "


def _atom(words: tuple[str, ...]) -> str:
    return "(" + " ".join(words) + ")"


def render_text(plan: AbstractPlan) -> str:
    """Render `plan`; the initial line lists the initial facts the plan uses (those linked from step 0)."""
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
