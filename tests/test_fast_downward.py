"""Fast Downward through unified-planning (the optional extra `tailor[planners]`, in `[test]` so CI runs these):
`--planner fast-downward` plans a large classic instance in seconds (pyperplan finds no plan for it within a
minute: tests/benchmarks/test_fast_downward_vs_pyperplan.py), and its answers keep the README's exit statuses:
solved 0, unsolvable proven 6, out of time 7."""

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

from tailor.cli.main import main
from tailor.planner_bridge import plan_from_ipc, read_pddl

FIXTURES = Path(__file__).parent / "fixtures" / "pddl"
BLOCKS = FIXTURES / "blocks" / "domain.pddl"
LARGE = FIXTURES / "blocks" / "large-50.pddl"  # 50 blocks: Fast Downward about a second, pyperplan > 60 s
BAD = FIXTURES / "bad"

# Without the extra the tests are skipped, except in CI, which installs `.[test]`: there they must run.
pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("up_fast_downward") is None and not os.environ.get("CI"),
    reason="Fast Downward is not installed: pip install 'tailor[planners]'",
)


def tailor(capsys, *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def test_fast_downward_plans_the_large_instance_in_seconds(tmp_path, capsys):
    """Solved: status 0, a valid plan (the bridge validates it), written as an IPC plan file and read back."""
    code, out, err = tailor(capsys, "plan", str(BLOCKS), str(LARGE), "--planner", "fast-downward",
                            "--timeout", "60", "--format", "ipc")
    assert (code, err) == (0, "")
    steps = out.splitlines()[:-1]
    assert len(steps) >= 50 and out.splitlines()[-1] == f"; cost = {len(steps)} (unit cost)"
    (tmp_path / "sas_plan").write_text(out, encoding="utf-8")
    plan = plan_from_ipc(read_pddl(BLOCKS, LARGE), tmp_path / "sas_plan")
    assert [f"({' '.join((s.action, *s.args))})" for s in plan.steps] == steps


def test_fast_downward_names_itself_and_links_the_plan(capsys):
    code, out, err = tailor(capsys, "plan", "soccer", "score", "--planner", "fast-downward")
    assert (code, err) == (0, "")
    assert out.startswith(";; domain soccer, problem score, planner fast-downward\n")
    assert "Step 2 : (dribbleball pos2 pos3)\n    1 -> (atball pos2)\n" in out


def test_an_unsolvable_problem_fast_downward_proves_so_is_status_6(capsys):
    code, out, err = tailor(capsys, "plan", str(BAD / "domain.pddl"), str(BAD / "unsolvable_problem.pddl"),
                            "--planner", "fast-downward")
    assert (code, out) == (6, "")
    assert err == (f"tailor plan: error: {BAD / 'unsolvable_problem.pddl'}: no plan exists (planner "
                   "'fast-downward' proved the goal unreachable)\n")


# --- out of time ----------------------------------------------------------------------------------------
TIMEOUT_S = 4  # Fast Downward's optimal configuration (A* with LM-cut) does not finish 50 blocks in hours




@pytest.fixture(scope="module")
def timed_out(tmp_path_factory):
    """`tailor plan` of the large instance with fast-downward-opt and a timeout: its status, its output, whether
    Fast Downward's search was running before the timeout, and Fast Downward's processes left once tailor ended.
    unified-planning runs Fast Downward in a session of its own, with its files in a temporary folder: under a
    TMPDIR of this test's own, so its processes are told by their command lines (and killed afterwards)."""
    if not Path("/proc/self/stat").exists():
        pytest.skip("needs /proc to see the planner's processes")
    tmp = tmp_path_factory.mktemp("fast-downward-tmp")
    command = [sys.executable, "-m", "tailor.cli", "plan", str(BLOCKS), str(LARGE), "--planner",
               "fast-downward-opt", "--timeout", str(TIMEOUT_S)]
    tailor_process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                      env={**os.environ, "TMPDIR": str(tmp)})
    searching, left = False, {}
    try:
        while tailor_process.poll() is None:
            searching = searching or any("bin/downward" in c for c in processes_naming(str(tmp)).values())
            time.sleep(0.2)
        out, err = tailor_process.communicate()
        time.sleep(0.3)  # what tailor kills needs a moment to go
        left = processes_naming(str(tmp))
        yield tailor_process.returncode, out, err, searching, sorted(left.values())
    finally:
        tailor_process.kill()
        tailor_process.wait()
        for pid in left:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass


def test_fast_downward_out_of_time_is_status_7(timed_out):
    code, out, err, _, _ = timed_out
    assert (code, out) == (7, "")
    assert err == (f"tailor plan: error: {LARGE}: planner 'fast-downward-opt' found no plan within the timeout "
                   f"of {TIMEOUT_S} s\n")


def test_no_planner_process_outlives_the_timeout(timed_out):
    """Fast Downward's driver and search run in a session of their own, out of reach of a signal to the child:
    the parent ends them with it (planner_bridge.worker.end_descendants)."""
    *_, searching, left = timed_out
    if not searching:
        pytest.skip("Fast Downward's search had not started before the timeout (a very loaded machine)")
    assert left == []
