"""`tailor plan soccer score` costs no more CPU than a bare script that parses with unified-planning and solves with
pyperplan (issue 27's floor: at most 1.05 x, paired runs, whole process with its children)."""

from __future__ import annotations

import resource
import statistics
import subprocess
import sys

import pytest

from tailor.planner_bridge import resolve_problem

PAIRS = 11
BARE = ("import sys\nfrom unified_planning.io import PDDLReader\nfrom unified_planning.shortcuts import OneshotPlanner\n"
        "problem = PDDLReader().parse_problem(sys.argv[1], sys.argv[2])\n"
        "with OneshotPlanner(name='pyperplan') as planner:\n    print(len(planner.solve(problem).plan.actions))\n")


def _cpu(command: list[str]) -> float:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


@pytest.mark.benchmark
def test_tailor_plan_costs_no_more_cpu_than_a_bare_script():
    domain, problem = map(str, resolve_problem("soccer", "score"))
    ratios, ours, bare = [], [], []
    for _ in range(PAIRS):
        ours.append(_cpu([sys.executable, "-m", "tailor.cli", "plan", "soccer", "score"]))
        bare.append(_cpu([sys.executable, "-c", BARE, domain, problem]))
        ratios.append(ours[-1] / bare[-1])
    print(f"\ntailor plan soccer score: median CPU {statistics.median(ours):.3f} s; bare unified-planning + pyperplan "
          f"{statistics.median(bare):.3f} s; median paired ratio {statistics.median(ratios):.3f} ({PAIRS} pairs)")
    assert statistics.median(ratios) <= 1.05
