"""`tailor refine` on every bundled problem that can be refined, compared in full with tests/golden/refine/
(regenerate with `python tests/regenerate_golden.py`), and its errors."""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from regenerate_golden import refine_golden_path, refine_pairs, tailor_refine_output

from tailor.cli.main import main

PAIRS = refine_pairs()


def test_the_soccer_problems_can_be_refined():
    assert ("soccer", "score") in PAIRS and ("soccer", "waypoints") in PAIRS


@pytest.mark.parametrize("domain, problem", PAIRS)
def test_refine_json_matches_golden(domain, problem):
    assert tailor_refine_output(domain, problem) == refine_golden_path(domain, problem).read_text(encoding="utf-8")


def test_refined_score_is_consistent(capsys):
    assert main(["refine", "soccer", "score", "--json", "--simulate"]) == 0
    data = json.loads(capsys.readouterr().out)
    # approachball is goToPose guarded by its success model (Ch. 6); here no subgoal is needed
    assert [a["action"] for a in data["refined"]["actions"]] == ["goToPose", "dribbleBall"]
    assert data["refined"]["actions"][0]["guard"] == "goToPose"
    assert data["refined"]["actions"][0]["predicted_success"] is True
    assert [a["inserted"] for a in data["assertions"]] == [False]
    free = {p["id"]: p for p in data["free_parameters"]}
    assert set(free) == {"pos2.phi", "pos2.v"}
    approach, dribble = data["refined"]["actions"]
    # the shared subgoal: the approach's goal heading and speed are dribbleBall's start
    assert approach["params"]["phig"] == dribble["params"]["phi"] == pytest.approx(free["pos2.phi"]["value"], abs=1e-6)
    assert approach["params"]["vg"] == dribble["params"]["v"] == pytest.approx(free["pos2.v"]["value"], abs=1e-6)
    assert 0.0 <= free["pos2.v"]["value"] <= 0.3
    for execution in (data["refined"], data["greedy"]):
        assert execution["predicted_total"] == pytest.approx(sum(a["predicted"] for a in execution["actions"]), abs=1e-3)
        assert execution["simulated_total"] == pytest.approx(sum(a["simulated"] for a in execution["actions"]), abs=1e-3)
    # refinement minimizes the summed prediction, greedy only the first action's
    assert data["refined"]["predicted_total"] <= data["greedy"]["predicted_total"] + 1e-9
    assert approach["predicted"] >= data["greedy"]["actions"][0]["predicted"] - 1e-9


def test_refine_plot_writes_trajectories_and_polar_plot(tmp_path, capsys):
    out = tmp_path / "score.png"
    previous = os.umask(0o022)
    try:
        assert main(["refine", "soccer", "score", "--plot", str(out)]) == 0
    finally:
        os.umask(previous)
    polar, waypoint = tmp_path / "score_polar.png", tmp_path / "score_waypoint.png"  # Fig. 5.8; Fig. 5.9 at the ball
    assert all(png.stat().st_size > 10_000 for png in (out, polar, waypoint))
    printed = capsys.readouterr().out
    assert all(f"Wrote {png}\n" in printed for png in (out, polar, waypoint))  # every file written is named
    for png in (out, polar, waypoint):  # a new file's permissions under umask 022, not mkstemp's 0600
        assert stat.S_IMODE(png.stat().st_mode) == 0o644
    assert sorted(p.name for p in tmp_path.iterdir()) == ["score.png", "score_polar.png", "score_waypoint.png"]


def _tailor(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "tailor.cli", *args], capture_output=True, text=True)


def test_bad_belief_file_is_one_line_with_its_exit_status(tmp_path):
    belief = tmp_path / "bad.toml"
    belief.write_text("[objects.pos1]\nx = 0.0\ny = 'one'\n")
    result = _tailor("refine", "soccer", "score", "--belief", str(belief))
    assert result.returncode == 10 and result.stdout == ""
    assert result.stderr.count("\n") == 1 and str(belief) in result.stderr and "Traceback" not in result.stderr


def test_missing_models_are_one_line_with_their_exit_status(tmp_path):
    domain = Path(__file__).resolve().parent.parent / "domains" / "soccer"
    copy = tmp_path / "soccer"
    (copy / "problems").mkdir(parents=True)
    for name in ("domain.pddl", "actions.toml", "problems/score.pddl", "problems/score.toml"):
        (copy / name).write_text((domain / name).read_text())
    result = _tailor("refine", str(copy / "domain.pddl"), str(copy / "problems/score.pddl"))
    assert result.returncode == 12 and "models" in result.stderr and result.stderr.count("\n") == 1



def test_the_printed_free_values_reproduce_the_prediction(capsys):
    """The JSON's chosen values are the values refinement bound, to the last bit, and bound back into the
    sequence they give the predicted total (an analytic optimum may lie on a split of a model tree, where a
    rounded value falls into the next leaf: issue of knife-edge optima)."""
    import tailor
    from tailor.refinement.models.action_models import load_action_models
    from tailor.refinement.refine import predicted_durations

    assert main(["refine", "soccer", "score", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    refined = tailor.refine("soccer", "score")
    models = load_action_models(refined.models, tuple(sorted({a.action for a in refined.sequence.actions})))
    for key, execution in (("value", "refined"), ("greedy", "greedy")):
        values = {p["id"]: p[key] for p in data["free_parameters"]}
        approach = next(a for a in data[execution]["actions"] if a["step"] == 1)
        assert values["pos2.phi"] == approach["params"]["phig"] and values["pos2.v"] == approach["params"]["vg"]
        total = sum(predicted_durations(refined.instantiated.bind(values), models))
        assert total == pytest.approx(data[execution]["predicted_total"], abs=5e-5)  # durations: 4 decimals


def test_the_improvement_is_a_dash_where_greedy_is_predicted_to_take_no_time():
    """A binding whose models extrapolate greedy to 0 s crashed the text output half-way (ZeroDivisionError)."""
    from tailor.cli.refine import _gain

    assert _gain(0.0, 0.0) == "-" and _gain(9.0, 10.0) == "10.0%" and _gain(11.0, 10.0) == "-10.0%"


def test_the_header_and_the_json_name_the_optimizer_that_ran(capsys):
    """auto, the default, is no optimizer of its own: the refined column names the one whose choices it took
    (on the bundled soccer models the certified branch and bound: their feature spaces are not piecewise affine,
    which the note says, but declare bounds), never one that did not run; with its gap."""
    assert main(["refine", "soccer", "score"]) == 0
    text = capsys.readouterr().out
    assert "refined (h=2, certified, risk 1, neighbourhood 0.02)" in text
    assert "analytic" not in text.split("Optimizer:")[0]
    assert "analytic not applicable: feature 5 of term '(approachball pos1 pos2)' is not piecewise affine" in text
    assert main(["refine", "soccer", "score", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["optimizer"] == "auto" and data["refined"]["optimizers"] == ["certified"]
    window = data["refined"]["optimization"][0]
    assert window["method"] == "certified" and 0 <= window["gap"] <= 0.01 * window["cost"]
    assert window["lower_bound"] <= window["cost"]
    assert main(["refine", "soccer", "score", "--json", "--optimizer", "analytic"]) == 0
    assert json.loads(capsys.readouterr().out)["refined"]["optimizers"] == ["ga"]  # analytic fell back
