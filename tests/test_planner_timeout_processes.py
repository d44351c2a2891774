"""No planner process outlives `tailor plan`, however it ends: unified-planning runs Fast Downward (its driver,
then its search) in a session of its own, out of reach of any signal to the planner child; the child ends it
when its lifeline to the parent closes (the parent killed, SIGKILL included), the parent when it kills the child
(planner_bridge.worker.end_descendants). The timeout itself: tests/test_fast_downward.py."""

from __future__ import annotations

import importlib.util
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from processes import processes_naming
from tailor.planner_bridge.worker import descendants, end_descendants

FIXTURES = Path(__file__).parent / "fixtures" / "pddl"
BLOCKS = FIXTURES / "blocks" / "domain.pddl"
LARGE = FIXTURES / "blocks" / "large-50.pddl"  # fast-downward-opt searches it for hours
START_S = 60  # how long Fast Downward may take to start its search on a loaded machine
# Fast Downward's search writes a line to its pipe every few seconds (each new f layer): an orphaned one ends
# of SIGPIPE at its next line. So the test looks right after the planner child is gone, as a user would with ps:
# what is left then runs on for seconds to minutes (the slower, the longer the search has run).
SEARCHING_S = 2.0  # killed this long into the search
LOOK_S = 0.3  # how long after the child is gone the test looks (what was killed needs a moment to go)
GONE_S = 5  # how long tailor and its child may take to end (the floor of issue 33)

pytestmark = [
    pytest.mark.skipif(importlib.util.find_spec("up_fast_downward") is None and not os.environ.get("CI"),
                       reason="Fast Downward is not installed: pip install 'tailor[planners]'"),
    pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc to see the planner's processes"),
]




def _cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return ""


def _alive(pid: int) -> bool:
    """Whether the process runs (neither gone nor a zombie)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return False


def _wait_for(condition, seconds: float) -> bool:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.1)
    return condition()


@pytest.mark.parametrize("signum", [signal.SIGKILL, signal.SIGTERM], ids=["SIGKILL", "SIGTERM"])
def test_fast_downward_goes_with_a_killed_tailor(tmp_path, signum):
    """`tailor plan` killed while Fast Downward searches: once its planner child is gone, so are Fast Downward's
    driver and search. Its processes are told by their command lines, which name files under the TMPDIR given
    here."""
    command = [sys.executable, "-m", "tailor.cli", "plan", str(BLOCKS), str(LARGE), "--planner",
               "fast-downward-opt", "--timeout", "600"]
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                               env={**os.environ, "TMPDIR": str(tmp_path)})
    searching = lambda: any("bin/downward" in c for c in processes_naming(str(tmp_path)).values())
    try:
        if not _wait_for(searching, START_S):
            pytest.skip("Fast Downward's search did not start in time (a very loaded machine)")
        time.sleep(SEARCHING_S)
        child = [pid for pid in descendants(process.pid) if "planner_bridge.child" in _cmdline(pid)]
        assert len(child) == 1
        process.send_signal(signum)
        _, err = process.communicate(timeout=GONE_S)
        if signum == signal.SIGTERM:
            assert (process.returncode, err) == (143, "tailor plan: terminated\n")
        assert _wait_for(lambda: not _alive(child[0]), GONE_S)
        time.sleep(LOOK_S)
        assert processes_naming(str(tmp_path)) == {}
    finally:
        process.kill()
        process.wait()
        for pid in processes_naming(str(tmp_path)):
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass


def test_end_descendants_ends_a_grandchild_in_a_session_of_its_own():
    """A process a child started in a new session (as unified-planning starts Fast Downward) is found, after
    its parent, and killed with its group; the child itself is left to its caller."""
    script = ("import subprocess, sys, time; subprocess.Popen([sys.executable, '-c', 'import time; "
              "time.sleep(60)'], start_new_session=True); time.sleep(60)")
    child = subprocess.Popen([sys.executable, "-c", script])
    try:
        assert _wait_for(lambda: len(descendants(child.pid)) == 1, 10)
        grandchild = descendants(child.pid)[0]
        assert os.getsid(grandchild) == grandchild != os.getsid(child.pid)
        mine = descendants(os.getpid())
        assert mine.index(child.pid) < mine.index(grandchild)
        end_descendants(child.pid)
        assert _wait_for(lambda: descendants(child.pid) == [], 5)
        assert child.poll() is None
    finally:
        for pid in descendants(child.pid):
            os.kill(pid, signal.SIGKILL)
        child.kill()
        child.wait()
