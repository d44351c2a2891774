"""Each input is read once per command (issue 27), the planner child included: the parent reads and checks the
pair, the child plans from the texts it is sent. Counted with an audit hook (sys.addaudithook) that a
sitecustomize module installs in every Python process started with it on PYTHONPATH, the child included."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tailor.planner_bridge import resolve_problem
from tailor.planner_bridge.worker import CHILD_MODULE

# Written to a folder put first on PYTHONPATH: Python imports it at start-up (site), before any of our code.
SITECUSTOMIZE = '''\
import os
import sys

_LOG = os.open(os.environ["TAILOR_READ_LOG"], os.O_WRONLY | os.O_APPEND | os.O_CREAT)
os.write(_LOG, f"start {os.getpid()} {' '.join(sys.orig_argv)}\\n".encode())


def _opened(event, args):
    if event == "open" and isinstance(args[0], (str, bytes, os.PathLike)):
        path = os.fsdecode(args[0])
        if path.endswith(".pddl"):
            os.write(_LOG, f"open {os.getpid()} {os.path.realpath(path)}\\n".encode())


sys.addaudithook(_opened)
'''


def opened(tmp_path: Path, script: str, *args: str) -> tuple[dict[int, str], list[tuple[int, str]]]:
    """Run `script` in a new Python process with the audit hook: (pid -> command line of every Python process
    it started, itself included; (pid, path) of every .pddl file opened, in order)."""
    hook = tmp_path / "hook"
    hook.mkdir()
    (hook / "sitecustomize.py").write_text(SITECUSTOMIZE, encoding="utf-8")
    log = tmp_path / "reads.log"
    env = {**os.environ, "TAILOR_READ_LOG": str(log),
           "PYTHONPATH": os.pathsep.join([str(hook), *filter(None, [os.environ.get("PYTHONPATH")])])}
    done = subprocess.run([sys.executable, "-c", script, *args], env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    processes, opens = {}, []
    for line in log.read_text(encoding="utf-8").splitlines():
        kind, pid, rest = line.split(" ", 2)
        if kind == "start":
            processes[int(pid)] = rest
        else:
            opens.append((int(pid), rest))
    return processes, opens


PLAN_FILES = "import sys; from tailor.planner_bridge import plan_files; print(plan_files(*sys.argv[1:]).to_text())"
PLAN_HERE = "import sys; from tailor.planner_bridge import plan_here; print(plan_here(*sys.argv[1:]).to_text())"


@pytest.mark.skipif(not hasattr(sys, "addaudithook"), reason="needs audit hooks")
def test_plan_files_reads_each_file_once_across_parent_and_planner_child(tmp_path):
    domain, problem = (os.path.realpath(p) for p in resolve_problem("soccer", "score"))
    processes, opens = opened(tmp_path, PLAN_FILES, domain, problem)
    children = [pid for pid, command in processes.items() if CHILD_MODULE in command]
    assert len(processes) == 2 and len(children) == 1, processes  # the hook ran in the planner child too
    assert sorted(path for _, path in opens) == sorted([domain, problem])  # each once, nothing else
    assert not [path for pid, path in opens if pid in children]  # the child plans from the texts it was sent


@pytest.mark.skipif(not hasattr(sys, "addaudithook"), reason="needs audit hooks")
def test_plan_here_reads_each_file_once(tmp_path):
    domain, problem = (os.path.realpath(p) for p in resolve_problem("soccer", "score"))
    processes, opens = opened(tmp_path, PLAN_HERE, domain, problem)
    assert len(processes) == 1
    assert sorted(path for _, path in opens) == sorted([domain, problem])
