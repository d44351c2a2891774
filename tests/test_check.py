"""`tailor check`: the free parameters, the belief values read, and the warnings a user needs before a robot
moves (a belief value never read; a quantity the belief gives left free; a `read` on a fact never true
initially, which made a user's shelf and desk free parameters that refinement moved onto the start)."""

from __future__ import annotations

import json
import shutil

import pytest

from tailor.cli.main import main
from tailor.planner_bridge.bundled import DOMAINS_DIR


@pytest.fixture
def soccer(tmp_path):
    domain = tmp_path / "soccer"
    shutil.copytree(DOMAINS_DIR / "soccer", domain, ignore=shutil.ignore_patterns("training"))
    return domain


@pytest.mark.parametrize("domain", ["soccer", "arm", "kitchen"])
def test_the_bundled_problems_have_no_warnings(domain, capsys):
    assert main(["check", domain, "--json", "--strict"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["problems"] and all(p["warnings"] == [] for p in report["problems"])
    assert all(b["read"] for p in report["problems"] for b in p["belief"])


def test_free_parameters_and_belief_values_are_listed(capsys):
    assert main(["check", "soccer", "score"]) == 0
    out = capsys.readouterr().out
    assert "free parameters: 2" in out and "pos2.phi" in out and "pos2.v" in out
    assert "belief values: 10" in out and "NOT READ" not in out and "no warnings" in out


def test_a_read_on_a_fact_never_true_initially_is_said_and_strict_makes_it_an_error(soccer, capsys):
    binding = soccer / "actions.toml"
    text = binding.read_text()
    text = text.replace('[predicates.final]\nread = ["x", "y", "phi", "v"]\n', '[predicates.final]\n')
    text = text.replace('[predicates.atball]\n', '[predicates.atball]\nread = ["x", "y"]\n')
    binding.write_text(text)
    domain = str(soccer / "domain.pddl")
    assert main(["check", domain, "score", "--json"]) == 0
    warnings = json.loads(capsys.readouterr().out)["problems"][0]["warnings"]
    assert any(w.startswith("[predicates.atball] read = ['x', 'y'] reads nothing: no (atball ...) fact is true "
                            "initially") for w in warnings)
    # the goal pose's values in the belief go unread: its position is left to refinement to choose
    assert any(w.startswith("pos3.x is free in [-4, 4] and refinement will choose it, although") for w in warnings)
    assert main(["check", domain, "score", "--strict"]) == 11
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("tailor check: error: ") and "(--strict)" in err[0]


def test_a_belief_value_left_free_is_said_by_refine_too(soccer, capsys):
    belief = soccer / "problems" / "score.toml"
    belief.write_text(belief.read_text().replace("[objects.pos2]\n", "[objects.pos2]\nphi = 1.0\n"))
    assert main(["-q", "refine", str(soccer / "domain.pddl"), "score", "--optimizer", "sample"]) == 0
    err = capsys.readouterr().err
    assert "pos2.phi is free in [-3.14159, 3.14159] and refinement will choose it, although" in err
    assert "gives phi = 1" in err


def test_a_value_for_an_object_no_action_uses_is_never_read(soccer, capsys):
    problem = soccer / "problems" / "score.pddl"
    problem.write_text(problem.read_text().replace("(:objects pos1 pos2 pos3 - pos)", "(:objects pos1 pos2 pos3 pos4 - pos)"))
    belief = soccer / "problems" / "score.toml"
    belief.write_text(belief.read_text() + "\n[objects.pos4]\nx = 0.5\n")
    assert main(["check", str(soccer / "domain.pddl"), "score"]) == 0
    out = capsys.readouterr().out
    assert "pos4.x               0.5        NOT READ" in out
    assert f"warning: [objects.pos4] x = 0.5 in {belief} is never read" in out
