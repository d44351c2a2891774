"""Long stages report off a terminal too: a line when they start, at least every 30 s, and when they end."""

from __future__ import annotations

import logging

from tailor import progress


def test_a_stage_off_a_terminal_logs_its_start_every_30_s_and_its_end(monkeypatch, caplog):
    clock = iter([0.0, 10.0, 31.0, 45.0, 62.0, 69.0, 70.0])
    monkeypatch.setattr(progress.time, "monotonic", lambda: next(clock))
    monkeypatch.setattr(progress.sys.stderr, "isatty", lambda: False, raising=False)
    with caplog.at_level(logging.INFO, logger="tailor.progress"):
        with progress.stage_bar(5, "gather move", "ep") as bar:
            for _ in range(5):
                bar.update()
    assert [r.getMessage() for r in caplog.records] == [
        "gather move: 5 ep to do", "gather move: 2/5 ep (31 s)", "gather move: 4/5 ep (62 s)",
        "gather move: 5 ep done in 70.0 s"]


def test_quiet_or_empty_stages_say_nothing(caplog):
    with caplog.at_level(logging.INFO, logger="tailor.progress"):
        for bar in (progress.stage_bar(5, "x", "ep", enabled=False), progress.stage_bar(0, "x", "ep")):
            with bar:
                bar.update()
    assert caplog.records == []


def test_an_evaluation_piped_to_a_file_says_how_far_it_is(capsys):
    from tailor.cli.main import main

    assert main(["evaluate", "soccer", "--episodes", "2", "--oracle-episodes", "0", "--horizon-episodes", "0",
                 "--json"]) == 0
    err = capsys.readouterr().err
    assert "tailor evaluate: note: greedy vs refined: 2 ep to do" in err
    assert "tailor evaluate: note: greedy vs refined: 2 ep done in" in err


def test_a_stage_whose_step_takes_long_still_says_how_far_it_is(monkeypatch, caplog):
    """Issue 32: one long step (a fit, a batch of episodes in the workers) must not silence a stage: a watcher
    says how far it is once LOG_EVERY_S have passed without a line, and nothing once the stage is closed."""
    import time

    monkeypatch.setattr(progress, "LOG_EVERY_S", 0.05)
    monkeypatch.setattr(progress.sys.stderr, "isatty", lambda: False, raising=False)
    with caplog.at_level(logging.INFO, logger="tailor.progress"):
        with progress.stage_bar(3, "training", "fit") as bar:
            time.sleep(0.3)  # no update: the step is still running
            bar.update(3)
        said = len(caplog.records)
        time.sleep(0.2)
    messages = [r.getMessage() for r in caplog.records]
    assert messages[0] == "training: 3 fit to do" and messages[-1].startswith("training: 3 fit done in")
    assert sum(m.startswith("training: 0/3 fit (") for m in messages) >= 2  # every 0.05 s, not once
    assert len(caplog.records) == said  # closed: the watcher is silent


def test_finish_counts_a_stage_done_when_it_took_fewer_steps(monkeypatch, caplog):
    monkeypatch.setattr(progress.sys.stderr, "isatty", lambda: False, raising=False)
    with caplog.at_level(logging.INFO, logger="tailor.progress"):
        with progress.stage_bar(10, "training", "fit") as bar:
            bar.update(4)
            progress.finish(bar)
        progress.finish(progress.stage_bar(0, "x", "fit"))  # (no bar: nothing to count)
    assert caplog.records[-1].getMessage().startswith("training: 10 fit done in")


def test_train_and_gather_piped_to_a_file_say_how_far_they_are(tmp_path, monkeypatch, capsys):
    """Off a terminal, `tailor train` and `tailor gather` log every stage (gathering, training, retraining)
    and, at least every LOG_EVERY_S (here made 0: every step), how far it is."""
    import synthetic_episodes
    from tailor.cli.main import main

    monkeypatch.setattr(progress, "LOG_EVERY_S", 0.0)
    assert main(["gather", "soccer", "--seeds", "0:12", "--scenario", "goToPosition", "--out",
                 str(tmp_path / "experience")]) == 0
    err = capsys.readouterr().err
    assert "tailor gather: note: gather goToPosition: 12 ep to do" in err
    assert "tailor gather: note: gather goToPosition: 10/12 ep (" in err  # after the first batch of ten
    assert "tailor gather: note: gather goToPosition: 12 ep done in" in err
    monkeypatch.setattr("tailor.sims.experience.gather", synthetic_episodes.gather)
    assert main(["train", "soccer", "--only", "goToPosition", "--episodes", "24", "--n-i", "1,3", "--out",
                 str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err
    started = [line for line in err.splitlines() if line.startswith("tailor train: note: training: ")]
    assert started[0].endswith("fit to do") and "/" in started[1] and " fit done in " in started[-1]
