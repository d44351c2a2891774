"""The planner child process, `python -m tailor.planner_bridge.child` (started by planner_bridge.worker, which
says why a child and speaks the protocol): plan each pair the parent read and sent, in this process.
"""

from __future__ import annotations

import json
import os
import select
import signal
import sys
import threading
import time
import types

from tailor import errors
from tailor.planner_bridge.in_process import plan_pddl_here
from tailor.planner_bridge.reading import PDDLTask
from tailor.planner_bridge.solving import oneshot_planners
from tailor.planner_bridge.worker import (
    LIFELINE_ENV,
    PARENT_ENV,
    end_descendants,
    error_json,
    out_of_memory,
    resident_gb,
)

WATCH_PARENT_S = 1.0  # how often the watcher also checks that the parent's pid is still this process's parent
# CPython (3.11 and later) keeps Python frames in chunks of 16 kB and frees a chunk as soon as the frame at its
# base returns: unified-planning's imports, calling in and out across a chunk boundary, had one allocated and
# freed about 18 000 times (an mmap, a munmap and page faults each time: about a tenth of the child's CPU time).
# The child runs from a frame reserving this much stack (in words, never written), so it gets a chunk of its own
# with room for every frame its imports and the planner push.
ROOM_WORDS = 1 << 16


def _die_with_parent() -> None:
    """Make sure this child does not outlive the process that started it (SIGTERM, SIGKILL or a crash of the
    parent), whichever of the parent's threads started it.

    The parent passes the read end of a pipe (its number in LIFELINE_ENV) whose write end only it holds: the
    kernel closes that end when the parent process ends, however it ends, and a thread here, waiting on the
    pipe, then ends this process. (Linux's PR_SET_PDEATHSIG is no substitute: it fires when the parent *thread*
    that forked the child ends, and the Python API keeps one child for a whole session, for all its threads.)
    The watcher also checks that the parent's pid is still our parent's, should another process it forked
    hold a copy of the write end. Either way the engines this process started go with it (_end)."""
    parent = int(os.environ.get(PARENT_ENV, "0") or 0)
    lifeline = int(os.environ.get(LIFELINE_ENV, "-1") or -1)

    def watch() -> None:
        while True:
            if lifeline >= 0:
                ready, _, _ = select.select([lifeline], [], [], WATCH_PARENT_S)
                if ready:  # end of file (or an error): the parent's end is closed
                    _end()
            else:
                time.sleep(WATCH_PARENT_S)
            if parent and os.getppid() != parent:
                _end()

    if parent and os.getppid() != parent:  # the parent died before we looked
        _end()
    threading.Thread(target=watch, name="tailor-parent-watch", daemon=True).start()


def _end(signum: int | None = None, frame=None) -> None:
    """End this process now, and first every engine it started: unified-planning runs an engine binary (Fast
    Downward) in a session of its own, which would otherwise search on, orphaned, for minutes. Also the
    handler of SIGTERM, which then ends the process as it would have without one."""
    end_descendants(os.getpid())
    if signum is not None:
        signal.signal(signum, signal.SIG_DFL)
        os.kill(os.getpid(), signum)
    os._exit(1)


def _limit_memory(limit_gb: float | None) -> None:
    """Where the parent cannot read the child's resident memory (no /proc), limit the address space instead:
    a coarser bound (an allocation beyond it fails, as MemoryError or worse inside an engine's C code)."""
    if limit_gb is None or resident_gb(os.getpid()) is not None:
        return
    import resource

    limit = int(limit_gb * 2**30)
    _, hard = resource.getrlimit(resource.RLIMIT_AS)
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))


def main() -> int:
    """Plan each request line in this process, answer on the original stdout, until stdin ends."""
    _die_with_parent()
    signal.signal(signal.SIGTERM, _end)
    answer = os.fdopen(os.dup(1), "w", encoding="utf-8")
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)  # from here on, anything printed by the engines is discarded

    def send(message: dict) -> None:
        answer.write(json.dumps(message) + "\n")
        answer.flush()

    # imported before the clock starts: the imports are not the user's time
    import unified_planning.io
    import unified_planning.shortcuts  # noqa: F401

    oneshot_planners()  # imports the installed engines
    send({"event": "ready"})
    limited = False
    for line in sys.stdin:  # one request per line; a reused child (PlannerProcess) gets many
        request = json.loads(line)
        task = PDDLTask.from_json(request["task"])
        limit_gb = request.get("memory_gb")
        try:
            if not limited:
                _limit_memory(limit_gb)
                limited = True
            plan = plan_pddl_here(task, request["planner"], lambda: send({"event": "searching"}))
            send({"plan": plan.to_json(facts=True)})
        except MemoryError:
            send({"error": error_json(errors.PlannerError(out_of_memory(limit_gb), str(task.problem)))})
        except errors.PlannerError as exc:
            send({"error": error_json(exc)})
        except Exception as exc:  # a bug or an engine's surprise: still one line for the user
            send({"error": error_json(errors.PlannerError(f"internal error: {type(exc).__name__}: {exc}"))})
    return 0


def _call(function):
    return function()


def _in_room(function):
    """function() called from a frame reserving ROOM_WORDS of stack: _call's code with a larger declared stack
    (which only CPython's frame chunks take into account)."""
    return types.FunctionType(_call.__code__.replace(co_stacksize=ROOM_WORDS), {})(function)


if __name__ == "__main__":
    sys.exit(_in_room(main))
