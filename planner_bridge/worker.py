"""Run the planner bridge in a child Python process: `python -m planner_bridge.worker`.

Why a child process:
- determinism: pyperplan and unified-planning's grounder iterate over sets of strings, so the plan they find
  depends on Python's per-process string hash seed; the child runs with PYTHONHASHSEED=0, so the same files
  give the same plan on every run (golden tests and everything built on the plan rely on it);
- timeouts: not every engine honours one (pyperplan does not), a child process can always be killed;
- a clean stdout: the child points its file descriptor 1 at /dev/null, so no engine's chatter reaches ours.

Protocol: the parent writes one JSON request line on the child's stdin; the child answers on its original
stdout with JSON lines: {"event": "searching"} when the engine starts, then {"plan": ...} or {"error": ...}.
"""

from __future__ import annotations

import json
import os
import select
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from tailor.planner_bridge import errors
from tailor.planner_bridge.abstract_plan import AbstractPlan

HASH_SEED = "0"  # fixed string hashing in the child: the engines' set iteration order, hence the plan, is fixed
KILL_WAIT_S = 5.0  # how long to wait for a killed child to go away
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


def _child_main() -> int:
    """The child: plan the request in this process, answer on the original stdout."""
    answer = os.fdopen(os.dup(1), "w", encoding="utf-8")
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)  # from here on, anything printed by the engines is discarded

    def send(message: dict) -> None:
        answer.write(json.dumps(message) + "\n")
        answer.flush()

    request = json.loads(sys.stdin.readline())
    from tailor.planner_bridge.bridge import plan_here

    try:
        plan = plan_here(request["domain"], request["problem"], request["planner"], lambda: send({"event": "searching"}))
        send({"plan": plan.to_json(facts=True)})
    except errors.PlannerError as exc:
        send({"error": _error_json(exc)})
    except Exception as exc:  # a bug or an engine's surprise: still one line for the user
        send({"error": _error_json(errors.PlannerError(f"internal error: {type(exc).__name__}: {exc}"))})
    return 0


def _read_message(child: subprocess.Popen, deadline: float | None, planner: str, timeout, file: str) -> dict:
    """The child's next message; PlannerTimeoutError when the deadline passes first."""
    while True:
        remaining = None if deadline is None else deadline - time.monotonic()
        if remaining is not None and remaining <= 0:
            raise errors.PlannerTimeoutError(
                f"planner '{planner}' found no plan within the timeout of {timeout:g} s", file
            )
        ready, _, _ = select.select([child.stdout], [], [], remaining)
        if ready:
            line = child.stdout.readline()
            if not line:
                return {}
            return json.loads(line)


def plan_in_worker(domain: Path, problem: Path, planner: str, timeout: float | None) -> AbstractPlan:
    """Plan in a child process with a fixed hash seed; kill it when its search exceeds `timeout` seconds."""
    env = {**os.environ, "PYTHONHASHSEED": HASH_SEED}  # the child imports the installed tailor, as we do
    request = {"domain": str(domain), "problem": str(problem), "planner": planner}
    with tempfile.TemporaryFile() as stderr:
        child = subprocess.Popen(
            [sys.executable, "-m", "tailor.planner_bridge.worker"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=stderr, env=env, text=True,
        )
        try:
            child.stdin.write(json.dumps(request) + "\n")
            child.stdin.close()
            message = _read_message(child, None, planner, timeout, str(problem))
            if message.get("event") == "searching":
                deadline = None if timeout is None else time.monotonic() + timeout
                message = _read_message(child, deadline, planner, timeout, str(problem))
        finally:
            if child.poll() is None:
                child.kill()
            child.wait(KILL_WAIT_S)
            child.stdout.close()
        if "plan" in message:
            return AbstractPlan.from_json(message["plan"])
        if "error" in message:
            _raise_error(message["error"])
        stderr.seek(0)
        last = (stderr.read().decode(errors="replace").strip().splitlines() or ["no message"])[-1]
        raise errors.PlannerError(f"the planner process ended with status {child.returncode}: {last}", str(problem))


if __name__ == "__main__":
    sys.exit(_child_main())
