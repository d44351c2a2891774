"""POCL (tailor-pocl) against deordered pyperplan on the bundled and classic test problems: time, plan
length, ordering constraints and width, one table (also `python -m tailor.planner_bridge.benchmark`)."""

import pytest

from tailor.planner_bridge.benchmark import LIMIT_S, default_problems, measure, table


@pytest.mark.benchmark
def test_pocl_vs_pyperplan_table():
    print("\n" + table(default_problems(), ["pocl", "pyperplan"], repeat=3))


@pytest.mark.benchmark
@pytest.mark.parametrize("domain, problem", default_problems(), ids=lambda p: f"{p.parent.name}/{p.stem}")
def test_pocl_solves_within_the_limit_and_commits_no_more_than_deordering(domain, problem):
    pocl, deordered = measure(domain, problem, "pocl"), measure(domain, problem, "pyperplan")
    assert "error" not in pocl and pocl["seconds"] < LIMIT_S
    if "error" not in deordered and pocl["steps"] == deordered["steps"]:
        assert pocl["pairs"] <= deordered["pairs"]
