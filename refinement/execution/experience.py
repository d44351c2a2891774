"""Executed actions kept as experience (Ch. 8.1: data gathered during operation): one recorded-executions log per
action, `DIR/<action>.csv` in format `tailor.action_log/1` (refinement.learning.logs, docs/logs.md), source
"execution", so `tailor train --log DIR/*.csv` learns from them and `tailor execute --learn --log DIR` starts
from them. A run's rows are added to what the file holds (the whole file rewritten atomically)."""

from __future__ import annotations

import csv
import io
from collections.abc import Mapping, Sequence
from pathlib import Path

from tailor.errors import DataError
from tailor.outputs import check_output_dir, write_atomically
from tailor.refinement.learning.logs import _cell, episode_rows, read_logs
from tailor.sims.episode import Episode
from tailor.sims.protocol import SimulatorEntry

SOURCE = "execution"
SUFFIX = ".csv"


def log_path(folder: Path, action: str) -> Path:
    return Path(folder) / f"{action}{SUFFIX}"


def check_log(folder: Path) -> None:
    """The log folder can be written (checked before any work; see tailor.outputs)."""
    check_output_dir(folder)


def read_executions(folder: Path, entry: SimulatorEntry, actions: Sequence[str]) -> list[Episode]:
    """The executions logged in `folder` for `actions`, every row checked (a DataError naming file:row)."""
    paths = [log_path(folder, a) for a in actions if log_path(folder, a).is_file()]
    if not paths:
        return []
    found = read_logs(paths, entry, actions)
    return [e for action in actions for e in found.get(action, [])]


def write_executions(folder: Path, executed: Mapping[str, list[Episode]], entry: SimulatorEntry, run: str) -> None:
    """Add this run's executed actions to their logs in `folder` (created where missing)."""
    Path(folder).mkdir(parents=True, exist_ok=True)
    for action, episodes in executed.items():
        if not episodes:
            continue
        columns, rows = episode_rows(episodes, entry, run=run, source=SOURCE)
        path = log_path(folder, action)
        before = ""
        if path.is_file():
            before = path.read_text(encoding="utf-8")
            header = next(csv.reader(io.StringIO(before)), None)
            if header != columns:
                raise DataError(f"the log's columns differ from those of {action}'s executions now "
                                f"({', '.join(columns)}); keep it elsewhere or give another --log folder",
                                file=str(path))

        def write(tmp: Path, before=before, columns=columns, rows=rows) -> None:
            with open(tmp, "w", newline="", encoding="utf-8") as f:
                if before:
                    f.write(before if before.endswith("\n") else before + "\n")
                writer = csv.writer(f)
                if not before:
                    writer.writerow(columns)
                for row in rows:
                    writer.writerow([_cell(row.get(c, "")) for c in columns])

        write_atomically(path, write)
