"""Shared test set-up: the helpers beside the tests (golden-file regeneration, synthetic episodes) import as
top-level modules, since pytest puts this folder on the import path for test modules outside a package."""

from __future__ import annotations

import os

os.environ.setdefault("MPLBACKEND", "Agg")  # plots are written to files; never open a window
