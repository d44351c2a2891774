"""Shared test set-up: the helpers beside the tests (golden-file regeneration, synthetic episodes) import as
top-level modules, since pytest puts this folder on the import path for test modules outside a package."""

from __future__ import annotations

import os

os.environ.setdefault("MPLBACKEND", "Agg")  # plots are written to files; never open a window

import pytest  # noqa: E402


@pytest.fixture(autouse=True)
def _user_folders(tmp_path_factory, monkeypatch):
    """No test reads or writes the real user's data folder or follows the user's $TAILOR_MODELS."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path_factory.mktemp("user-data")))
    monkeypatch.delenv("TAILOR_MODELS", raising=False)


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_auto_num_workers(config):
    """Benchmarks time one process on a quiet machine: a run that selects them is never spread over cores."""
    expression = config.option.markexpr or ""
    if "benchmark" in expression and expression.strip() != "not benchmark":
        return 0
    return None
