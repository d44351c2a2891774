"""Run the planner bridge in a child Python process: `python -m planner_bridge.worker`.

Why a child process:
- determinism: pyperplan and unified-planning's grounder iterate over sets of strings, so the plan they find
  depends on Python's per-process string hash seed; the child runs with PYTHONHASHSEED=0, so the same files
  give the same plan on every run (golden tests and everything built on the plan rely on it);
- limits: not every engine honours a timeout (pyperplan does not), but a child process can always be killed;
  the time limit runs from the moment the child is ready to read the files (its imports done), so it covers
  parsing, compiling, grounding and search; the parent also kills the child when its resident memory exceeds
  the memory limit (bridge.MEMORY_LIMIT_GB by default; checked every POLL_S, so it may overshoot briefly;
  without /proc the child's address space is limited instead), and says so in one line, "planner ran out of
  memory (limit N GB)" (status 1, a PlannerError);
- a clean stdout: the child points its file descriptor 1 at /dev/null, so no engine's chatter reaches ours;
- no orphans: the child asks the kernel to kill it when its parent dies (Linux: PR_SET_PDEATHSIG; elsewhere a
  thread watches the parent's pid), and the parent kills it on every way out of plan_in_worker.

Protocol: the parent writes one JSON request line on the child's stdin; the child answers on its original
stdout with JSON lines: {"event": "ready"} when its imports are done (the clock starts), {"event": "searching"}
when the engine starts, then {"plan": ...} or {"error": ...}.
"""

from __future__ import annotations

import json
import os
import select
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from tailor import errors
from tailor.planner_bridge.abstract_plan import AbstractPlan
from tailor.planner_bridge.bridge import MEMORY_LIMIT_GB

HASH_SEED = "0"  # fixed string hashing in the child: the engines' set iteration order, hence the plan, is fixed
KILL_WAIT_S = 5.0  # how long to wait for a killed child to go away
PARENT_ENV = "TAILOR_PLANNER_PARENT"  # the parent's pid, so a child whose parent died before it looked exits
PR_SET_PDEATHSIG = 1  # from <linux/prctl.h>
POLL_S = 0.1  # how often the parent checks the child's time and memory while it waits for an answer
WATCH_PARENT_S = 1.0  # how often the fallback thread checks that the parent is alive (not on Linux)
ERROR_CLASSES = {
    cls.__name__: cls
    for cls in (
        errors.PlannerError,
        errors.InputFileError,
        errors.PDDLSyntaxError,
        errors.PDDLSemanticError,
        errors.NoPlanError,
        errors.PlannerTimeoutError,
        errors.PlannerUnavailableError,
    )
}


def _error_json(exc: errors.PlannerError) -> dict:
    return {"class": type(exc).__name__, "message": exc.message, "file": exc.file, "line": exc.line, "col": exc.col}


def _raise_error(data: dict) -> None:
    cls = ERROR_CLASSES.get(data["class"], errors.PlannerError)
    raise cls(data["message"], data["file"], data["line"], data["col"])


def out_of_memory(limit_gb: float) -> str:
    return f"planner ran out of memory (limit {limit_gb:g} GB)"


def _die_with_parent() -> None:
    """Make sure this child does not outlive the process that started it (SIGTERM or a crash of the parent)."""
    parent = int(os.environ.get(PARENT_ENV, "0") or 0)
    if sys.platform.startswith("linux"):
        import ctypes
        import signal

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    elif parent:
        import threading

        def watch() -> None:
            while os.getppid() == parent:
                time.sleep(WATCH_PARENT_S)
            os._exit(1)

        threading.Thread(target=watch, daemon=True).start()
    if parent and os.getppid() != parent:  # the parent died before the kernel was asked to tell us
        os._exit(1)


def _limit_memory(limit_gb: float | None) -> None:
    """Where the parent cannot read the child's resident memory (no /proc), limit the address space instead:
    a coarser bound (an allocation beyond it fails, as MemoryError or worse inside an engine's C code)."""
    if limit_gb is None or _resident_gb(os.getpid()) is not None:
        return
    import resource

    limit = int(limit_gb * 2**30)
    _, hard = resource.getrlimit(resource.RLIMIT_AS)
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))


def _child_main() -> int:
    """The child: plan the request in this process, answer on the original stdout."""
    _die_with_parent()
    answer = os.fdopen(os.dup(1), "w", encoding="utf-8")
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)  # from here on, anything printed by the engines is discarded

    def send(message: dict) -> None:
        answer.write(json.dumps(message) + "\n")
        answer.flush()

    # imported before the clock starts: the imports are not the user's time
    import unified_planning.io
    import unified_planning.shortcuts  # noqa: F401

    from tailor.planner_bridge.bridge import plan_here
    from tailor.planner_bridge.solving import oneshot_planners

    oneshot_planners()  # imports the installed engines
    request = json.loads(sys.stdin.readline())
    limit_gb = request.get("memory_gb")
    send({"event": "ready"})
    try:
        _limit_memory(limit_gb)
        plan = plan_here(request["domain"], request["problem"], request["planner"], lambda: send({"event": "searching"}))
        send({"plan": plan.to_json(facts=True)})
    except MemoryError:
        send({"error": _error_json(errors.PlannerError(out_of_memory(limit_gb), request["problem"]))})
    except errors.PlannerError as exc:
        send({"error": _error_json(exc)})
    except Exception as exc:  # a bug or an engine's surprise: still one line for the user
        send({"error": _error_json(errors.PlannerError(f"internal error: {type(exc).__name__}: {exc}"))})
    return 0


def _resident_gb(pid: int) -> float | None:
    """The process's resident memory (Linux /proc), or None where it cannot be read."""
    try:
        with open(f"/proc/{pid}/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 2**20  # kB -> GB
    except (OSError, ValueError):
        return None
    return None


@dataclass
class _Limits:
    """What the parent enforces on the child while it waits for its answer."""

    planner: str
    file: str
    timeout: float | None
    memory_gb: float | None
    deadline: float | None = None  # set when the child is ready

    def check(self, child: subprocess.Popen) -> None:
        if self.deadline is not None and time.monotonic() >= self.deadline:
            raise errors.PlannerTimeoutError(
                f"planner '{self.planner}' found no plan within the timeout of {self.timeout:g} s", self.file
            )
        resident = _resident_gb(child.pid) if self.memory_gb is not None else None
        if resident is not None and resident > self.memory_gb:
            raise errors.PlannerError(out_of_memory(self.memory_gb), self.file)


def _read_message(child: subprocess.Popen, limits: _Limits) -> dict:
    """The child's next message; PlannerTimeoutError or PlannerError when it exceeds its limits first."""
    while True:
        limits.check(child)
        wait = POLL_S if limits.deadline is None else max(0.0, min(POLL_S, limits.deadline - time.monotonic()))
        ready, _, _ = select.select([child.stdout], [], [], wait)
        if ready:
            line = child.stdout.readline()
            return json.loads(line) if line else {}


def plan_in_worker(
    domain: Path, problem: Path, planner: str, timeout: float | None, memory_gb: float | None = MEMORY_LIMIT_GB
) -> AbstractPlan:
    """Plan in a child process with a fixed hash seed; kill it when parsing, compiling and searching together
    take more than `timeout` seconds, or when it holds more than `memory_gb` of memory (None: no limit)."""
    env = {**os.environ, "PYTHONHASHSEED": HASH_SEED, PARENT_ENV: str(os.getpid())}
    request = {"domain": str(domain), "problem": str(problem), "planner": planner, "memory_gb": memory_gb}
    limits = _Limits(planner, str(problem), timeout, memory_gb)
    with tempfile.TemporaryFile() as stderr:
        child = subprocess.Popen(
            [sys.executable, "-m", "tailor.planner_bridge.worker"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=stderr, env=env, text=True,
        )
        try:
            child.stdin.write(json.dumps(request) + "\n")
            child.stdin.close()
            message = _read_message(child, limits)
            if message.get("event") == "ready":  # the clock starts before the child reads the files
                limits.deadline = None if timeout is None else time.monotonic() + timeout
                message = _read_message(child, limits)
            while message.get("event"):
                message = _read_message(child, limits)
        finally:  # every way out, KeyboardInterrupt included: the child goes too
            if child.poll() is None:
                child.kill()
            child.wait(KILL_WAIT_S)
            child.stdout.close()
        if "plan" in message:
            return AbstractPlan.from_json(message["plan"])
        if "error" in message:
            _raise_error(message["error"])
        stderr.seek(0)
        lines = stderr.read().decode(errors="replace").strip().splitlines() or ["no message"]
        if memory_gb is not None and any("MemoryError" in line for line in lines[-3:]):
            raise errors.PlannerError(out_of_memory(memory_gb), str(problem))
        raise errors.PlannerError(f"the planner process ended with status {child.returncode}: {lines[-1]}", str(problem))


if __name__ == "__main__":
    sys.exit(_child_main())
