"""`tailor plan` on every bundled domain/problem pair, compared in full with the golden files under
tests/golden/plan/ (regenerate them and see the diff with `python tests/regenerate_golden.py`)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tailor.planner_bridge import AbstractPlan, InputFileError, render_text, resolve_problem
from tailor.cli.main import main

from regenerate_golden import ROOT, bundled_pairs, golden_path, without_provenance

# Fig. 5.6 of the dissertation, with our step ids (1..n in sequence; VHPOP numbers steps backwards).
FIG_5_6_LINKS = [
    {"from": 0, "fact": ["robot", "pos1"], "to": 1},
    {"from": 0, "fact": ["ball", "pos2"], "to": 1},
    {"from": 1, "fact": ["atball", "pos2"], "to": 2},
    {"from": 0, "fact": ["final", "pos3"], "to": "goal"},
    {"from": 2, "fact": ["atball", "pos3"], "to": "goal"},
]


def tailor_plan(capsys, *args: str) -> str:
    assert main(["plan", *args]) == 0
    out, err = capsys.readouterr()
    assert err == ""
    return out


def test_every_bundled_domain_has_two_problems_and_golden_files():
    pairs = bundled_pairs()
    domains = {d for d, _ in pairs}
    assert {"soccer", "kitchen", "arm"} <= domains
    assert all(sum(d == name for d, _ in pairs) >= 2 for name in domains)
    goldens = {p.relative_to(ROOT / "tests/golden/plan") for p in (ROOT / "tests/golden/plan").glob("*/*.*")}
    expected = {golden_path(d, p, s).relative_to(ROOT / "tests/golden/plan") for d, p in pairs for s in (".json", ".txt")}
    assert goldens == expected, "golden files and bundled problems differ: run python tests/regenerate_golden.py"


@pytest.mark.parametrize("domain,problem", bundled_pairs())
def test_plan_json_matches_golden(capsys, domain, problem):
    out = without_provenance(tailor_plan(capsys, domain, problem, "--json"))
    assert out == golden_path(domain, problem, ".json").read_text(encoding="utf-8")
    # the text rendering of the same plan matches its golden file too (`tailor plan` without --json prints it)
    plan = AbstractPlan.from_json(json.loads(out))
    assert render_text(plan) == golden_path(domain, problem, ".txt").read_text(encoding="utf-8")


def test_plan_text_is_the_rendering_of_the_json_plan(capsys):
    assert tailor_plan(capsys, "soccer", "score") == golden_path("soccer", "score", ".txt").read_text(encoding="utf-8")


def test_score_is_the_plan_of_figure_5_6():
    data = json.loads(golden_path("soccer", "score", ".json").read_text(encoding="utf-8"))
    assert list(data)[:8] == ["schema", "units", "domain", "problem", "planner", "steps", "links", "orderings"]
    assert data["schema"] == "tailor.plan/1"
    assert (data["domain"], data["problem"], data["planner"]) == ("soccer", "score", "pyperplan")
    assert data["steps"] == [
        {"id": 1, "action": "approachball", "args": ["pos1", "pos2"]},
        {"id": 2, "action": "dribbleball", "args": ["pos2", "pos3"]},
    ]
    assert data["links"] == FIG_5_6_LINKS
    assert data["orderings"] == [[1, 2]]


def test_waypoints_is_four_gotopose_steps_in_turn():
    data = json.loads(golden_path("soccer", "waypoints", ".json").read_text(encoding="utf-8"))
    assert [(s["action"], s["args"]) for s in data["steps"]] == [
        ("gotopose", ["p0", "w1"]), ("gotopose", ["w1", "w2"]), ("gotopose", ["w2", "w3"]), ("gotopose", ["w3", "w4"])
    ]


def test_resolve_bundled_names_and_paths(tmp_path):
    soccer = ROOT / "domains" / "soccer"
    assert resolve_problem("soccer", "score") == (soccer / "domain.pddl", soccer / "problems" / "score.pddl")
    # a domain file and the name of a problem in the problems/ folder beside it
    assert resolve_problem(soccer / "domain.pddl", "waypoints") == (
        soccer / "domain.pddl", soccer / "problems" / "waypoints.pddl"
    )
    problem = tmp_path / "mine.pddl"
    problem.write_text("(define (problem mine) (:domain soccer))")
    assert resolve_problem("soccer", str(problem)) == (soccer / "domain.pddl", problem)


def test_a_folder_here_named_like_a_bundled_domain_wins_and_says_so(tmp_path, monkeypatch, capsys):
    """An existing path wins over a bundled name; a bare name that is both warns once per command, a path
    written as one (./soccer) does not."""
    import shutil

    from tailor.planner_bridge import bundled

    shutil.copytree(ROOT / "domains" / "soccer", tmp_path / "soccer")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(bundled, "_WARNED", set())
    assert main(["plan", "soccer", "score", "--json"]) == 0
    err = capsys.readouterr().err
    assert err.count("warning: soccer: the folder here, not the bundled domain of that name") == 1
    assert resolve_problem("soccer", "score")[0] == Path("soccer") / "domain.pddl"  # the copy here
    monkeypatch.setattr(bundled, "_WARNED", set())
    assert main(["plan", "./soccer", "score", "--json"]) == 0
    assert "warning" not in capsys.readouterr().err


@pytest.mark.parametrize(
    "domain,problem,named",
    [("socer", "score", "socer"), ("soccer", "scor", "scor"), ("soccer", "nowhere/score.pddl", "nowhere/score.pddl")],
)
def test_resolve_unknown_names_fail_with_the_name(domain, problem, named):
    with pytest.raises(InputFileError) as info:
        resolve_problem(domain, problem)
    assert str(info.value).startswith(f"{named}: ")
    assert info.value.exit_code == 3
