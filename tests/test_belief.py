"""Belief state files: the bundled ones, and every error path."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from tailor.planner_bridge.abstract_plan import AbstractPlan
from tailor.refinement.belief import belief_path_for, load_belief
from tailor.refinement.binding import load_domain_binding
from tailor.errors import BeliefError
from tailor.refinement.instantiate import instantiate

SOCCER = Path(__file__).resolve().parents[1] / "domains" / "soccer"
FIXTURES = Path(__file__).parent / "fixtures" / "binding"


def test_belief_path_is_beside_the_problem_with_the_same_stem():
    assert belief_path_for(SOCCER / "problems" / "score.pddl") == SOCCER / "problems" / "score.toml"
    assert belief_path_for("a/b.c/p.pddl") == Path("a/b.c/p.toml")


def test_score_belief_is_fig_5_3():
    belief = load_belief(SOCCER / "problems" / "score.toml", objects=["pos1", "pos2", "pos3"])
    assert {o: dict(v) for o, v in belief.objects.items()} == {
        "pos1": {"x": 0.0, "y": 1.0, "phi": 0.0, "v": 0.0},
        "pos2": {"x": 3.0, "y": 1.0},
        "pos3": {"x": 1.0, "y": 3.0, "phi": 2.6, "v": 0.0},
    }
    assert belief.value("POS3", "phi") == 2.6


def soccer_problems() -> list[Path]:
    return sorted((SOCCER / "problems").glob("*.pddl"))


def test_every_bundled_problem_has_a_valid_belief_file_and_instantiates():
    from unified_planning.io import PDDLReader

    assert {p.stem for p in soccer_problems()} >= {"score", "waypoints"}
    binding = load_domain_binding(SOCCER)
    for problem_file in soccer_problems():
        problem = PDDLReader().parse_problem(str(SOCCER / "domain.pddl"), str(problem_file))
        belief = load_belief(belief_path_for(problem_file), objects=[o.name for o in problem.all_objects])
        fixture = FIXTURES / f"{problem_file.stem}_plan.json"
        if fixture.exists():  # every value the binding reads for the plan is there and in range
            instantiate(AbstractPlan.from_json(json.loads(fixture.read_text())), binding, belief)


def test_waypoints_are_a_zig_zag_a_metre_or_two_apart_inside_the_field():
    belief = load_belief(SOCCER / "problems" / "waypoints.toml")
    points = [(belief.value(o, "x"), belief.value(o, "y")) for o in ("p0", "w1", "w2", "w3", "w4")]
    for (x0, y0), (x1, y1) in zip(points, points[1:]):
        assert 1.0 <= ((x1 - x0) ** 2 + (y1 - y0) ** 2) ** 0.5 <= 2.0
        assert -4.0 < x1 < 4.0 and -3.0 < y1 < 3.0
    turns = [(b[1] - a[1]) * (c[1] - b[1]) < 0 for a, b, c in zip(points, points[1:], points[2:])]
    assert all(turns)  # y goes up and down alternately


BAD_BELIEFS = [
    ("[objects.pos1]\nz = 1.0\n", r"\[objects.pos1\] z: unknown quantity 'z' \(known: x, y, phi, v\)"),
    ("[objects.pos1]\nx = \"one\"\n", r"\[objects.pos1\] x = 'one' is not a number"),
    ("[objects.pos1]\nx = true\n", r"\[objects.pos1\] x = True is not a number"),
    ("[objects.pos1]\nx = [1.0]\n", r"\[objects.pos1\] x = \[1.0\] is not a number"),
    ("[objects.pos1]\nx = nan\n", r"\[objects.pos1\] x = nan is not a finite number"),
    ("[objects.pos1]\nx = -inf\n", r"\[objects.pos1\] x = -inf is not a finite number"),
    ("[objects.pos9]\nx = 1.0\n",
     r"\[objects.pos9\]: 'pos9' is not an object of the problem \(objects: pos1, pos2\)"),
    ("[objects.pos1]\nx = 1.0\n[objects.POS1]\nx = 1.0\n", r"\[objects.POS1\] given twice"),
    ("[objects]\npos1 = 3\n", r"\[objects.pos1\] must be a table of quantities"),
    ("objects = 3\n", r"'objects' must be a table of tables"),
    ("[pos1]\nx = 1.0\n", r"unknown top-level key 'pos1' \(expected \[objects.NAME\] tables\)"),
    ("schema = 7\n", r"unsupported schema 7 \(expected 1\)"),
]


@pytest.mark.parametrize("text, message", BAD_BELIEFS)
def test_belief_errors_name_the_file_and_the_problem(tmp_path, text, message):
    path = tmp_path / "p.toml"
    path.write_text(text)
    with pytest.raises(BeliefError, match=f"^{re.escape(str(path))}: {message}") as info:
        load_belief(path, objects=["pos1", "pos2"], quantities=load_domain_binding(SOCCER).quantities)
    assert "\n" not in str(info.value) and info.value.exit_code == 10


def test_quantities_are_not_checked_without_the_simulator(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text("[objects.pos1]\nz = 1.5\n")
    assert load_belief(path, objects=["pos1"]).value("pos1", "z") == 1.5
    with pytest.raises(BeliefError, match=r"z: unknown quantity 'z' \(known: x, y\)$"):
        load_belief(path, objects=["pos1"], quantities=("x", "y"))


def test_objects_are_not_checked_without_the_problem(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text("[objects.pos9]\nx = 1\n")
    assert load_belief(path).value("pos9", "x") == 1.0


def test_missing_belief_file(tmp_path):
    where = re.escape(str(tmp_path / "q.toml"))
    with pytest.raises(BeliefError, match=rf"^{where}: belief state file not found$"):
        load_belief(tmp_path / "q.toml")


def test_bad_toml_gives_line_and_column(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text("[objects.pos1]\nx = 1.0\ny = = 2\n")
    with pytest.raises(BeliefError, match=rf"^{re.escape(str(path))}:3:5: invalid TOML: Invalid value$"):
        load_belief(path)


def test_missing_value_names_object_and_quantity(tmp_path):
    path = tmp_path / "score.toml"
    path.write_text("[objects.pos1]\nx = 0.0\ny = 1.0\nphi = 0.0\nv = 0.0\n[objects.pos2]\nx = 3.0\n"
                    "[objects.pos3]\nx = 1.0\ny = 3.0\nphi = 2.6\nv = 0.0\n")
    plan = AbstractPlan.from_json(json.loads((FIXTURES / "score_plan.json").read_text()))
    with pytest.raises(BeliefError, match=rf"^{re.escape(str(path))}: object 'pos2' has no value for 'y' "
                                          r"\(needed by \(ball pos2\) in the initial state\)$"):
        instantiate(plan, load_domain_binding(SOCCER), load_belief(path))
