"""POCL (tailor-pocl) against deordered pyperplan on the bundled, classic test and parallel problems (those of
tests/benchmarks/pocl): time, plan length, ordering constraints and width side by side, one table (also
`python -m tailor.planner_bridge.benchmark tests/fixtures/pddl/{gripper,blocks,logistics,briefcase}
tests/benchmarks/pocl`); every POCL plan checked as the deordered ones are."""

from pathlib import Path

import pytest
from test_planner_bridge import check_plan  # beside tests/conftest.py, which pytest puts on the import path

from tailor.planner_bridge.benchmark import LIMIT_S, default_problems, measure, table

FIXTURES = Path(__file__).resolve().parent.parent / "fixtures" / "pddl"
CLASSIC = tuple(FIXTURES / name for name in ("gripper", "blocks", "logistics", "briefcase"))
PARALLEL = Path(__file__).resolve().parent / "pocl"  # its logistics problems take the classic logistics domain
PROBLEMS = default_problems(*CLASSIC, PARALLEL)


@pytest.mark.benchmark
def test_pocl_vs_pyperplan_table():
    print("\n" + table(PROBLEMS, ("pocl", "pyperplan"), repeat=3))


@pytest.mark.benchmark
@pytest.mark.parametrize("domain, problem", PROBLEMS, ids=lambda p: f"{p.parent.name}/{p.stem}")
def test_pocl_solves_within_the_limit_soundly_and_commits_no_more_than_deordering(domain, problem):
    from tailor.planner_bridge.reading import read_problem

    pocl, deordered = measure(domain, problem, "pocl"), measure(domain, problem, "pyperplan")
    assert "error" not in pocl and pocl["seconds"] < LIMIT_S
    check_plan(read_problem(domain, problem)[0], pocl["plan"])  # valid in id order, links, every linearization
    if "error" not in deordered and pocl["steps"] <= deordered["steps"]:
        assert pocl["pairs"] <= deordered["pairs"]
