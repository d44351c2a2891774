"""Checks that an output file or folder can be written, made before any work whose result would be lost.

A command that plans, refines, simulates or trains for minutes and only then finds that its output cannot be
written has wasted the user's time: `tailor refine --plot` and `tailor train --out` probe the place first, by
creating (and removing) a temporary file in the nearest folder that exists, which catches read-only folders,
pseudo file systems such as /proc and missing permissions alike, also for root.

Every output is written atomically (`write_atomically`: a temporary file beside the target, renamed over it
once complete) with the permissions any new file of the user gets (0666 less the umask, usually 0644), not
the 0600 `tempfile.mkstemp` gives: models, reports and plots are meant to be read by others.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from collections.abc import Callable
from pathlib import Path

from tailor.errors import OutputFileError

NEW_FILE_MODE = 0o666  # what open() asks for; the umask takes away from it


def _nearest_existing(path: Path) -> Path:
    path = Path(os.path.abspath(path))
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def _probe(folder: Path, shown: str) -> None:
    """Create and remove a temporary file in `folder`; an OutputFileError naming `shown` if that fails."""
    if not folder.is_dir():
        raise OutputFileError(f"cannot write here: {folder} is not a folder", file=shown)
    try:
        fd, tmp = tempfile.mkstemp(prefix=".tailor-probe.", dir=folder)
    except OSError as exc:
        raise OutputFileError(f"cannot write in {folder}: {exc.strerror or exc}", file=shown) from None
    os.close(fd)
    os.unlink(tmp)


def check_output_dir(path: Path | str) -> None:
    """`path` is (or can be made) a folder we can write files in."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise OutputFileError("exists and is not a folder", file=str(path))
    _probe(_nearest_existing(path), str(path))


def check_output_file(path: Path | str, suffix: str | None = None) -> None:
    """`path` names a file (not a folder) with `suffix` (e.g. ".png") that can be created or replaced."""
    path = Path(path)
    if suffix is not None and path.suffix.lower() != suffix:
        raise OutputFileError(f"the file name must end in {suffix}", file=str(path))
    if path.is_dir():
        raise OutputFileError("is a folder, not a file name", file=str(path))
    if path.exists() and not os.access(path, os.W_OK):
        raise OutputFileError("exists and is not writable", file=str(path))
    _probe(_nearest_existing(path.parent), str(path))


def umask() -> int:
    """The process's umask, read without changing it where the platform tells (Linux: /proc/self/status);
    otherwise set and restored at once."""
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def new_file_mode() -> int:
    """The permissions open() gives a new file here: 0666 less the umask (0644 with the usual umask 022)."""
    return NEW_FILE_MODE & ~umask()


def staged_file(path: Path | str) -> Path:
    """A new empty file beside `path` (hidden, unique name, same suffix) with the permissions of a new file,
    to be written and then renamed over `path`; the caller removes it if it is not renamed."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
    try:
        os.fchmod(fd, new_file_mode())  # mkstemp makes the file private (0600)
    finally:
        os.close(fd)
    return Path(tmp)


def write_atomically(path: Path | str, write: Callable[[Path], None]) -> Path:
    """Write `path` by `write(tmp)` into a staged file beside it, renamed over `path` once complete: a reader
    never sees half a file, and an error or Ctrl-C leaves the old file (or none). OSError becomes the one-line
    OutputFileError naming `path`. Returns `path`."""
    path = Path(path)
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = staged_file(path)
        write(tmp)
        os.replace(tmp, path)
    except OSError as exc:
        raise write_error(path, exc) from None
    finally:
        if tmp is not None and tmp.exists():
            tmp.unlink()
    return path


def write_error(path: Path | str, exc: OSError) -> OutputFileError:
    """An OSError met while writing `path` as the one-line project error."""
    return OutputFileError(f"cannot write: {exc.strerror or exc}", file=str(path))


def finite(data):
    """`data` with every NaN or infinite float replaced by None: JSON has no such numbers, and a reader of
    `--json` output must be able to parse it."""
    if isinstance(data, float):
        return data if math.isfinite(data) else None
    if isinstance(data, dict):
        return {k: finite(v) for k, v in data.items()}
    if isinstance(data, (list, tuple)):
        return [finite(v) for v in data]
    return data


def json_text(data, indent: int | None = 1) -> str:
    """Strict JSON (never NaN or Infinity) of `data`, non-finite numbers written as null."""
    return json.dumps(finite(data), indent=indent, allow_nan=False)


SCHEMA_VERSION = 1
# the units of every number in the JSON outputs: durations in seconds, the simulators' quantities in SI units
UNITS = {"durations": "s", "quantities": "SI: m, rad, m/s, rad/s"}


def versioned(kind: str, data: dict) -> dict:
    """A command's JSON output led by its schema (`tailor.<kind>/<version>`) and the units of its numbers
    (the README's "JSON outputs")."""
    return {"schema": f"tailor.{kind}/{SCHEMA_VERSION}", "units": UNITS, **data}
