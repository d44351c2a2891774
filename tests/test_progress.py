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
