"""`tailor-pocl` is an engine of unified-planning once tailor is imported, whichever of the two comes first, and
`import tailor` does not import unified-planning for it."""

from __future__ import annotations

import subprocess
import sys

import pytest

SOLVE = ("from unified_planning.io import PDDLReader\n"
         "from tailor.planner_bridge import resolve_problem\n"
         "from unified_planning.shortcuts import OneshotPlanner\n"
         "problem = PDDLReader().parse_problem(*map(str, resolve_problem('soccer', 'score')))\n"
         "with OneshotPlanner(name='tailor-pocl') as planner:\n"
         "    print(planner.name, planner.solve(problem).status.name)\n")


@pytest.mark.parametrize("first", [
    "import tailor\nimport sys\nassert 'unified_planning' not in sys.modules\n",
    "import unified_planning.shortcuts\nunified_planning.shortcuts.get_environment().factory\nimport tailor\n",
])
def test_tailor_pocl_is_found_by_name_after_import_tailor(first):
    done = subprocess.run([sys.executable, "-c", first + SOLVE], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split() == ["tailor-pocl", "SOLVED_SATISFICING"]


def test_without_import_tailor_unified_planning_does_not_know_it():
    """The test above could fail: unified-planning alone has no engine of that name."""
    script = ("from unified_planning.shortcuts import OneshotPlanner\n"
              "try:\n    OneshotPlanner(name='tailor-pocl')\nexcept Exception as exc:\n    print(type(exc).__name__)\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert done.stdout.strip() == "UPNoRequestedEngineAvailableException"
