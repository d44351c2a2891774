"""Shared test set-up: the helpers beside the tests (golden-file regeneration, synthetic episodes) import as
top-level modules, since pytest puts this folder on the import path for test modules outside a package."""

from __future__ import annotations

import os
import signal
import sys

os.environ.setdefault("MPLBACKEND", "Agg")  # plots are written to files; never open a window
# A test run started as a background job inherits Ctrl-C ignored, and so would every process it starts: the
# tests of Ctrl-C (in this process and in child commands) need it to raise, as in a terminal.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

import pytest  # noqa: E402


@pytest.fixture(autouse=True, scope="session")
def _session_user_folders(tmp_path_factory):
    """Neither does a module- or session-scoped fixture (set up before the per-test fixture below), nor a command
    it starts: the user data folder is a temporary one for the whole session, also where platformdirs derives
    it from the home folder (macOS: ~/Library/Application Support) rather than from $XDG_DATA_HOME."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("XDG_DATA_HOME", str(tmp_path_factory.mktemp("session-user-data")))
        patch.delenv("TAILOR_MODELS", raising=False)
        if sys.platform == "darwin":
            patch.setenv("HOME", str(tmp_path_factory.mktemp("home")))
        yield


@pytest.fixture(autouse=True)
def _user_folders(tmp_path_factory, monkeypatch):
    """No test reads or writes the real user's data folder or follows the user's $TAILOR_MODELS."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path_factory.mktemp("user-data")))
    monkeypatch.delenv("TAILOR_MODELS", raising=False)


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_auto_num_workers(config):
    """Benchmarks time one process on a quiet machine: a run that selects them is never spread over cores.

    Whether the -m expression selects a test marked benchmark is evaluated, not guessed from the word: the
    default "not benchmark and not differential" (pyproject addopts) names it but excludes it, and must run on
    every core (testing for the word alone ran the default suite in one process)."""
    expression = (config.option.markexpr or "").strip()
    if not expression:
        return None
    try:
        from _pytest.mark.expression import Expression

        selects_benchmarks = Expression.compile(expression).evaluate(lambda name, **kwargs: name == "benchmark")
    except Exception:  # an expression (or a pytest) this cannot evaluate: the cautious answer, one process
        return 0
    return 0 if selects_benchmarks else None
