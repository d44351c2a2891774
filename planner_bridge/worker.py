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

Protocol: the child says {"event": "ready"} on its original stdout when its imports are done; then, for each
JSON request line the parent writes on its stdin (the clock starts), it answers with JSON lines:
{"event": "searching"} when the engine starts, then {"plan": ...} or {"error": ...}. The CLI's commands
plan once per child; the Python API keeps one child for many plans (PlannerProcess).
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
    """The child: plan each request line in this process, answer on the original stdout, until stdin ends."""
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
    send({"event": "ready"})
    limited = False
    for line in sys.stdin:  # one request per line; a reused child (PlannerProcess) gets many
        request = json.loads(line)
        limit_gb = request.get("memory_gb")
        try:
            if not limited:
                _limit_memory(limit_gb)
                limited = True
            plan = plan_here(request["domain"], request["problem"], request["planner"],
                             lambda: send({"event": "searching"}))
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


class PlannerProcess:
    """A planner child process kept for many requests, so its interpreter and imports (about 1.8 s) are paid
    once: the Python API plans through one. A request that ends in a timeout or the memory limit kills the
    child; the next request starts a new one. Use it as a context manager, or call close()."""

    def __init__(self, memory_gb: float | None = MEMORY_LIMIT_GB):
        self.memory_gb = memory_gb
        self._child: subprocess.Popen | None = None
        self._stderr = None

    def _start(self) -> subprocess.Popen:
        env = {**os.environ, "PYTHONHASHSEED": HASH_SEED, PARENT_ENV: str(os.getpid())}
        self._stderr = tempfile.TemporaryFile()
        child = subprocess.Popen(
            [sys.executable, "-m", "tailor.planner_bridge.worker"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self._stderr, env=env, text=True,
        )
        self._child = child
        return child

    def plan(self, domain: Path, problem: Path, planner: str, timeout: float | None) -> AbstractPlan:
        """Plan in the child; kill it when parsing, compiling and searching together take more than `timeout`
        seconds, or when it holds more than the memory limit."""
        request = {"domain": str(domain), "problem": str(problem), "planner": planner, "memory_gb": self.memory_gb}
        limits = _Limits(planner, str(problem), timeout, self.memory_gb)
        child = self._child if self._child is not None and self._child.poll() is None else self._start()
        keep = False
        try:
            child.stdin.write(json.dumps(request) + "\n")
            child.stdin.flush()
            if not getattr(child, "ready", False):  # a new child: its imports do not count against the timeout
                message = _read_message(child, limits)
                if message.get("event") != "ready":
                    self._fail(message, problem)
                child.ready = True
            limits.deadline = None if timeout is None else time.monotonic() + timeout
            message = _read_message(child, limits)
            while message.get("event"):
                message = _read_message(child, limits)
            if "plan" in message:
                keep = True
                return AbstractPlan.from_json(message["plan"])
            if "error" in message:
                keep = True  # the planner answered: the child is fine for the next request
                _raise_error(message["error"])
            self._fail(message, problem)
        except BrokenPipeError:
            self._fail({}, problem)
        finally:  # every way out but an answer, KeyboardInterrupt included: the child goes
            if not keep:
                self.close()

    def _fail(self, message: dict, problem: Path) -> None:
        """The child ended without an answer: say why in one line."""
        child = self._child
        if child is not None and child.poll() is None:
            child.kill()
        if child is not None:
            child.wait(KILL_WAIT_S)
        self._stderr.seek(0)
        lines = self._stderr.read().decode(errors="replace").strip().splitlines() or ["no message"]
        if self.memory_gb is not None and any("MemoryError" in line for line in lines[-3:]):
            raise errors.PlannerError(out_of_memory(self.memory_gb), str(problem))
        status = child.returncode if child is not None else None
        raise errors.PlannerError(f"the planner process ended with status {status}: {lines[-1]}", str(problem))

    def close(self) -> None:
        """End the child (it is killed: nothing it holds needs a clean shutdown)."""
        child, self._child = self._child, None
        if child is not None:
            if child.poll() is None:
                child.kill()
            child.wait(KILL_WAIT_S)
            for stream in (child.stdin, child.stdout):
                try:
                    stream.close()
                except OSError:  # a pipe to a killed child
                    pass
        if self._stderr is not None:
            self._stderr.close()
            self._stderr = None

    def __enter__(self) -> "PlannerProcess":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def plan_in_worker(
    domain: Path, problem: Path, planner: str, timeout: float | None, memory_gb: float | None = MEMORY_LIMIT_GB
) -> AbstractPlan:
    """Plan in a new child process with a fixed hash seed (see PlannerProcess), ended afterwards."""
    with PlannerProcess(memory_gb) as process:
        return process.plan(domain, problem, planner, timeout)


if __name__ == "__main__":
    sys.exit(_child_main())
