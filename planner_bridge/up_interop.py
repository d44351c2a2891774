"""unified-planning objects in and out: plan a `Problem` built in Python, link a plan any UP engine found, and
give our partial-order plan back as a UP `PartialOrderPlan`, so results feed UP's own tools.

A Problem is planned in this process (no child interpreter: there are no files to hand over); under a timeout
in a copy of this process (os.fork), which is killed when the time is up: not every engine honours a timeout,
and unified-planning itself can take minutes over a large Problem before any engine starts (its `kind` alone
grounds every fluent). The engines' choice among equally good plans can depend on Python's string hash seed;
start Python with PYTHONHASHSEED=0 for the same plan across runs (files planned through
planner_bridge.plan_files always are).
"""

from __future__ import annotations

import json
import math
import os
import select
import signal
import time
import warnings

from tailor.errors import ArgumentTypeError, ArgumentValueError, PlannerError, PlannerTimeoutError
from tailor.planner_bridge.abstract_plan import GOAL, INITIAL, AbstractPlan
from tailor.planner_bridge.bridge import check_limits
from tailor.planner_bridge.causal import partial_order
from tailor.planner_bridge.in_process import DEFAULT_PLANNER, plan_parsed, problem_facts
from tailor.planner_bridge.solving import canonical, validate
from tailor.planner_bridge.worker import KILL_WAIT_S, POLL_S, error_json, out_of_memory, raise_error

GIVEN = "given"  # the planner name of an AbstractPlan made from a plan the caller brought
# The forked planner ends itself this long after its timeout (SIGALRM), should its parent be gone or stuck.
ALARM_GRACE_S = 5
MAX_ALARM_S = 2**31 - 1  # the most signal.alarm takes everywhere


def check_problem(problem, argument: str = "problem") -> None:
    """A unified-planning Problem, or an ArgumentTypeError naming the argument."""
    from unified_planning.model import Problem

    if not isinstance(problem, Problem):
        raise ArgumentTypeError(f"{argument} must be a unified_planning.model.Problem, not {type(problem).__name__}")


def plan_problem(problem, planner: str = DEFAULT_PLANNER, domain: str | None = None,
                 timeout: float | None = None) -> AbstractPlan:
    """Plan a unified-planning Problem with any installed engine (compiling what it lacks), validate the plan
    and link it (Sec. 5.2). `domain` names the domain in the plan (default: the problem's name). `timeout`
    limits everything from the Problem to the linked plan, in seconds (PlannerTimeoutError); None: no limit."""
    check_problem(problem)
    file = f"<problem {problem.name}>"
    if timeout is None:
        return plan_parsed(problem, domain or problem.name, planner, file=file)
    check_limits(timeout)
    return _plan_forked(problem, domain or problem.name, canonical(planner), file, timeout)


def _plan_forked(problem, domain: str, planner: str, file: str, timeout: float) -> AbstractPlan:
    """plan_parsed in a forked copy of this process, which sends its plan (or error) back through a pipe and
    is killed when it has not within `timeout` seconds. The copy sees the Problem as it is here without any
    transfer, and whatever planning does to unified-planning's state stays in it."""
    if not hasattr(os, "fork"):
        raise ArgumentValueError("timeout: a unified-planning Problem is planned under a time limit in a forked "
                                 "process, and this platform cannot fork (plan it without a timeout)")
    incoming, outgoing = os.pipe()
    with warnings.catch_warnings():  # (Python 3.12 warns of a fork among threads: the copy uses none of theirs)
        warnings.simplefilter("ignore", DeprecationWarning)
        pid = os.fork()
    if pid == 0:  # the copy: never returns
        try:
            os.close(incoming)
            _answer_forked(problem, domain, planner, file, timeout, outgoing)
        finally:
            os._exit(1)
    os.close(outgoing)
    ended = False
    try:
        received = _read_until_end(incoming, time.monotonic() + timeout)
        if received is None:
            raise PlannerTimeoutError(f"planner '{planner}' found no plan within the timeout of {timeout:g} s",
                                      file)
        _reap(pid)
        ended = True
        try:
            message = json.loads(received.decode("utf-8"))
        except ValueError:  # it died without a whole answer (killed, or out of memory)
            raise PlannerError("the planner process ended without an answer", file) from None
        if "error" in message:
            raise_error(message["error"])
        return AbstractPlan.from_json(message["plan"])
    finally:  # every way out, Ctrl-C included: the copy goes
        os.close(incoming)
        if not ended:
            _kill(pid)


def _answer_forked(problem, domain: str, planner: str, file: str, timeout: float, outgoing: int) -> None:
    """In the forked copy: plan, write the answer as JSON to `outgoing`, end. It ends itself ALARM_GRACE_S after
    the timeout whatever happens to its parent, and keeps no other file of its parent open (a pipe held open
    would hide the parent's death from a planner child of its own, see worker)."""
    try:
        signal.signal(signal.SIGALRM, signal.SIG_DFL)  # (the copy's one thread is its main thread)
    except ValueError:
        pass
    signal.alarm(min(math.ceil(timeout) + ALARM_GRACE_S, MAX_ALARM_S))
    null = os.open(os.devnull, os.O_RDWR)
    for fd in (0, 1, 2):  # no engine's chatter on the parent's terminal or stdout
        os.dup2(null, fd)
    keep = sorted({0, 1, 2, outgoing})
    for low, high in zip(keep, keep[1:] + [os.sysconf("SC_OPEN_MAX") if hasattr(os, "sysconf") else 1 << 16]):
        os.closerange(low + 1, high)
    try:
        message = {"plan": plan_parsed(problem, domain, planner, file=file).to_json(facts=True)}
    except PlannerError as exc:
        message = {"error": error_json(exc)}
    except MemoryError:
        message = {"error": error_json(PlannerError(out_of_memory(None), file))}
    except Exception as exc:  # a bug or an engine's surprise: still one line for the user
        message = {"error": error_json(PlannerError(f"internal error: {type(exc).__name__}: {exc}", file))}
    data = json.dumps(message).encode("utf-8")
    while data:
        data = data[os.write(outgoing, data):]
    os._exit(0)


def _read_until_end(fd: int, deadline: float) -> bytes | None:
    """Everything written to the pipe `fd` until its writer closes it; None if that is not before `deadline`."""
    chunks = []
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            return None
        ready, _, _ = select.select([fd], [], [], min(POLL_S, left))
        if ready:
            chunk = os.read(fd, 1 << 16)
            if not chunk:
                return b"".join(chunks)
            chunks.append(chunk)


def _reap(pid: int) -> None:
    """Wait for the forked planner to end (it has closed its end of the pipe)."""
    try:
        os.waitpid(pid, 0)
    except ChildProcessError:  # reaped already (by a handler of SIGCHLD of the application's)
        pass


def _kill(pid: int) -> None:
    """Kill the forked planner, with every process it started (an engine such as Fast Downward runs in a session
    of its own, which killing the fork would not reach), and reap it."""
    from tailor.planner_bridge.worker import end_descendants

    end_descendants(pid)
    try:
        os.kill(pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    deadline = time.monotonic() + KILL_WAIT_S
    while time.monotonic() < deadline:
        try:
            if os.waitpid(pid, os.WNOHANG)[0]:
                return
        except ChildProcessError:  # reaped already
            return
        time.sleep(0.01)


def link_plan(problem, plan, domain: str | None = None, planner: str = GIVEN) -> AbstractPlan:
    """Our partial-order plan with causal links from a plan any unified-planning engine found for `problem`:
    a SequentialPlan, or a PartialOrderPlan (read in one of its linearizations, then deordered). The plan is
    validated first; an invalid plan is a PlannerError."""
    from unified_planning.plans import PartialOrderPlan, PlanKind, SequentialPlan

    check_problem(problem)
    if isinstance(plan, PartialOrderPlan):
        plan = plan.convert_to(PlanKind.SEQUENTIAL_PLAN, problem)
    if not isinstance(plan, SequentialPlan):
        raise ArgumentTypeError("plan must be a unified_planning SequentialPlan or PartialOrderPlan, "
                                f"not {type(plan).__name__}")
    file = f"<problem {problem.name}>"
    validate(problem, plan, planner, file)
    steps, links, orderings = partial_order(problem, plan)
    objects, initial = problem_facts(problem)
    return AbstractPlan(domain or problem.name, problem.name, planner, steps, links, orderings, objects, initial)


def to_partial_order_plan(plan: AbstractPlan, problem):
    """The plan as a unified-planning PartialOrderPlan of `problem`'s actions: an edge for every ordering and
    every causal link between two steps (the links themselves stay in the AbstractPlan)."""
    from unified_planning.plans import ActionInstance, PartialOrderPlan

    check_problem(problem)
    if not isinstance(plan, AbstractPlan):
        raise ArgumentTypeError(f"plan must be a tailor AbstractPlan, not {type(plan).__name__}")
    instances = {}
    for step in plan.steps:
        try:
            action = problem.action(step.action)
            args = tuple(problem.object(name) for name in step.args)
        except Exception:  # UPValueError: the plan is of another problem
            raise ArgumentValueError(f"step {step.id} ({step.action} {' '.join(step.args)}) is not an action "
                                     f"of problem {problem.name!r}") from None
        instances[step.id] = ActionInstance(action, args)
    edges = {(a, b) for a, b in plan.orderings}
    edges |= {(k.producer, k.consumer) for k in plan.links if k.producer != INITIAL and k.consumer != GOAL}
    adjacency = {instances[s.id]: [] for s in plan.steps}
    for a, b in sorted(edges):
        if a not in instances or b not in instances:
            raise PlannerError(f"the plan orders step {a} before {b}, which it does not have")
        adjacency[instances[a]].append(instances[b])
    return PartialOrderPlan(adjacency, problem.environment)
