"""Run the planner bridge in a child Python process (planner_bridge.child): the parent's side.

Why a child process:
- determinism: pyperplan and unified-planning's grounder iterate over sets of strings, so the plan they find
  depends on Python's per-process string hash seed; the child runs with PYTHONHASHSEED=0, so the same files
  give the same plan on every run (golden tests and everything built on the plan rely on it);
- limits: not every engine honours a timeout (pyperplan does not), but a child process can always be killed;
  the time limit runs from the moment the child is ready for the pair (its imports done), so it covers
  parsing, compiling, grounding and search; the parent also kills the child when its resident memory exceeds
  the memory limit (MEMORY_LIMIT_GB by default; checked every POLL_S, so it may overshoot briefly; without
  /proc the child's address space is limited instead), and says so in one line, "planner ran out of memory
  (limit N GB)" (status 1, a PlannerError);
- a clean stdout: the child points its file descriptor 1 at /dev/null, so no engine's chatter reaches ours;
- no orphans: the child holds the read end of a pipe whose write end only the parent process holds (its
  "lifeline"); a thread in the child ends it when that end closes, which the kernel does when the parent process
  ends, however it ends. The child's lifetime is tied to the process, not to the thread that started it (Linux's
  PR_SET_PDEATHSIG fires when that *thread* ends: the Python API's child, kept for the session, died with the
  first thread that planned). The parent kills it on every way out of PlannerProcess.plan_pddl but an answer;
- no engine left running: unified-planning starts an engine binary (Fast Downward's driver, then its search) in a
  session of its own, which no signal to the child reaches and which would search on for minutes after the child
  is gone. Whoever ends the child ends its descendants first, each with the process group it leads
  (end_descendants): the parent when it kills the child (the child is stopped meanwhile, so it starts nothing
  more), the child itself when its lifeline closes. The engines' temporary files go in the child's folder
  (TMPDIR), removed with it.

The parent reads and checks the pair (planner_bridge.reading.read_pddl) and sends the child what it read: the
child neither opens the files nor checks them again.

Protocol: the child says {"event": "ready"} on its original stdout when its imports are done; then, for each
JSON request line the parent writes on its stdin ({"task": PDDLTask.to_json(), "planner", "memory_gb"}; the
clock starts), it answers with JSON lines: {"event": "searching"} when the engine starts, then {"plan": ...}
or {"error": ...}. The CLI's commands plan once per child; the Python API keeps one child for many plans
(PlannerProcess).
"""

from __future__ import annotations

import json
import os
import select
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from tailor import errors
from tailor.planner_bridge.abstract_plan import AbstractPlan
from tailor.planner_bridge.reading import PDDLTask, read_pddl

# The planner process's memory (see above): a bound, so a huge problem ends in one line instead of swapping the
# machine; its imports alone take about 0.4 GB.
MEMORY_LIMIT_GB = 8.0
CHILD_MODULE = "tailor.planner_bridge.child"
HASH_SEED = "0"  # fixed string hashing in the child: the engines' set iteration order, hence the plan, is fixed
KILL_WAIT_S = 5.0  # how long to wait for a killed child to go away
PARENT_ENV = "TAILOR_PLANNER_PARENT"  # the parent's pid, so a child whose parent died before it looked exits
LIFELINE_ENV = "TAILOR_PLANNER_LIFELINE"  # the number of the child's file descriptor of the lifeline (see above)
POLL_S = 0.1  # how often the parent checks the child's time and memory while it waits for an answer
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


def error_json(exc: errors.PlannerError) -> dict:
    """A planner error as the child sends it (raise_error raises it again in the parent)."""
    return {"class": type(exc).__name__, "message": exc.message, "file": exc.file, "line": exc.line,
            "col": exc.col}


def raise_error(data: dict) -> None:
    cls = ERROR_CLASSES.get(data["class"], errors.PlannerError)
    raise cls(data["message"], data["file"], data["line"], data["col"])


def out_of_memory(limit_gb: float | None) -> str:
    return "planner ran out of memory" + ("" if limit_gb is None else f" (limit {limit_gb:g} GB)")


def descendants(pid: int) -> list[int]:
    """The live processes started by process `pid`, directly or not, parents before children (from Linux's
    /proc; elsewhere none are found)."""
    children: dict[int, list[int]] = {}
    try:
        entries = [entry.name for entry in os.scandir("/proc") if entry.name.isdigit()]
    except OSError:
        return []
    for name in entries:
        try:
            with open(f"/proc/{name}/stat", "rb") as stat:
                state, parent = stat.read().rsplit(b")", 1)[1].split()[:2]  # after the command's name
        except (OSError, ValueError):
            continue  # it ended meanwhile
        if state != b"Z":
            children.setdefault(int(parent), []).append(int(name))
    found, queue = [], list(children.get(pid, ()))
    while queue:
        found.append(queue.pop(0))
        queue.extend(children.get(found[-1], ()))
    return found


def end_descendants(pid: int) -> None:
    """Kill (SIGKILL) every process descended from process `pid` (not `pid` itself), with the whole process
    group of each one that leads a group: an engine unified-planning started in a session of its own (Fast
    Downward) then goes with whatever it started meanwhile."""
    for descendant in descendants(pid):
        try:
            if os.getpgid(descendant) == descendant:
                os.killpg(descendant, signal.SIGKILL)
            else:
                os.kill(descendant, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):  # it ended meanwhile
            pass


def resident_gb(pid: int) -> float | None:
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
        resident = resident_gb(child.pid) if self.memory_gb is not None else None
        if resident is not None and resident > self.memory_gb:
            raise errors.PlannerError(out_of_memory(self.memory_gb), self.file)


def _read_message(child: subprocess.Popen, limits: _Limits) -> dict:
    """The child's next message; PlannerTimeoutError or PlannerError when it exceeds its limits first.

    Lines are cut from the child's raw pipe here, not by a buffered reader: a buffered readline may take two
    messages from the pipe at once ("searching", then the plan), and a select on the pipe would then wait for
    the second one forever while it sits in the reader's buffer."""
    pending = getattr(child, "pending", b"")
    while b"\n" not in pending:
        limits.check(child)
        wait = POLL_S if limits.deadline is None else max(0.0, min(POLL_S, limits.deadline - time.monotonic()))
        ready, _, _ = select.select([child.stdout], [], [], wait)
        if ready:
            chunk = os.read(child.stdout.fileno(), 1 << 16)
            if not chunk:  # the child ended without a whole message
                child.pending = b""
                return {}
            pending += chunk
    line, _, child.pending = pending.partition(b"\n")
    return json.loads(line.decode("utf-8"))


class PlannerProcess:
    """A planner child process kept for many requests, so its interpreter and imports (about 1.8 s) are paid
    once: the Python API plans through one. A request that ends in a timeout or the memory limit kills the
    child; the next request starts a new one. Use it as a context manager, or call close()."""

    def __init__(self, memory_gb: float | None = MEMORY_LIMIT_GB):
        self.memory_gb = memory_gb
        self._child: subprocess.Popen | None = None
        self._stderr = None
        self._lifeline: int | None = None  # the write end of the child's lifeline, held open while it lives
        self._room: tempfile.TemporaryDirectory | None = None  # the folder the child runs in

    def _start(self) -> subprocess.Popen:
        self.close()  # a child that ended on its own: its pipes and files go before the next one starts
        self._stderr = tempfile.TemporaryFile()
        # a folder of its own to run in: engines that write files where they run (Fast Downward's output.sas)
        # write them there, not into the user's working folder; it goes with the child
        self._room = tempfile.TemporaryDirectory(prefix="tailor-planner-")
        given, held = os.pipe()  # the child's read end and our write end; both close on exec (pass_fds gives
        # the child its end), so no other program this process starts holds the lifeline
        env = {**os.environ, "PYTHONHASHSEED": HASH_SEED, PARENT_ENV: str(os.getpid()),
               LIFELINE_ENV: str(given), "TMPDIR": self._room.name}
        try:  # a process group of its own, so that _end stops and kills it with what it started in its group
            child = subprocess.Popen(
                [sys.executable, "-m", CHILD_MODULE], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                stderr=self._stderr, env=env, text=True, pass_fds=(given,), cwd=self._room.name,
                process_group=0,
            )
        except BaseException:
            os.close(held)
            raise
        finally:
            os.close(given)
        self._child, self._lifeline = child, held
        return child

    def plan(self, domain: Path, problem: Path, planner: str, timeout: float | None) -> AbstractPlan:
        """Read and check the pair, then plan it in the child (see plan_pddl)."""
        return self.plan_pddl(read_pddl(domain, problem), planner, timeout)

    def plan_pddl(self, task: PDDLTask, planner: str, timeout: float | None) -> AbstractPlan:
        """Plan a pair read by read_pddl in the child; kill it when parsing, compiling and searching together
        take more than `timeout` seconds, or when it holds more than the memory limit."""
        problem = task.problem
        request = {"task": task.to_json(), "planner": planner, "memory_gb": self.memory_gb}
        limits = _Limits(planner, str(problem), timeout, self.memory_gb)
        child = self._child if self._child is not None and self._child.poll() is None else self._start()
        keep = False
        try:
            if not getattr(child, "ready", False):  # a new child: its imports do not count against the timeout
                message = _read_message(child, limits)
                if message.get("event") != "ready":
                    self._fail(message, problem)
                child.ready = True
            limits.deadline = None if timeout is None else time.monotonic() + timeout
            # sent once the child is ready: a long problem would fill the pipe, and block this write while the
            # child imports, when the parent must watch its memory
            child.stdin.write(json.dumps(request) + "\n")
            child.stdin.flush()
            message = _read_message(child, limits)
            while message.get("event"):
                message = _read_message(child, limits)
            if "plan" in message:
                keep = True
                return AbstractPlan.from_json(message["plan"])
            if "error" in message:
                keep = True  # the planner answered: the child is fine for the next request
                raise_error(message["error"])
            self._fail(message, problem)
        except BrokenPipeError:
            self._fail({}, problem)
        finally:  # every way out but an answer, KeyboardInterrupt included: the child goes
            if not keep:
                self.close()

    def _fail(self, message: dict, problem: Path) -> None:
        """The child ended without an answer: say why in one line."""
        child = self._child
        if child is not None:
            _end(child)
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
            _end(child)
            for stream in (child.stdin, child.stdout):
                try:
                    stream.close()
                except OSError:  # a pipe to a killed child
                    pass
        if self._stderr is not None:
            self._stderr.close()
            self._stderr = None
        lifeline, self._lifeline = self._lifeline, None
        if lifeline is not None:
            os.close(lifeline)
        room, self._room = self._room, None
        if room is not None:
            room.cleanup()

    def __enter__(self) -> "PlannerProcess":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _end(child: subprocess.Popen) -> None:
    """Kill the child and every process it started (see "no engine left running" above), and reap it. It is
    stopped first, so that it starts nothing while its descendants are found; its own group (it leads one) goes
    last, with whatever of it started meanwhile."""
    if child.poll() is None:  # not reaped, so its pid (and its group's) still names it
        try:
            os.killpg(child.pid, signal.SIGSTOP)
            end_descendants(child.pid)
            os.killpg(child.pid, signal.SIGKILL)
        except ProcessLookupError:  # it has just ended
            pass
    child.wait(KILL_WAIT_S)


def plan_in_worker(
    domain: Path, problem: Path, planner: str, timeout: float | None, memory_gb: float | None = MEMORY_LIMIT_GB
) -> AbstractPlan:
    """Plan the pair in a new child process with a fixed hash seed (see PlannerProcess), ended afterwards."""
    with PlannerProcess(memory_gb) as process:
        return process.plan(domain, problem, planner, timeout)
