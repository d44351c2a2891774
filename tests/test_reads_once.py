"""Each input is read once per command: one `tailor refine soccer score --simulate` opens domain.pddl, the
problem, the binding and the belief file once each, the planner's child process included.

An audit hook (sitecustomize.py on PYTHONPATH, so every Python process of the command has it) logs every file
opened for reading whose name ends in .pddl or .toml.
"""

from __future__ import annotations

import collections
import os
import subprocess
import sys
from pathlib import Path

from tailor.planner_bridge.bundled import DOMAINS_DIR

HOOK = '''
import os, sys

def _log_reads(event, args):
    if event == "open" and isinstance(args[0], (str, bytes, os.PathLike)):
        name = os.fsdecode(args[0])
        mode = args[1] if len(args) > 1 and isinstance(args[1], str) else "r"
        if name.endswith((".pddl", ".toml")) and "w" not in mode and "a" not in mode:
            with open(os.environ["TAILOR_READ_LOG"], "a", encoding="utf-8") as log:
                log.write(f"{os.getpid()} {os.path.realpath(name)}\\n")

sys.addaudithook(_log_reads)
'''


def reads(tmp_path: Path, *command: str) -> tuple[collections.Counter, set[str]]:
    """How often `command` (run with the hook) read each .pddl and .toml file, and the processes that read."""
    (tmp_path / "hook").mkdir()
    (tmp_path / "hook" / "sitecustomize.py").write_text(HOOK)
    log = tmp_path / "reads.log"
    env = {**os.environ, "TAILOR_READ_LOG": str(log),
           "PYTHONPATH": os.pathsep.join([str(tmp_path / "hook"), os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run(command, capture_output=True, text=True, env=env, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    lines = log.read_text().splitlines() if log.exists() else []
    return collections.Counter(line.split(" ", 1)[1] for line in lines), {line.split(" ", 1)[0] for line in lines}


def test_refine_reads_each_input_once(tmp_path):
    counts, processes = reads(tmp_path, sys.executable, "-m", "tailor.cli", "-q", "refine", "soccer", "score",
                              "--simulate")
    soccer = DOMAINS_DIR.resolve() / "soccer"
    expected = {soccer / "domain.pddl", soccer / "problems" / "score.pddl", soccer / "actions.toml",
                soccer / "problems" / "score.toml"}
    assert {Path(name): n for name, n in counts.items()} == {path: 1 for path in expected}
    assert len(processes) == 1  # the command alone: its planner child plans from the texts it was sent


def test_the_hook_sees_a_second_read(tmp_path):
    """The count could fail: a command that reads the problem twice (plan, then refine's own check) is seen."""
    script = ("from tailor.planner_bridge import resolve_problem\nfrom pathlib import Path\n"
              "d, p = resolve_problem('soccer', 'score')\nPath(p).read_text(); Path(p).read_text()\n")
    counts, _ = reads(tmp_path, sys.executable, "-c", script)
    assert counts == {str((DOMAINS_DIR / "soccer" / "problems" / "score.pddl").resolve()): 2}
