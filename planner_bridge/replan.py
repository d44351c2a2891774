"""The symbolic side of closed-loop execution (Ch. 8.1): which facts hold after the steps executed so far, and
the same task posed again from facts that hold now, for the planner to plan from.

    effects = StepEffects(task)                  # the domain's effects of ground steps, from the task's texts
    facts = effects.after(plan.initial, done)    # the facts that hold after the executed steps `done`
    again = with_initial(task, facts)            # the task with those facts as its :init (same objects, goal)
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import replace

from tailor.errors import PlannerError
from tailor.planner_bridge.abstract_plan import Step
from tailor.planner_bridge.causal import ground_steps
from tailor.planner_bridge.ipc import PlanLine, _instance
from tailor.planner_bridge.reading import PDDLTask, parse_task
from tailor.planner_bridge.sexpr import SList, read_sexpr

Fact = tuple[str, ...]


class StepEffects:
    """The add and delete effects of ground steps of one task (parsed once with unified-planning)."""

    def __init__(self, task: PDDLTask):
        self.task = task
        self.problem = parse_task(task)
        self._cache: dict[tuple[str, tuple[str, ...]], tuple[frozenset[Fact], frozenset[Fact]]] = {}

    def of(self, step: Step) -> tuple[frozenset[Fact], frozenset[Fact]]:
        """(adds, deletes) of one ground step; a PlannerError for an action with conditional effects, whose
        effects depend on the state."""
        key = (step.action, tuple(step.args))
        if key not in self._cache:
            from unified_planning.plans import SequentialPlan

            line = PlanLine(step.action, tuple(step.args), step.id)
            ground = ground_steps(SequentialPlan([_instance(self.problem, line, str(self.task.problem))]))[0]
            if not ground.simple:
                raise PlannerError(f"step {step.id} ({step.action} {' '.join(step.args)}): closed-loop execution "
                                   "follows STRIPS effects only (this action's effects are conditional or "
                                   "quantified)", str(self.task.domain))
            self._cache[key] = frozenset(ground.adds), frozenset(ground.deletes)
        return self._cache[key]

    def after(self, initial: Iterable[Sequence[str]], steps: Sequence[Step]) -> frozenset[Fact]:
        """The facts that hold after `steps`, executed in order from `initial` (deletes before adds, as in PDDL)."""
        facts = {tuple(f) for f in initial}
        for step in steps:
            adds, deletes = self.of(step)
            facts = (facts - deletes) | adds
        return frozenset(facts)


def with_initial(task: PDDLTask, facts: Iterable[Sequence[str]]) -> PDDLTask:
    """`task` with `facts` as its initial state: the problem text's (:init ...) replaced (numeric assignments
    kept), everything else as written, so the planner plans again from what holds now."""
    root = read_sexpr(task.problem_text, str(task.problem))
    init = next((item for item in root.items if isinstance(item, SList) and item.head == ":init"), None)
    if init is None:
        raise PlannerError("the problem has no (:init ...) section to replan from", str(task.problem))
    start = _offset(task.problem_text, init.line, init.col)
    end = _closing(task.problem_text, start)
    kept = [_text(item) for item in init.items[1:] if isinstance(item, SList) and item.head == "="]
    atoms = [f"({' '.join(fact)})" for fact in sorted(tuple(f) for f in facts)]
    body = "(:init\n    " + "\n    ".join(atoms + kept) + ")"
    text = task.problem_text[:start] + body + task.problem_text[end + 1:]
    return replace(task, problem_text=text)


def _offset(text: str, line: int, col: int) -> int:
    """The index in `text` of 1-based (line, col)."""
    lines = text.split("\n")
    return sum(len(lines[k]) + 1 for k in range(line - 1)) + col - 1


def _closing(text: str, start: int) -> int:
    """The index of the ')' that closes the '(' at `start` (comments skipped)."""
    depth, i = 0, start
    while i < len(text):
        ch = text[i]
        if ch == ";":
            while i < len(text) and text[i] != "\n":
                i += 1
            continue
        if ch == "(":
            depth += 1
        elif ch == ")":
            depth -= 1
            if depth == 0:
                return i
        i += 1
    raise PlannerError("unbalanced (:init ...) section", None)


def _text(expr) -> str:
    if isinstance(expr, SList):
        return "(" + " ".join(_text(item) for item in expr.items) + ")"
    return expr.text
