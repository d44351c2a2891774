"""Issue 11, the refinement / command-line side: every bad input ends in one line with the README's status,
before any work is lost; an empty plan is a success in every mode; no worker process outlives `tailor train`;
the status reported after Ctrl-C matches what is on disk."""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from tailor.planner_bridge.bundled import DOMAINS_DIR
from tailor.cli.main import main

SOCCER = DOMAINS_DIR / "soccer"
ONE_ERROR_LINE = re.compile(r"^tailor \w+: error: .+$")


def one_line(err: str) -> str:
    """The single line of stderr, checked to be a `tailor CMD: error: ...` line (no usage block, no traceback)."""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and ONE_ERROR_LINE.match(lines[0]), err
    return lines[0]


@pytest.fixture
def soccer(tmp_path) -> Path:
    """A copy of the soccer domain (PDDL, binding, problems, models) to break."""
    domain = tmp_path / "soccer"
    shutil.copytree(SOCCER, domain, ignore=shutil.ignore_patterns("training"))
    return domain


def refine(domain: Path, *args: str) -> list[str]:
    return ["refine", str(domain / "domain.pddl"), "score", *args]


def _no_work(*args, **kwargs):
    raise AssertionError("work was started although the input was bad")


# --- 1. --plot is checked before planning ----------------------------------------------------------------
@pytest.mark.parametrize("plot", ["/proc/x.png", "{tmp}/folder.png", "{tmp}/picture.jpg", "{tmp}/picture"])
def test_a_plot_that_cannot_be_written_fails_before_planning(plot, tmp_path, monkeypatch, capsys):
    (tmp_path / "folder.png").mkdir()
    plot = plot.format(tmp=tmp_path)
    monkeypatch.setattr("tailor.refinement.pipeline.prepare", _no_work)
    assert main(["refine", "soccer", "score", "--plot", plot]) == 16
    assert one_line(capsys.readouterr().err).startswith(f"tailor refine: error: {plot}: ")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["folder.png"]  # nothing written


@pytest.mark.parametrize("companion", ["picture_polar.png", "picture_costs.png"])
def test_a_plot_whose_companion_cannot_be_written_fails_before_planning(companion, tmp_path, monkeypatch, capsys):
    """FILE.png comes with FILE_polar.png or FILE_costs.png: both are checked before any work, and the FILE.png
    there is left as it was."""
    (tmp_path / "picture.png").write_text("old")
    (tmp_path / companion).mkdir()
    monkeypatch.setattr("tailor.refinement.pipeline.prepare", _no_work)
    assert main(["refine", "soccer", "score", "--plot", str(tmp_path / "picture.png")]) == 16
    assert one_line(capsys.readouterr().err) == (f"tailor refine: error: {tmp_path / companion}: is a folder, not "
                                                 "a file name")
    assert (tmp_path / "picture.png").read_text() == "old"


def test_a_belief_file_bad_in_itself_fails_before_planning(tmp_path, monkeypatch, capsys):
    belief = tmp_path / "belief.toml"
    belief.write_text('[objects.pos1]\nx = "far"\n')
    monkeypatch.setattr("tailor.refinement.pipeline.plan_pddl", _no_work)
    assert main(["refine", "soccer", "score", "--belief", str(belief)]) == 10
    assert one_line(capsys.readouterr().err) == f"tailor refine: error: {belief}: [objects.pos1] x = 'far' is not a number"


def test_a_plot_in_a_read_only_file_system_fails_before_planning(monkeypatch, capsys):
    if os.access("/sys", os.W_OK) and not os.path.ismount("/sys"):
        pytest.skip("no read-only file system to write into")
    monkeypatch.setattr("tailor.refinement.pipeline.prepare", _no_work)
    assert main(["refine", "soccer", "score", "--plot", "/sys/x.png"]) == 16
    one_line(capsys.readouterr().err)


# --- 2. model and binding files of the wrong type --------------------------------------------------------
def test_a_model_file_of_random_bytes_is_one_line(soccer, capsys):
    model = soccer / "models" / "goToPose.json"  # the approach of `score` is goToPose (Ch. 6)
    model.write_bytes(bytes(range(128, 256)) * 3)
    assert main(refine(soccer)) == 12
    assert one_line(capsys.readouterr().err).startswith(f"tailor refine: error: {model}: not JSON")


@pytest.mark.parametrize("key, value", [("feature_set", ["pose"]), ("feature_names", {"x": 1}), ("n_i", [5]),
                                        ("duration", [1]), ("report", [1])])
def test_a_model_field_of_the_wrong_type_names_file_and_key(soccer, key, value):
    from tailor.errors import ModelFileError
    from tailor.refinement.models.action_models import load_action_models

    model = soccer / "models" / "approachBall.json"
    data = json.loads(model.read_text())
    data[key] = value
    model.write_text(json.dumps(data))
    with pytest.raises(ModelFileError, match=f"^{re.escape(str(model))}: .*{key.split('_')[0]}") as info:
        load_action_models(soccer / "models", ("approachBall",))
    assert info.value.exit_code == 12


def test_nan_in_a_model_file_is_not_json(soccer):
    from tailor.errors import ModelFileError
    from tailor.refinement.models.action_models import load_action_models

    model = soccer / "models" / "approachBall.json"
    model.write_text(model.read_text().replace('"intercept": ', '"intercept": NaN, "x": ', 1))
    with pytest.raises(ModelFileError, match=f"^{re.escape(str(model))}: not JSON: NaN"):
        load_action_models(soccer / "models", ("approachBall",))


@pytest.mark.parametrize("executable", ['["goToPose"]', '{ name = "goToPose" }', "3"])
def test_a_binding_executable_of_the_wrong_type_names_file_and_key(soccer, capsys, executable):
    binding = soccer / "actions.toml"
    text = binding.read_text()
    assert '[actions.approachball]\nexecutable = "goToPose"' in text
    binding.write_text(text.replace('[actions.approachball]\nexecutable = "goToPose"',
                                    f"[actions.approachball]\nexecutable = {executable}"))
    assert main(refine(soccer)) == 11
    line = one_line(capsys.readouterr().err)
    assert line.startswith(f"tailor refine: error: {binding}: [actions.approachball] executable")


def test_an_inline_table_where_a_table_of_tables_is_meant_is_one_line(soccer, capsys):
    binding = soccer / "actions.toml"
    text = binding.read_text().replace("[actions.approachball]\nexecutable", "[actions.approachball]\nx = {a = 1}\n"
                                       "executable")
    binding.write_text(text)
    assert main(refine(soccer)) == 11
    assert "unknown key 'x'" in one_line(capsys.readouterr().err)


# --- 3. a goal that already holds ------------------------------------------------------------------------
@pytest.mark.parametrize("flags", [[], ["--json"], ["--simulate"], ["--json", "--simulate"]])
def test_an_empty_plan_is_done_in_every_mode(soccer, capsys, flags):
    problem = soccer / "problems" / "already.pddl"
    problem.write_text((soccer / "problems" / "score.pddl").read_text().replace(
        "(:goal (and (atball pos3) (final pos3)))", "(:goal (robot pos1))"))
    shutil.copy(soccer / "problems" / "score.toml", soccer / "problems" / "already.toml")
    assert main(["refine", str(soccer / "domain.pddl"), "already", *flags]) == 0
    captured = capsys.readouterr()
    assert captured.err == ""
    if "--json" in flags:
        data = json.loads(captured.out)
        assert data["refined"]["actions"] == [] and data["refined"]["predicted_total"] == 0.0 and data["free_parameters"] == []
        assert ("succeeded" in data["refined"]) == ("--simulate" in flags)
    else:
        assert "Nothing to refine" in captured.out


# --- 4. one line and one status per usage fault, in every command ----------------------------------------
@pytest.mark.parametrize("argv, status", [
    (["train", "nosuch"], 3), (["refine", "nosuch", "x"], 3), (["evaluate", "nosuch"], 3),
    (["train", "soccer", "--jobs", "0"], 2), (["evaluate", "soccer", "--jobs", "0"], 2),
    (["train", "soccer", "--episodes", "5"], 2), (["train", "soccer", "--fresh-episodes", "0"], 2),
    (["evaluate", "soccer", "--episodes", "-1"], 2), (["refine", "soccer", "score", "--horizon", "0"], 2),
    (["refine", "soccer"], 2), (["train", "soccer", "--no-such-option"], 2), (["nosuch"], 2),
    # a negative seed (numpy's generators refuse it), counts beyond what a machine can run
    (["refine", "arm", "letter-f", "--seed", "-1"], 2), (["evaluate", "arm", "--seed", "-1"], 2),
    (["coordinate", "soccer", "--seed", "-1"], 2), (["train", "arm", "--seed", "-1"], 2),
    (["gather", "arm", "--seeds", "0:2", "--seed", "-1"], 2), (["gather", "arm", "--seeds", "0:10000000000"], 2),
    (["evaluate", "kitchen", "--episodes", "99999999999999999999999"], 2),
    (["coordinate", "soccer", "--episodes", "99999999999999999999999"], 2),
])
def test_usage_faults_are_one_line_with_one_status(argv, status, capsys, monkeypatch):
    monkeypatch.setattr("tailor.sims.experience.gather", _no_work)
    try:
        code = main(argv)
    except SystemExit as exit:  # argparse ends the process (tailor's __main__ does not catch it either)
        code = exit.code
    assert code == status
    err = capsys.readouterr().err
    if status == 2:
        lines = err.strip().splitlines()
        assert len(lines) == 1 and re.match(r"^tailor( \w+)?: error: ", lines[0]), err
    else:
        one_line(err)


def test_usage_errors_exit_with_status_2():
    run = subprocess.run([sys.executable, "-m", "tailor.cli", "train", "soccer", "--jobs", "0"], check=False,
                         capture_output=True, text=True)
    assert run.returncode == 2 and run.stderr.startswith("tailor train: error: argument --jobs")
    assert len(run.stderr.strip().splitlines()) == 1


# --- 5. train --out is checked before gathering ----------------------------------------------------------
def test_train_to_an_unwritable_folder_fails_before_gathering(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr("tailor.sims.experience.gather", _no_work)
    assert main(["train", "soccer", "--out", "/proc/tailor-out"]) == 16
    assert one_line(capsys.readouterr().err).startswith("tailor train: error: /proc/tailor-out: ")
    (tmp_path / "file").write_text("")
    assert main(["train", "soccer", "--out", str(tmp_path / "file")]) == 16
    assert one_line(capsys.readouterr().err) == f"tailor train: error: {tmp_path / 'file'}: exists and is not a folder"


# --- 6. the binding against the domain -------------------------------------------------------------------
@pytest.mark.parametrize("old, new, message", [
    ("[predicates.atball]", "[predicates.atbal]",
     "[predicates.atbal]: domain 'soccer' has no predicate 'atbal'; did you mean 'atball'?"),
    ("[actions.gotopose]", "[actions.gotopos]",
     "[actions.gotopos]: domain 'soccer' has no action 'gotopos'; did you mean 'gotopose'?"),
    ('domain = "soccer"', 'domain = "kitchen"', "domain = 'kitchen', but {domain} defines domain 'soccer'"),
    ("[types.pos]", "[types.poss]", "[types.poss]: domain 'soccer' has no type 'poss'; did you mean 'pos'?"),
    ('scene = "robot"', 'secne = "robot"', "[predicates.robot]: unknown key 'secne'"),
])
def test_binding_names_the_domain_lacks_are_errors(soccer, capsys, monkeypatch, old, new, message):
    binding = soccer / "actions.toml"
    binding.write_text(binding.read_text().replace(old, new))
    monkeypatch.setattr("tailor.planner_bridge.plan_files", _no_work)  # before planning
    monkeypatch.setattr("tailor.refinement.pipeline.plan_pddl", _no_work)
    assert main(refine(soccer)) == 11
    line = one_line(capsys.readouterr().err)
    assert line.startswith(f"tailor refine: error: {binding}: " + message.format(domain=soccer / "domain.pddl"))


def test_train_and_evaluate_check_the_binding_against_the_domain_too(soccer, capsys, monkeypatch):
    binding = soccer / "actions.toml"
    binding.write_text(binding.read_text().replace("[predicates.atball]", "[predicates.atbal]"))
    monkeypatch.setattr("tailor.sims.experience.gather", _no_work)
    for argv in (["train", str(soccer), "--out", str(soccer / "out")], ["evaluate", str(soccer)]):
        assert main(argv) == 11
        assert "has no predicate 'atbal'" in one_line(capsys.readouterr().err)


@pytest.mark.parametrize("simulate", [(), ("--simulate",)])
def test_a_scene_object_the_simulator_lacks_fails_when_the_binding_is_read(soccer, capsys, monkeypatch, simulate):
    binding = soccer / "actions.toml"
    binding.write_text(binding.read_text().replace('scene = "ball"', 'scene = "goalpost"'))
    monkeypatch.setattr("tailor.refinement.pipeline.plan_pddl", _no_work)  # caught before planning
    assert main(refine(soccer, *simulate)) == 11
    line = one_line(capsys.readouterr().err)
    assert line.startswith(f"tailor refine: error: {binding}: ") and "scene = 'goalpost' is not a scene object" in line


def test_a_scene_the_simulator_rejects_fails_the_dry_reset():
    """For simulators that declare no scene objects, dispatch's dry reset (run before refining) catches it."""
    from tailor.refinement.action_sequence import ActionSequence, ExecutableAction
    from tailor.refinement.dispatch import check_scene
    from tailor.errors import SimError

    action = ExecutableAction(1, "(gotopose p0 p1)", "goToPose", ())
    sequence = ActionSequence("soccer", "score", (action,), {"robot": (0.0, 0.0, 0.0, 0.0), "goalpost": (1.0, 1.0)},
                              "soccer")
    with pytest.raises(SimError, match=r"^actions.toml: simulator 'soccer' rejects the scene .*goalpost"):
        check_scene(sequence, "actions.toml")
    check_scene(ActionSequence("soccer", "score", (action,), {"robot": (0.0, 0.0, 0.0, 0.0)}, "soccer"))


# --- 7. absurd but finite model coefficients -------------------------------------------------------------
@pytest.mark.parametrize("leaf", [{"coef": 1e300}, {"intercept": -1e6}, {"intercept": 1e6}])
def test_absurd_predictions_are_rejected_naming_the_model(soccer, capsys, leaf):
    model = soccer / "models" / "goToPose.json"
    data = json.loads(model.read_text())
    for row in data["duration"]["leaves"]:
        for key, value in leaf.items():
            row[key] = [value] * len(row[key]) if isinstance(row[key], list) else value
    model.write_text(json.dumps(data))
    for flags in ([], ["--json"]) if "coef" in leaf else ([],):
        assert main(refine(soccer, *flags)) == 12
        captured = capsys.readouterr()
        assert "Infinity" not in captured.out
        assert one_line(captured.err).startswith(f"tailor refine: error: {model}: step 1 goToPose: ")


def test_json_output_is_strict_json():
    from tailor.outputs import json_text

    assert json.loads(json_text({"a": float("inf"), "b": [float("nan"), 1.5]})) == {"a": None, "b": [None, 1.5]}


def test_predictions_are_checked_against_the_durations_seen_in_training():
    from tailor.errors import ModelFileError
    from tailor.refinement.models.action_models import ActionModel

    class Tree:
        pass

    model = ActionModel("a", "pose", (), Tree(), 1, {"duration_range": [2.0, 10.0]})
    assert model.plausible_range() == (-6.0, 18.0)
    assert model.check_duration(-0.5, "step 1") == 0.0 and model.check_duration(17.0, "step 1") == 17.0
    with pytest.raises(ModelFileError, match="outside the plausible"):
        model.check_duration(-7.0, "step 1")
    assert ActionModel("a", "pose", (), Tree(), 1, {"mean_duration": 5.0}).plausible_range() == (-10.0, 20.0)
    silent = ActionModel("a", "pose", (), Tree(), 1, {})  # a file whose report says nothing: a day either side
    assert silent.plausible_range() == (-86400.0, 86400.0)
    with pytest.raises(ModelFileError, match="outside the plausible"):
        silent.check_duration(1e300, "step 1")


@pytest.mark.parametrize("seen", [[5.0, 1.0], "abc", [1.0], [-1.0, 3.0], [1.0, float("inf")]])
def test_a_malformed_duration_range_is_refused_at_load(seen):
    from tailor.errors import ModelFileError
    from tailor.refinement.models.action_models import _report

    with pytest.raises(ModelFileError, match=r"^m.json: 'report.duration_range' must be \[shortest, longest\]"):
        _report({"report": {"duration_range": seen}}, "m.json")


# --- 8. --jobs capped at the CPU count -------------------------------------------------------------------
def test_jobs_beyond_the_cpus_are_capped_with_a_note(capsys):
    from tailor.cli.arguments import cpu_count, worker_count
    from tailor.cli.logs import cli_logging

    with cli_logging(0):
        assert worker_count("1000") == cpu_count()
    assert capsys.readouterr().err.strip() == f"tailor: note: --jobs 1000 capped at {cpu_count()}, the number of CPUs"
    with cli_logging(-1):  # -q: notes are silenced
        assert worker_count("1000") == cpu_count()
    assert capsys.readouterr().err == ""
    assert worker_count("1") == 1


# --- 9. SIGTERM stops tailor train and its workers -------------------------------------------------------
def _group_members(pgid: int) -> list[int]:
    members = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if fields[0] != "Z" and (int(fields[2]) == pgid or int(fields[1]) == pgid):  # process group or parent
            members.append(int(entry.name))
    return members


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="walks /proc")
@pytest.mark.parametrize("command", [
    ["train", "soccer", "--jobs", "2", "--episodes", "20000"],
    ["evaluate", "soccer", "--jobs", "2", "--episodes", "2000", "--oracle-episodes", "0"],
])
def test_sigterm_to_a_long_command_leaves_no_worker(tmp_path, command):
    out = ["--out", str(tmp_path / "out")] if command[0] == "train" else []
    process = subprocess.Popen([sys.executable, "-m", "tailor.cli", *command, *out],
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and len(_group_members(process.pid)) < 3:  # the workers started
            time.sleep(0.2)
        assert len(_group_members(process.pid)) >= 3, f"{command[0]} did not start its workers"
        time.sleep(1.0)
        process.send_signal(signal.SIGTERM)
        assert process.wait(timeout=30) == 143
        assert process.stderr.read().strip().endswith(f"tailor {command[0]}: terminated")
        deadline = time.monotonic() + 10
        while _group_members(process.pid) and time.monotonic() < deadline:
            time.sleep(0.2)
        assert _group_members(process.pid) == []
        assert not (tmp_path / "out" / "models").exists()
    finally:
        try:
            os.killpg(process.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass


# --- 10. Ctrl-C once the renames have begun --------------------------------------------------------------
def test_ctrl_c_during_the_renames_completes_them(tmp_path, monkeypatch):
    from tailor.refinement.learning import training

    staged = []
    for k in range(3):
        tmp, target = tmp_path / f".m{k}.tmp", tmp_path / f"m{k}.json"
        tmp.write_text(str(k))
        staged.append((tmp, target))
    replace = os.replace

    def interrupted_replace(source, target):
        replace(source, target)
        os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C after the first rename

    monkeypatch.setattr(training.os, "replace", interrupted_replace)
    training._rename_all(staged)  # no KeyboardInterrupt: the renames complete
    assert [target.read_text() for _, target in staged] == ["0", "1", "2"]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_ctrl_c_after_the_models_are_written_reports_done(tmp_path, monkeypatch, capsys):
    from tailor import outputs

    def trained(recipe, episodes, seed, out, **kwargs):  # stands in for a training run that wrote its models
        (out / "models").mkdir(parents=True)
        (out / "models" / "goToPose.json").write_text("{}")
        return {"models": {}}

    def interrupted(*args, **kwargs):  # Ctrl-C while the report is printed
        raise KeyboardInterrupt

    monkeypatch.setattr("tailor.refinement.learning.training.train_domain", trained)
    monkeypatch.setattr(outputs, "json_text", interrupted)
    assert main(["train", "soccer", "--out", str(tmp_path), "--json"]) == 0
    assert capsys.readouterr().err.strip() == (f"tailor train: interrupted while printing the report; the models in "
                                               f"{tmp_path / 'models'} are complete")


# --- standard output that cannot be written; a domain given as its folder ----------------------------------
@pytest.mark.parametrize("argv", [["plan", "arm", "letter-f", "--json"], ["domains"]])  # (one handler for all)
@pytest.mark.parametrize("closed", [False, True])
def test_results_that_cannot_be_written_are_one_line(argv, closed):
    """A full disk (/dev/full) or a closed standard output: one line, the output status, no traceback."""
    if not closed and not Path("/dev/full").exists():
        pytest.skip("no /dev/full here")
    with open("/dev/full", "w") if not closed else open(os.devnull, "w") as sink:
        run = subprocess.run([sys.executable, "-m", "tailor.cli", "-q", *argv], check=False,
                             stdout=sink, stderr=subprocess.PIPE, text=True,
                             preexec_fn=(lambda: os.close(1)) if closed else None)
    assert run.returncode == 16, run.stderr
    assert run.stderr.strip().splitlines() == [f"tailor {argv[0]}: error: cannot write to standard output: "
                                               + ("standard output is closed" if closed else "No space left on device")]


def test_plan_and_refine_take_a_domain_folder(tmp_path, capsys):
    """(Both resolve the pair in planner_bridge.resolve_problem.)"""
    folder = shutil.copytree(DOMAINS_DIR / "arm", tmp_path / "arm")
    assert main(["plan", "arm", "letter-f"]) == 0
    bundled = capsys.readouterr().out
    assert main(["plan", str(folder), "letter-f"]) == 0
    assert capsys.readouterr().out == bundled.replace(str(DOMAINS_DIR / "arm"), str(folder))
    (tmp_path / "empty").mkdir()
    assert main(["plan", str(tmp_path / "empty"), "letter-f"]) == 3
    assert capsys.readouterr().err.strip() == f"tailor plan: error: {tmp_path / 'empty'}: a domain folder needs a domain.pddl"


@pytest.mark.parametrize("argv, status, line", [
    (["plan", "soccer", "score", "--bogus"], 2,
     "tailor plan: error: unrecognized arguments: --bogus (see `tailor plan --help`)"),
    (["evaluate", "arm", "--plot", "e.png"], 2, "tailor evaluate: error: --plot draws the instances of --assertion"),
    (["domains", "{tmp}/notes.txt"], 3, "tailor domains: error: {tmp}/notes.txt: not a domain folder's domain.pddl"),
])
def test_usage_mistakes_are_said_by_the_command_with_their_status(argv, status, line, tmp_path, capsys):
    """An unknown option is the command's usage error; --plot without what it draws is a usage error (2); a
    file that is not a domain.pddl is not taken for the folder holding it."""
    (tmp_path / "notes.txt").write_text("not PDDL")
    argv = [a.format(tmp=tmp_path) for a in argv]
    try:
        code = main(argv)
    except SystemExit as exit:
        code = exit.code
    assert code == status
    assert one_line(capsys.readouterr().err).startswith(line.format(tmp=tmp_path))
