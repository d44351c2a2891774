"""Issue 33, items 2, 6, 8 and 10: outputs. The installed package and its bundled domains are read-only to every
command whatever path names them; one run at a time gathers into an experience folder (an advisory lock); a
path that cannot be looked at (a loop of symbolic links, a name too long) is status 16 naming it; a SIGTERM
after `tailor train` has put its files in place does not change its status (0)."""

from __future__ import annotations

import argparse
import contextlib
import importlib
import io
import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from tailor.cli.main import main
from tailor.errors import OutputFileError
from tailor.outputs import check_output_dir, check_output_file
from tailor.planner_bridge.bundled import DOMAINS_DIR

ONE_ERROR_LINE = re.compile(r"^tailor \w+: error: [^\x00-\x1f\x7f]+$")
SOCCER = DOMAINS_DIR / "soccer"
READ_ONLY = "leads into the installed tailor package"
fcntl = pytest.importorskip("fcntl")


def one_line(err: str) -> str:
    lines = [line for line in err.strip().splitlines() if ": note: " not in line]
    assert len(lines) == 1 and ONE_ERROR_LINE.match(lines[0]), err
    return lines[0]


def _snapshot(folder: Path) -> dict[str, tuple[int, int]]:
    """Every file below `folder`, with its size and modification time."""
    return {str(p.relative_to(folder)): (p.stat().st_size, p.stat().st_mtime_ns) for p in folder.rglob("*")}


def _no_work(*args, **kwargs):
    raise AssertionError("work was started although the output cannot be written")


@pytest.fixture
def bundled_untouched():
    """The bundled domains as they were before the test, and after it."""
    before = _snapshot(DOMAINS_DIR)
    yield
    assert _snapshot(DOMAINS_DIR) == before


# --- 2. the installed package and its domains are read-only, whatever path names them ---------------------------
def _paths_into_soccer(tmp_path: Path) -> dict[str, Path]:
    (tmp_path / "link").symlink_to(SOCCER)
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "models").symlink_to(SOCCER / "models")  # DIR/models is where train writes
    return {"the folder": SOCCER, "through ..": DOMAINS_DIR / "arm" / ".." / "soccer",
            "a symbolic link": tmp_path / "link", "a folder in it": SOCCER / "models",
            "a folder whose models/ links into it": tmp_path / "out"}


@pytest.mark.parametrize("way", ["the folder", "through ..", "a symbolic link", "a folder in it",
                                 "a folder whose models/ links into it"])
def test_train_never_writes_into_a_bundled_domain(way, tmp_path, monkeypatch, capsys, bundled_untouched):
    out = _paths_into_soccer(tmp_path)[way]
    monkeypatch.setattr("tailor.refinement.learning.training.train_domain", _no_work)
    assert main(["train", "soccer", "--only", "goToPosition", "--episodes", "8", "--jobs", "1", "--out", str(out)]) == 16
    line = one_line(capsys.readouterr().err)
    assert line.startswith(f"tailor train: error: {out}: {READ_ONLY}")


def test_gather_refine_and_evaluate_never_write_into_the_package(tmp_path, monkeypatch, capsys, bundled_untouched):
    monkeypatch.setattr("tailor.sims.shards.stored_gather", _no_work)
    monkeypatch.setattr("tailor.refinement.pipeline.prepare", _no_work)
    for argv, named in [
        (["gather", "soccer", "--seeds", "0:8", "--out", str(SOCCER / "models")], SOCCER / "models"),
        (["gather", "soccer", "--seeds", "0:8", "--out", str(DOMAINS_DIR / "new")], DOMAINS_DIR / "new"),
        (["refine", "soccer", "score", "--plot", str(SOCCER / "training" / "run.png")], SOCCER / "training" / "run.png"),
        (["evaluate", "soccer", "--meta", "--episodes", "20", "--models", str(SOCCER / "models")], SOCCER / "models"),
    ]:
        assert main(argv) == 16, argv
        assert one_line(capsys.readouterr().err).startswith(f"tailor {argv[0]}: error: {named}: {READ_ONLY}")
    assert not (DOMAINS_DIR / "new").exists()


def test_the_package_folder_itself_and_its_code_are_protected(tmp_path):
    from tailor.outputs import protected_folders

    package = Path(os.path.realpath(DOMAINS_DIR)).parent
    for folder in (package, *protected_folders()):
        with pytest.raises(OutputFileError, match=READ_ONLY):
            check_output_dir(folder)
    with pytest.raises(OutputFileError, match=READ_ONLY):
        check_output_file(package / "planner_bridge" / "x.png", ".png")
    check_output_dir(tmp_path / "models")  # an ordinary folder is fine
    check_output_file(tmp_path / "x.png", ".png")


# --- 8. a path that cannot be looked at is 16, naming it -------------------------------------------------------
def test_a_loop_or_a_name_too_long_is_an_output_error(tmp_path, monkeypatch, capsys):
    (tmp_path / "loop").symlink_to(tmp_path / "loop")
    long_name = tmp_path / ("n" * 300)
    monkeypatch.setattr("tailor.refinement.learning.training.train_domain", _no_work)
    monkeypatch.setattr("tailor.sims.shards.stored_gather", _no_work)
    for argv, named, reason in [
        (["train", "soccer", "--episodes", "8", "--out", str(tmp_path / "loop")], tmp_path / "loop",
         "a loop of symbolic links"),
        (["train", "soccer", "--episodes", "8", "--out", str(tmp_path / "loop" / "deeper")], tmp_path / "loop" / "deeper",
         "a loop of symbolic links"),
        (["train", "soccer", "--episodes", "8", "--out", str(long_name)], long_name, "the name is too long"),
        (["gather", "soccer", "--seeds", "0:8", "--out", str(tmp_path / "loop")], tmp_path / "loop",
         "a loop of symbolic links"),
        (["refine", "soccer", "score", "--plot", str(tmp_path / "loop" / "x.png")], tmp_path / "loop" / "x.png",
         "a loop of symbolic links"),
    ]:
        assert main(argv) == 16, argv
        assert one_line(capsys.readouterr().err) == f"tailor {argv[0]}: error: {named}: cannot write here: {reason}"


def test_a_user_data_folder_in_a_loop_is_an_output_error(tmp_path, monkeypatch, capsys):
    (tmp_path / "loop").symlink_to(tmp_path / "loop")
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "loop"))
    monkeypatch.setattr("tailor.refinement.learning.training.train_domain", _no_work)
    assert main(["train", "soccer", "--episodes", "8"]) == 16
    assert one_line(capsys.readouterr().err) == (f"tailor train: error: {tmp_path / 'loop' / 'tailor' / 'soccer'}: "
                                                 "cannot write here: a loop of symbolic links")


# --- 6. one run at a time gathers into an experience folder ----------------------------------------------------
def test_a_gather_into_a_folder_another_run_is_gathering_into_is_refused(tmp_path, capsys):
    """Another process holds the folder's lock (here: this test, on its own open file): the gather ends at once
    with one line naming the folder and the process, writes nothing, and gathers once the lock is let go."""
    from tailor.sims.shards import LOCK_FILE

    holder = os.open(tmp_path / LOCK_FILE, os.O_RDWR | os.O_CREAT)
    fcntl.flock(holder, fcntl.LOCK_EX | fcntl.LOCK_NB)
    os.write(holder, b"4242\n")
    argv = ["-q", "gather", "soccer", "--seeds", "0:8", "--scenario", "goToPosition", "--out", str(tmp_path)]
    try:
        assert main(argv) == 16
        assert one_line(capsys.readouterr().err) == (
            f"tailor gather: error: {tmp_path}: another tailor run (process 4242) is gathering experience into this "
            "folder: wait for it to end, or give another folder")
        assert sorted(p.name for p in tmp_path.iterdir()) == [LOCK_FILE]
    finally:
        os.close(holder)
    assert main(argv) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["goToPosition.seed0.0-8.npz"]  # no lock file left


def test_two_gathers_at_once_into_one_folder_never_overlap(tmp_path):
    """The issue's case: seeds 0:400 and 200:600 into one folder at once; the second waits for nothing and says
    so (16); after the first, it gathers only what is missing, and training reads the folder."""
    from tailor.sims.shards import LOCK_FILE

    command = [sys.executable, "-m", "tailor.cli", "-q", "gather", "soccer", "--scenario", "goToPosition", "--out",
               str(tmp_path), "--seeds"]
    first = subprocess.Popen([*command, "0:400"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while not (tmp_path / LOCK_FILE).exists() and first.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        second = subprocess.run([*command, "200:600"], capture_output=True, text=True, timeout=60)
        assert first.wait(120) == 0, first.stderr.read()
    finally:
        if first.poll() is None:
            first.kill()
    if second.returncode == 0:  # the first was done before the second looked: nothing to test this time
        pytest.skip("the first gather ended before the second started")
    assert second.returncode == 16
    assert "another tailor run (process" in one_line(second.stderr)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["goToPosition.seed0.0-400.npz"]
    assert subprocess.run([*command, "200:600"], capture_output=True, timeout=120).returncode == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["goToPosition.seed0.0-400.npz",
                                                          "goToPosition.seed0.400-600.npz"]


def test_the_lock_holds_for_its_thread_and_refuses_another(tmp_path):
    from tailor.sims.shards import experience_lock

    refused = []

    def other():
        try:
            with experience_lock(tmp_path):
                pass
        except OutputFileError as exc:
            refused.append(str(exc))

    with experience_lock(tmp_path):
        with experience_lock(tmp_path):  # the same thread again: held on
            thread = threading.Thread(target=other)
            thread.start()
            thread.join()
    assert refused == [f"{tmp_path}: another thread of this process is gathering experience into this folder"]
    with experience_lock(tmp_path):  # let go: taken again
        pass
    assert list(tmp_path.iterdir()) == []


# --- 10. a late SIGTERM leaves tailor train's status as it was ---------------------------------------------------
@pytest.mark.skipif(not hasattr(signal, "SIGTERM") or sys.platform == "win32", reason="POSIX signals")
@pytest.mark.parametrize("delay", [0.05, 0.3])
def test_a_sigterm_once_the_files_are_in_place_ends_with_0(delay, tmp_path):
    """The last file is in place; the process still has most of a second of shutting down (the interpreter
    puts back the default action of SIGTERM before it tears its modules down): a SIGTERM then must not kill it
    by the signal with no word, but let it end as done."""
    out = tmp_path / "out"
    process = subprocess.Popen([sys.executable, "-m", "tailor.cli", "-q", "train", "soccer", "--only", "goToPosition",
                                "--episodes", "8", "--jobs", "1", "--out", str(out)],
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        last = out / "training" / "report.json"
        deadline = time.monotonic() + 120
        while not last.exists() and process.poll() is None and time.monotonic() < deadline:
            time.sleep(0.002)
        assert last.exists(), process.stderr.read()
        time.sleep(delay)
        process.send_signal(signal.SIGTERM)
        assert process.wait(30) == 0, process.stderr.read()
    finally:
        if process.poll() is None:
            process.kill()
    assert (out / "models" / "goToPosition.json").exists()


# A `tailor train` whose backend session takes this long to stop its workers once the files are in place
# (tests/test_hardening_outputs.py runs it with backend_session slowed; the marker file says when it is stopping)
SLOW_TRAIN = """
import contextlib, sys, time
from pathlib import Path
import tailor.sims.parallel as parallel

marker, stop_s = Path(sys.argv[1]), float(sys.argv[2])
real = parallel.backend_session

@contextlib.contextmanager
def slow_session(*args, **kwargs):
    with real(*args, **kwargs) as session:
        yield session
        marker.write_text("stopping the workers")
        time.sleep(stop_s)

parallel.backend_session = slow_session
from tailor.cli.main import main
sys.argv = ["tailor", *sys.argv[3:]]
sys.exit(main())
"""


@pytest.mark.skipif(not hasattr(signal, "SIGTERM") or sys.platform == "win32", reason="POSIX signals")
def test_a_sigterm_while_the_workers_stop_after_the_files_ends_with_0(tmp_path):
    """The files are in place, the backend session stops its workers (slowed here to 3 s): a SIGTERM then lets
    it finish and end with 0, every file complete."""
    out, marker = tmp_path / "out", tmp_path / "stopping"
    process = subprocess.Popen([sys.executable, "-c", SLOW_TRAIN, str(marker), "3", "-q", "train", "soccer",
                                "--only", "goToPosition", "--episodes", "8", "--jobs", "1", "--out", str(out)],
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not marker.exists() and process.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        assert marker.exists(), process.stderr.read()
        time.sleep(0.1)
        process.send_signal(signal.SIGTERM)
        assert process.wait(30) == 0, process.stderr.read()
    finally:
        if process.poll() is None:
            process.kill()
    report = json.loads((out / "training" / "report.json").read_text())
    assert [p for p in out.rglob(".*") if p.is_file()] == []  # no staged file left
    for name in report["files"]:
        assert (out / name).stat().st_size > 0
    json.loads((out / "models" / "goToPosition.json").read_text())


def test_a_sigterm_once_training_has_renamed_its_files_leaves_status_0(tmp_path, monkeypatch, capsys):
    """In this process: a SIGTERM as the backend session ends, after the renames began (the fake training
    below), is dropped; one before them still stops the run (143)."""
    from tailor.refinement.learning import training
    from tailor.sims import parallel

    real = parallel.backend_session

    @contextlib.contextmanager
    def terminated_session(*args, **kwargs):
        with real(*args, **kwargs) as session:
            yield session
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.2)  # (the handler runs here)

    def trained(recipe, episodes, seed, out, hold=None, **kwargs):  # a training run that renamed its files
        training._rename_all([], hold)
        return {"models": {}, "files": []}

    monkeypatch.setattr(parallel, "backend_session", terminated_session)
    monkeypatch.setattr(training, "train_domain", trained)
    assert main(["-q", "train", "soccer", "--only", "goToPosition", "--out", str(tmp_path), "--json"]) == 0
    assert capsys.readouterr().err == ""

    def stopped(*args, **kwargs):  # a training run stopped before its renames
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)

    monkeypatch.setattr(training, "train_domain", stopped)
    assert main(["-q", "train", "soccer", "--only", "goToPosition", "--out", str(tmp_path), "--json"]) == 143
    assert capsys.readouterr().err == "tailor train: terminated\n"


def test_a_sigterm_once_the_command_has_returned_leaves_its_status(monkeypatch):
    """The command has returned 0; a SIGTERM while its results are flushed (before the program ignores signals,
    cli.main._keep_status) leaves the status as it was."""
    cli = importlib.import_module("tailor.cli.main")  # (tailor.cli.main is also the name of its function)

    class SlowFlush(io.StringIO):
        def flush(self):
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.2)  # (the handler runs here)

    monkeypatch.setattr(sys, "stdout", SlowFlush())
    assert cli._run(argparse.Namespace(run=lambda args: 0, command="train")) == 0
