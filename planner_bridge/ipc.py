"""Plan files of any planner, in and out: the sequential IPC plan format, as Fast Downward writes `sas_plan`.

    (pick-up b3)
    (stack b3 b1)
    ; cost = 2 (unit cost)

Out: format_ipc writes one action a line in a valid linearization of our partial-order plan. In: read_ipc_plan
reads such a file (also `0.001: (name args) [1.000]` lines of timed plans, `;` comments, blank lines), each
malformed line one error naming file:line:col; plan_from_ipc matches its steps with the problem's actions and
objects, validates the plan with unified-planning's validator and links it (Sec. 5.2) into an AbstractPlan.
"""

from __future__ import annotations

import difflib
import heapq
import re
from dataclasses import dataclass
from pathlib import Path

from tailor.errors import PDDLSyntaxError, PlannerError
from tailor.planner_bridge.abstract_plan import GOAL, INITIAL, AbstractPlan, Step
from tailor.planner_bridge.reading import PDDLTask, parse_task, read_text
from tailor.planner_bridge.up_interop import GIVEN, link_plan

# A plan file larger than this is refused before it is read (about 300 000 steps of 25 characters).
MAX_PLAN_BYTES = 8 * 2**20
COMMENT = ";"
_NUMBER = r"(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?"
_TIMESTAMP = re.compile(rf"\s*({_NUMBER})\s*:\s*")  # `0.001:` before a timed plan's action
_AFTER = re.compile(rf"\s*(?:\[\s*{_NUMBER}\s*\]\s*)?")  # `[1.000]` after it: its duration


@dataclass(frozen=True)
class PlanLine:
    """One action of a plan file: its name and arguments (lower-cased, as PDDL is case-insensitive) and the
    line it is on (1-based)."""

    action: str
    args: tuple[str, ...]
    line: int

    def __str__(self) -> str:
        return "(" + " ".join((self.action, *self.args)) + ")"


# --- out ------------------------------------------------------------------------------------------------
def linearization(plan: AbstractPlan) -> tuple[Step, ...]:
    """The steps in an order every ordering and causal link of the plan allows; among the steps free to go
    next, the lowest id first (so a plan whose ids are already such an order keeps it)."""
    after: dict[int, set[int]] = {s.id: set() for s in plan.steps}
    edges = set(plan.orderings)
    edges |= {(k.producer, k.consumer) for k in plan.links if k.producer != INITIAL and k.consumer != GOAL}
    for a, b in edges:
        if a not in after or b not in after:
            raise PlannerError(f"the plan orders step {a} before step {b}, which it does not have")
        after[a].add(b)
    waiting = {s.id: 0 for s in plan.steps}
    for a, later in after.items():
        for b in later:
            waiting[b] += 1
    ready = [step_id for step_id, count in waiting.items() if count == 0]
    heapq.heapify(ready)
    order = []
    while ready:
        step_id = heapq.heappop(ready)
        order.append(plan.step(step_id))
        for b in after[step_id]:
            waiting[b] -= 1
            if waiting[b] == 0:
                heapq.heappush(ready, b)
    if len(order) != len(plan.steps):
        raise PlannerError("the plan's orderings form a cycle: it has no linearization")
    return tuple(order)


def format_ipc(plan: AbstractPlan) -> str:
    """The plan as a sequential IPC plan file (what Fast Downward writes to `sas_plan`): one `(action arg ...)`
    a line, lower case, in a valid linearization, then the unit cost."""
    lines = ["(" + " ".join((step.action, *step.args)).lower() + ")" for step in linearization(plan)]
    lines.append(f"{COMMENT} cost = {len(plan.steps)} (unit cost)")
    return "\n".join(lines) + "\n"


# --- in -------------------------------------------------------------------------------------------------
def read_ipc_plan(path: str | Path) -> tuple[PlanLine, ...]:
    """The actions of a plan file, in file order. A missing, unreadable, non-UTF-8 or too large file, or one that
    is not a regular file, is an InputFileError; a malformed line a PDDLSyntaxError naming it (file:line:col)."""
    return parse_ipc_plan(read_text(Path(path), MAX_PLAN_BYTES), str(path))


def parse_ipc_plan(text: str, file: str = "<plan>") -> tuple[PlanLine, ...]:
    """The actions of a plan file's text (see read_ipc_plan); `file` names it in errors. Timestamps, where
    given, must not decrease: the actions are taken in the order of the file."""
    actions, last_time = [], None
    for number, line in enumerate(text.splitlines(), start=1):
        parsed = _parse_line(line, file, number)
        if parsed is None:
            continue
        action, time = parsed
        if time is not None:
            if last_time is not None and time < last_time:
                raise PDDLSyntaxError(f"timestamp {time:g} is earlier than the one before it ({last_time:g}): "
                                      "a sequential plan lists its actions in order", file, number, 1)
            last_time = time
        actions.append(action)
    return tuple(actions)


def _parse_line(line: str, file: str, number: int) -> tuple[PlanLine, float | None] | None:
    """The action on one line and its timestamp (None when it has none), or None for a blank or comment line."""
    code = line.split(COMMENT, 1)[0].rstrip()

    def fail(message: str, at: int) -> PDDLSyntaxError:
        return PDDLSyntaxError(message, file, number, at + 1)

    start = len(code) - len(code.lstrip())
    if start == len(code):
        return None
    time = None
    stamp = _TIMESTAMP.match(code, start)
    if stamp:
        time, start = float(stamp.group(1)), stamp.end()
    if start == len(code):  # (a blank line ended above: this one had a timestamp alone)
        raise fail("expected an action '(name arg ...)' after the timestamp", start)
    if code[start] != "(":
        raise fail(f"expected an action '(name arg ...)', found {code[start:].split()[0]!r}", start)
    close = code.find(")", start)
    opened = code.find("(", start + 1)
    if 0 <= opened < close or (close < 0 and opened >= 0):
        raise fail("'(' inside an action: an action is '(name arg ...)' with names only", opened)
    if close < 0:
        raise fail("'(' not closed on this line: an action is one line, '(name arg ...)'", start)
    words = code[start + 1 : close].split()
    if not words:
        raise fail("empty action '()': an action is '(name arg ...)'", start)
    rest = _AFTER.match(code, close + 1).end()
    if rest < len(code):
        raise fail(f"unexpected {code[rest:].split()[0]!r} after the action: one action a line", rest)
    return PlanLine(words[0].lower(), tuple(w.lower() for w in words[1:]), number), time


def plan_from_ipc(task: PDDLTask, path: str | Path) -> AbstractPlan:
    """The partial-order plan with causal links of a plan file any planner wrote for the pair read by
    read_pddl: each line matched with the problem's actions and objects, the plan checked with unified-planning's
    validator and deordered (planner_bridge.up_interop.link_plan). An unknown action or object, a wrong number
    of arguments, an argument of the wrong type, or a plan the validator rejects is a PlannerError naming the
    plan file (and the line); a malformed file fails as read_ipc_plan says."""
    lines = read_ipc_plan(path)  # before the PDDL is parsed: a malformed plan file costs nothing more
    problem = parse_task(task)
    problem.environment.credits_stream = None  # no engine credits on stdout
    return link_lines(problem, lines, task.domain_name, str(path))


def link_lines(problem, lines: tuple[PlanLine, ...], domain: str, file: str) -> AbstractPlan:
    """The AbstractPlan of plan-file actions (see plan_from_ipc) for a unified-planning Problem."""
    from unified_planning.plans import SequentialPlan

    instances = [_instance(problem, line, file) for line in lines]
    plan = SequentialPlan(instances, problem.environment)
    try:
        return link_plan(problem, plan, domain=domain, planner=GIVEN)
    except PlannerError as exc:  # the validator rejected it: say where, and why, in the file's words
        try:
            explained = _rejection(problem, plan, lines, file)
        except Exception:  # explaining must not fail worse than the validator did: its own words then
            explained = None
        raise explained or PlannerError(exc.message, file) from None


def _instance(problem, line: PlanLine, file: str):
    """The unified-planning ActionInstance of one plan-file action, or a PlannerError naming its line."""
    from unified_planning.plans import ActionInstance

    def fail(message: str) -> PlannerError:
        return PlannerError(f"{line}: {message}", file, line.line)

    if not problem.has_action(line.action):
        names = [a.name for a in problem.actions]
        close = difflib.get_close_matches(line.action, names, n=1)
        hint = f"did you mean '{close[0]}'?" if close else f"the domain's actions: {', '.join(sorted(names))}"
        raise fail(f"unknown action '{line.action}' ({hint})")
    action = problem.action(line.action)
    if len(line.args) != len(action.parameters):
        wanted = " ".join(f"?{p.name} - {p.type}" for p in action.parameters) or "none"
        raise fail(f"{action.name} takes {len(action.parameters)} argument(s) ({wanted}), not {len(line.args)}")
    objects = []
    for position, (name, parameter) in enumerate(zip(line.args, action.parameters), start=1):
        if not problem.has_object(name):
            raise fail(f"unknown object '{name}' (argument {position}; not an object of the problem or a "
                       "constant of the domain)")
        obj = problem.object(name)
        if not parameter.type.is_compatible(obj.type):
            raise fail(f"argument {position}, {name}, is of type {obj.type}, not {parameter.type} "
                       f"(?{parameter.name} of {action.name})")
        objects.append(obj)
    return ActionInstance(action, tuple(objects))


def _rejection(problem, plan, lines: tuple[PlanLine, ...], file: str) -> PlannerError | None:
    """Why unified-planning's validator rejects the plan, naming the line of the first step that cannot be
    applied (with its conditions that do not hold) or the goals left unreached; None if it accepts it."""
    from unified_planning.engines import FailedValidationReason, ValidationResultStatus
    from unified_planning.model.walkers import StateEvaluator
    from unified_planning.shortcuts import PlanValidator

    with PlanValidator(problem_kind=problem.kind, plan_kind=plan.kind) as validator:
        result = validator.validate(problem, plan)
    if result.status == ValidationResultStatus.VALID:
        return None
    said = " ".join(" ".join(m.message for m in result.log_messages or ()).split())
    states = result.trace or []
    evaluator = StateEvaluator(problem)

    def unmet(conditions) -> str:
        """The conjuncts of `conditions` false in the last state reached, as PDDL ("" when none is)."""
        false = [c for c in _conjuncts(conditions) if not evaluator.evaluate(c, states[-1]).bool_constant_value()]
        if not false:
            return ""
        return " ".join(_pddl(c) for c in false) + (" does not hold" if len(false) == 1 else " do not hold")

    if result.reason == FailedValidationReason.INAPPLICABLE_ACTION and 0 < len(states) <= len(lines):
        index = len(states) - 1  # the trace holds the initial state and one state per step applied
        instance, line = plan.actions[index], lines[index]
        manager = problem.environment.expression_manager
        binding = {manager.ParameterExp(p): v for p, v in zip(instance.action.parameters, instance.actual_parameters)}
        why = unmet(c.substitute(binding) for c in instance.action.preconditions) or said
        return PlannerError(f"step {index + 1}, {line}, cannot be applied: {why}", file, line.line)
    if result.reason == FailedValidationReason.UNSATISFIED_GOALS and states:
        why = unmet(problem.goals) or said
        return PlannerError(f"the plan does not reach the goal: {why} after its {len(lines)} step(s)", file)
    return PlannerError(f"the plan is not valid: {said or getattr(result.reason, 'name', 'unknown reason')}", file)


def _conjuncts(conditions) -> list:
    """The conditions with every conjunction opened into its parts."""
    out = []
    for node in conditions:
        out += _conjuncts(node.args) if node.is_and() else [node]
    return out


def _pddl(node) -> str:
    """A ground literal as PDDL, `(on b1 b2)` or `(not (clear b3))`; other conditions as UP prints them."""
    if node.is_fluent_exp() and all(a.is_object_exp() for a in node.args):
        return "(" + " ".join((node.fluent().name, *(a.object().name for a in node.args))) + ")"
    if node.is_not():
        return f"(not {_pddl(node.arg(0))})"
    return str(node)
