"""Fast Downward (`--planner fast-downward`, the extra `tailor[planners]`) against pyperplan on a large classic
instance, 50 blocks (tests/fixtures/pddl/blocks/large-50.pddl), each through the planner bridge with a timeout
of a minute: wall and CPU seconds (the planner child and its children included), plan length.

    pytest -m benchmark tests/benchmarks/test_fast_downward_vs_pyperplan.py -s
"""

from __future__ import annotations

import importlib.util
import resource
import time
from pathlib import Path

import pytest

from tailor.errors import PlannerError, PlannerTimeoutError
from tailor.planner_bridge import plan_files

FIXTURES = Path(__file__).resolve().parent.parent / "fixtures" / "pddl"
BLOCKS, LARGE = FIXTURES / "blocks" / "domain.pddl", FIXTURES / "blocks" / "large-50.pddl"
LIMIT_S = 60.0


def measure(planner: str) -> dict:
    """Plan the large instance once; wall and CPU seconds, and the plan's length or the error's class."""
    before, start = resource.getrusage(resource.RUSAGE_CHILDREN), time.perf_counter()
    try:
        outcome = {"steps": len(plan_files(BLOCKS, LARGE, planner, timeout=LIMIT_S).steps)}
    except PlannerError as exc:
        outcome = {"error": type(exc).__name__}
    wall, after = time.perf_counter() - start, resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    return {"planner": planner, "wall": wall, "cpu": cpu, **outcome}


@pytest.mark.benchmark
@pytest.mark.skipif(importlib.util.find_spec("up_fast_downward") is None, reason="pip install 'tailor[planners]'")
def test_fast_downward_plans_in_seconds_what_pyperplan_cannot_in_a_minute():
    rows = [measure("fast-downward"), measure("pyperplan")]
    print(f"\n{LARGE.name} (timeout {LIMIT_S:g} s)")
    print(f"{'planner':<15}{'wall s':>8}{'CPU s':>8}  plan")
    for row in rows:
        print(f"{row['planner']:<15}{row['wall']:>8.1f}{row['cpu']:>8.1f}  "
              f"{row.get('steps', row.get('error'))}{' steps' if 'steps' in row else ''}")
    fast_downward, pyperplan = rows
    assert "steps" in fast_downward and fast_downward["wall"] < 10
    assert pyperplan.get("error") == PlannerTimeoutError.__name__
