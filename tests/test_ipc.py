"""IPC plan files in and out: `tailor plan --format ipc` writes the sequential plan Fast Downward's `sas_plan`
looks like; planner_bridge.ipc reads such a file (any planner's), each malformed line one error naming
file:line:col, and plan_from_ipc makes it our validated, linked AbstractPlan, or says which line is wrong."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from tailor.cli.main import main
from tailor.errors import InputFileError, PDDLSyntaxError, PlannerError
from tailor.planner_bridge import (AbstractPlan, CausalLink, Step, format_ipc, ipc, parse_task, plan_from_ipc,
                                   read_ipc_plan, read_pddl, resolve_problem)
from tailor.planner_bridge.up_interop import link_plan

FIXTURES = Path(__file__).parent / "fixtures" / "pddl"
GRIPPER = (FIXTURES / "gripper" / "domain.pddl", FIXTURES / "gripper" / "p01.pddl")
# Fast Downward 26.6's sas_plan for gripper p01, verbatim (`fast-downward.py --alias seq-opt-lmcut`).
SAS_PLAN = """(pick ball1 rooma right)
(pick ball2 rooma left)
(move rooma roomb)
(drop ball1 roomb right)
(drop ball2 roomb left)
(move roomb rooma)
(pick ball3 rooma right)
(pick ball4 rooma left)
(move rooma roomb)
(drop ball3 roomb right)
(drop ball4 roomb left)
; cost = 11 (unit cost)
"""


@pytest.fixture(scope="module")
def gripper():
    return read_pddl(*GRIPPER)


def write(tmp_path: Path, text: str, name: str = "sas_plan") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def tailor_plan(capsys, *args: str) -> str:
    assert main(["plan", *args]) == 0
    out, err = capsys.readouterr()
    assert err == ""
    return out


# --- out ------------------------------------------------------------------------------------------------
def test_format_ipc_is_one_action_a_line_then_the_unit_cost(capsys):
    out = tailor_plan(capsys, "soccer", "score", "--format", "ipc")
    assert out == "(approachball pos1 pos2)\n(dribbleball pos2 pos3)\n; cost = 2 (unit cost)\n"


def test_format_ipc_writes_a_linearization_of_the_partial_order_in_lower_case():
    # ids 1..3, but the orderings (and a causal link) put step 3 first: the file must follow them
    plan = AbstractPlan("d", "p", "pocl",
                        steps=(Step(1, "Move", ("A", "b")), Step(2, "move", ("b", "c")), Step(3, "pick", ("x",))),
                        links=(CausalLink(3, ("holding", "x"), 1), CausalLink(1, ("at", "b"), 2)),
                        orderings=((1, 2),))
    assert format_ipc(plan) == "(pick x)\n(move a b)\n(move b c)\n; cost = 3 (unit cost)\n"
    assert [s.id for s in ipc.linearization(plan)] == [3, 1, 2]


def test_an_ordering_cycle_has_no_linearization():
    plan = AbstractPlan("d", "p", "x", (Step(1, "a", ()), Step(2, "b", ())), (), ((1, 2), (2, 1)))
    with pytest.raises(PlannerError, match="cycle"):
        format_ipc(plan)


def test_the_empty_plan_is_its_cost_line_alone(tmp_path, capsys):
    domain = FIXTURES / "blocks" / "domain.pddl"
    problem = write(tmp_path, "(define (problem done) (:domain blocks) (:objects a - block)\n"
                              "  (:init (ontable a) (clear a) (handempty)) (:goal (ontable a)))\n", "done.pddl")
    out = tailor_plan(capsys, str(domain), str(problem), "--format", "ipc")
    assert out == "; cost = 0 (unit cost)\n"
    plan = plan_from_ipc(read_pddl(domain, problem), write(tmp_path, out))
    assert plan.steps == () and plan.links == (CausalLink(0, ("ontable", "a"), "goal"),)


def test_json_and_format_ipc_together_are_a_usage_error(capsys):
    with pytest.raises(SystemExit) as caught:
        main(["plan", "soccer", "score", "--json", "--format", "ipc"])
    assert caught.value.code == 2
    assert "not allowed with" in capsys.readouterr().err


def test_json_flag_and_format_json_print_the_same(capsys):
    from regenerate_golden import without_provenance  # (whose command lines differ)

    assert without_provenance(tailor_plan(capsys, "soccer", "score", "--json")) == without_provenance(
        tailor_plan(capsys, "soccer", "score", "--format", "json"))


@pytest.mark.parametrize("domain, problem, planner", [
    ("soccer", "score", "pyperplan"),
    ("soccer", "waypoints", "pyperplan"),
    (str(GRIPPER[0]), str(GRIPPER[1]), "pyperplan"),  # negative preconditions, compiled away for pyperplan
    (str(FIXTURES / "logistics" / "domain.pddl"), str(FIXTURES / "logistics" / "p02.pddl"), "pyperplan"),
    (str(FIXTURES / "logistics" / "domain.pddl"), str(FIXTURES / "logistics" / "p02.pddl"), "pocl"),
    (str(FIXTURES / "briefcase" / "domain.pddl"), str(FIXTURES / "briefcase" / "p01.pddl"), "pyperplan"),
])
def test_plan_written_as_ipc_reads_back_as_the_same_plan(tmp_path, capsys, domain, problem, planner):
    """`tailor plan --format ipc` read back by plan_from_ipc: the same steps in the order written; a plan whose
    step ids are its sequence (deordered pyperplan) comes back with the same links and orderings too."""
    planned = AbstractPlan.from_json(json.loads(tailor_plan(capsys, domain, problem, "--planner", planner, "--json")))
    written = tailor_plan(capsys, domain, problem, "--planner", planner, "--format", "ipc")
    assert written.endswith(f"; cost = {len(planned.steps)} (unit cost)\n")
    back = plan_from_ipc(read_pddl(*resolve_problem(domain, problem)), write(tmp_path, written))
    assert back.planner == "given" and (back.domain, back.problem) == (planned.domain, planned.problem)
    assert [(s.action, s.args) for s in back.steps] == [(s.action, s.args) for s in ipc.linearization(planned)]
    if planner == "pyperplan":
        assert (back.steps, back.links, back.orderings) == (planned.steps, planned.links, planned.orderings)
        assert back.objects and back.initial  # what refinement needs of the problem comes with it


# --- in -------------------------------------------------------------------------------------------------
def test_fast_downwards_sas_plan_is_read_validated_and_linked(tmp_path, gripper):
    plan = plan_from_ipc(gripper, write(tmp_path, SAS_PLAN))
    assert [(s.id, s.action, s.args) for s in plan.steps][:3] == [
        (1, "pick", ("ball1", "rooma", "right")), (2, "pick", ("ball2", "rooma", "left")),
        (3, "move", ("rooma", "roomb"))]
    assert len(plan.steps) == 11 and plan.planner == "given" and plan.domain == "gripper-neg"
    assert CausalLink(1, ("carry", "ball1", "right"), 4) in plan.links
    assert (1, 2) not in plan.orderings  # the two picks are unordered: the plan is deordered, not a chain
    # the same plan as link_plan makes of unified-planning's own objects
    problem = parse_task(gripper)
    lines = read_ipc_plan(write(tmp_path, SAS_PLAN))
    from unified_planning.plans import SequentialPlan

    sequential = SequentialPlan([ipc._instance(problem, line, "f") for line in lines], problem.environment)
    assert link_plan(problem, sequential, domain="gripper-neg") == plan


def test_timestamps_durations_comments_case_crlf_and_bom_are_read(tmp_path):
    text = ("\ufeff; a timed plan, as temporal planners write it\r\n\r\n"
            "0.000: (PICK Ball1 roomA left) [1.000]\r\n"
            "  1: (move rooma roomb)   ; the robot goes\r\n"
            "1: (drop ball1 roomb left)[1]\r\n"
            "2.5e0 : ( move roomb rooma )\r\n")
    path = tmp_path / "timed.plan"
    path.write_bytes(text.encode("utf-8"))
    lines = read_ipc_plan(path)
    assert [(x.action, x.args, x.line) for x in lines] == [
        ("pick", ("ball1", "rooma", "left"), 3), ("move", ("rooma", "roomb"), 4),
        ("drop", ("ball1", "roomb", "left"), 5), ("move", ("roomb", "rooma"), 6)]


@pytest.mark.parametrize("text, line, col, message", [
    ("(pick ball1 rooma left\n", 1, 1, "not closed on this line"),
    ("(move rooma roomb)\n(pick (ball1) rooma left)\n", 2, 7, "'(' inside an action"),
    ("; ok\n(move rooma roomb) (move roomb rooma)\n", 2, 20, "unexpected '(move' after the action"),
    ("(move rooma roomb))\n", 1, 19, "unexpected ')'"),
    ("()\n", 1, 1, "empty action"),
    ("   move rooma roomb\n", 1, 4, "expected an action '(name arg ...)', found 'move'"),
    ("1.0 (move rooma roomb)\n", 1, 1, "found '1.0'"),
    ("0.5:\n", 1, 5, "after the timestamp"),
    ("(move rooma roomb) [fast]\n", 1, 20, "unexpected '[fast]'"),
    ("2: (move rooma roomb)\n1: (move roomb rooma)\n", 2, 1, "timestamp 1 is earlier than the one before it"),
])
def test_each_malformed_line_is_one_error_naming_file_line_and_column(tmp_path, text, line, col, message):
    path = write(tmp_path, text)
    with pytest.raises(PDDLSyntaxError, match=re.escape(message)) as caught:
        read_ipc_plan(path)
    error = caught.value
    assert (error.file, error.line, error.col, error.exit_code) == (str(path), line, col, 4)
    assert str(error).startswith(f"{path}:{line}:{col}: ") and "\n" not in str(error)


def test_a_missing_unreadable_or_too_large_plan_file_is_an_input_file_error(tmp_path, monkeypatch):
    for path, message in ((tmp_path / "none", "no such file"), (tmp_path, "not a file")):
        with pytest.raises(InputFileError, match=message) as caught:
            read_ipc_plan(path)
        assert caught.value.exit_code == 3
    binary = tmp_path / "binary.plan"
    binary.write_bytes(b"(move \xff)\n")
    with pytest.raises(InputFileError, match="not a UTF-8 text file"):
        read_ipc_plan(binary)
    monkeypatch.setattr(ipc, "MAX_PLAN_BYTES", 20)
    with pytest.raises(InputFileError, match=r"too large to read \(38 bytes; at most 20\)"):
        read_ipc_plan(write(tmp_path, "(move rooma roomb)\n(move roomb rooma)\n"))


def test_a_malformed_plan_fails_before_the_pddl_is_parsed(tmp_path, gripper, monkeypatch):
    monkeypatch.setattr(ipc, "parse_task", lambda task: pytest.fail("the PDDL was parsed"))
    with pytest.raises(PDDLSyntaxError):
        plan_from_ipc(gripper, write(tmp_path, "(move\n"))


@pytest.mark.parametrize("text, line, message", [
    ("(pick ball1 rooma left)\n(mvoe rooma roomb)\n", 2,
     r"\(mvoe rooma roomb\): unknown action 'mvoe' \(did you mean 'move'\?\)"),
    ("(fly rooma roomb)\n", 1, r"unknown action 'fly' \(the domain's actions: drop, move, pick\)"),
    ("(move rooma roomb)\n(pick ball9 roomb left)\n", 2, "unknown object 'ball9' \\(argument 1;"),
    ("(move rooma)\n", 1, r"move takes 2 argument\(s\) \(\?from - room \?to - room\), not 1"),
    ("(pick rooma rooma left)\n", 1, r"argument 1, rooma, is of type room, not ball \(\?b of pick\)"),
    ("(move rooma roomb)\n(pick ball1 rooma left)\n", 2,
     r"step 2, \(pick ball1 rooma left\), cannot be applied: \(at-robby rooma\) does not hold"),
    ("(pick ball1 rooma left)\n(pick ball2 rooma left)\n", 2, r"\(not \(busy left\)\) does not hold"),
    ("(pick ball1 rooma left)\n", None,
     (r"does not reach the goal: \(at ball1 roomb\) \(at ball2 roomb\) \(at ball3 roomb\) \(at ball4 roomb\) "
      r"\(not \(busy left\)\) do not hold after its 1 step\(s\)")),
])
def test_a_plan_the_problem_refutes_is_a_planner_error_naming_the_line(tmp_path, gripper, text, line, message):
    path = write(tmp_path, text)
    with pytest.raises(PlannerError, match=message) as caught:
        plan_from_ipc(gripper, path)
    error = caught.value
    assert type(error) is PlannerError and error.exit_code == 1  # "a plan the validator rejects"
    assert (error.file, error.line) == (str(path), line)
    assert str(error).startswith(f"{path}:{line}: " if line else f"{path}: ")


def test_refine_takes_a_plan_file_another_planner_wrote(tmp_path, capsys):
    """`tailor refine --plan FILE`: the plan file is validated, linked and refined as a planned one would be."""
    from tailor.cli.main import main

    assert main(["plan", "soccer", "score", "--format", "ipc"]) == 0
    plan_file = tmp_path / "sas_plan"
    plan_file.write_text(capsys.readouterr().out)
    assert main(["-q", "refine", "soccer", "score", "--plan", str(plan_file), "--optimizer", "sample", "--json"]) == 0
    given = json.loads(capsys.readouterr().out)
    assert main(["-q", "refine", "soccer", "score", "--optimizer", "sample", "--json"]) == 0
    planned = json.loads(capsys.readouterr().out)
    assert given["planner"] == "given" and given["free_parameters"] == planned["free_parameters"]
    plan_file.write_text("(dribbleball pos2 pos3)\n")
    assert main(["refine", "soccer", "score", "--plan", str(plan_file)]) == 1
    assert capsys.readouterr().err.strip() == (f"tailor refine: error: {plan_file}:1: step 1, (dribbleball pos2 pos3), "
                                               "cannot be applied: (atball pos2) does not hold")
