"""Checks that an output file or folder can be written, made before any work whose result would be lost.

A command that plans, refines, simulates or trains for minutes and only then finds that its output cannot be
written has wasted the user's time: `tailor refine --plot` and `tailor train --out` probe the place first, by
creating (and removing) a temporary file in the nearest folder that exists, which catches read-only folders,
pseudo file systems such as /proc and missing permissions alike, also for root.

The installed package and its bundled domains are read-only to every command, whatever path names them (a
symbolic link, `domains/a/../b`): the checks compare the path with every symbolic link followed
(`protected_folders`), so `--out` can never overwrite the models a domain ships with. A path that cannot
be looked at (a loop of symbolic links, a name too long) is an OutputFileError naming it, like any other
output that cannot be written.

Every JSON output and report carries its `Provenance` (the tailor version, the command line, the seeds and the
SHA-256 of the model files read), so a result can be told apart from another and made again.

Every output is written atomically (`write_atomically`: a temporary file beside the target, renamed over it
once complete) with the permissions any new file of the user gets (0666 less the umask, usually 0644), not
the 0600 `tempfile.mkstemp` gives: models, reports and plots are meant to be read by others.
"""

from __future__ import annotations

import errno
import hashlib
import json
import math
import os
import stat
import sys
import tempfile
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from tailor import __version__
from tailor.errors import ModelFileError, OutputFileError

NEW_FILE_MODE = 0o666  # what open() asks for; the umask takes away from it
PACKAGE_DIR = Path(os.path.realpath(__file__)).parent  # the installed package (a source tree when editable)
DOMAINS = "domains"  # its bundled domains: PDDL, bindings, problems, models, training reports


def protected_folders() -> tuple[Path, ...]:
    """The folders no command writes in (nor below): the installed package; in a source tree installed in
    development mode (pyproject.toml beside the package's __init__.py), what installs from it: the bundled
    domains and the sub-packages (the tree's other folders, and new ones, are the developer's)."""
    if not (PACKAGE_DIR / "pyproject.toml").is_file():
        return (PACKAGE_DIR,)
    return (PACKAGE_DIR / DOMAINS, *sorted(entry for entry in PACKAGE_DIR.iterdir()
                                           if entry.is_dir() and (entry / "__init__.py").is_file()))


def _look(path: Path, shown: str) -> os.stat_result | None:
    """os.stat of `path` (None when it does not exist); a path that cannot be looked at, such as a loop of
    symbolic links or a name too long, is an OutputFileError naming `shown`."""
    try:
        return os.stat(path)
    except (FileNotFoundError, NotADirectoryError):
        return None
    except OSError as exc:
        reason = {errno.ELOOP: "a loop of symbolic links", errno.ENAMETOOLONG: "the name is too long"}.get(
            exc.errno, exc.strerror or str(exc))
        raise OutputFileError(f"cannot write here: {reason}", file=shown) from None


def _nearest_existing(path: Path, shown: str) -> Path:
    path = Path(os.path.abspath(path))
    while _look(path, shown) is None and path != path.parent:
        path = path.parent
    return path


def _check_not_protected(path: Path, shown: str, folder: bool) -> None:
    """An OutputFileError naming `shown` when `path`, every symbolic link in it followed, lies in a protected
    folder, or is the package folder itself where a folder is to be written (`folder`); for a folder, also
    when one of its entries is a symbolic link into one (a command writes in DIR/models, DIR/training)."""
    real = Path(os.path.realpath(path))
    targets = [real]
    if folder and real.is_dir():
        try:
            targets += [Path(os.path.realpath(e.path)) for e in os.scandir(real) if e.is_symlink()]
        except OSError:  # (unreadable: the probe says so)
            pass
    for target in targets:
        inside = any(target == p or p in target.parents for p in protected_folders())
        if inside or (folder and target == PACKAGE_DIR):
            raise OutputFileError(f"leads into the installed tailor package ({target}), which no command writes "
                                  "in: the bundled domains and models are read-only (give a folder of your own)",
                                  file=shown)


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
    """`path` is (or can be made) a folder we can write files in, outside the installed package."""
    path, shown = Path(path), str(path)
    found = _look(path, shown)
    if found is not None and not stat.S_ISDIR(found.st_mode):
        raise OutputFileError("exists and is not a folder", file=shown)
    nearest = _nearest_existing(path, shown)
    _check_not_protected(path, shown, folder=True)
    _probe(nearest, shown)


def check_output_file(path: Path | str, suffix: str | None = None) -> None:
    """`path` names a file (not a folder) with `suffix` (e.g. ".png") that can be created or replaced, outside
    the installed package."""
    path, shown = Path(path), str(path)
    if suffix is not None and path.suffix.lower() != suffix:
        raise OutputFileError(f"the file name must end in {suffix}", file=shown)
    found = _look(path, shown)
    if found is not None and stat.S_ISDIR(found.st_mode):
        raise OutputFileError("is a folder, not a file name", file=shown)
    if found is not None and not os.access(path, os.W_OK):
        raise OutputFileError("exists and is not writable", file=shown)
    nearest = _nearest_existing(path.parent, shown)
    _check_not_protected(path, shown, folder=False)
    _probe(nearest, shown)


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


def versioned(kind: str, data: dict, provenance: Provenance | None = None) -> dict:
    """A command's JSON output led by its schema (`tailor.<kind>/<version>`), the units of its numbers (the
    README's "JSON outputs") and, given, where it comes from (`Provenance.to_json`)."""
    head = {"schema": f"tailor.{kind}/{SCHEMA_VERSION}", "units": UNITS}
    if provenance is not None:
        head["provenance"] = provenance.to_json()
    return {**head, **data}


@dataclass(frozen=True)
class Provenance:
    """Where a result comes from: the tailor version that made it, the command line that asked for it, the
    seeds it used and the SHA-256 of every model file it read (a model retrained in place changes its digest)."""

    version: str
    argv: tuple[str, ...]  # ("tailor", "refine", ...); () where a library call, not a command, made the result
    seeds: tuple[tuple[str, int], ...] = ()  # (option or role, seed)
    models: tuple[tuple[str, str], ...] = ()  # (model file, SHA-256 of its bytes), by file name

    def to_json(self) -> dict:
        return {"tailor": self.version, "argv": list(self.argv), "seeds": dict(self.seeds),
                "models": [{"file": file, "sha256": digest} for file, digest in self.models]}


def provenance(argv: Sequence[str] | None = None, seeds: Mapping[str, int] | None = None,
               models: Iterable[Path | str] = ()) -> Provenance:
    """The provenance of a command's result: `argv` its arguments after the program name (default: this
    process's, sys.argv[1:]), `seeds` by name, `models` the model files it read (each digested here)."""
    words = tuple(sys.argv[1:] if argv is None else argv)
    files = sorted({str(path) for path in models}, key=lambda name: (Path(name).name, name))
    return Provenance(__version__, ("tailor", *words), tuple((seeds or {}).items()),
                      tuple((file, file_digest(file)) for file in files))


def provenance_lines(data: Mapping) -> list[str]:
    """A provenance in its JSON form (`Provenance.to_json`, as a report holds it) as lines of text, for a report
    meant to be read: the version, the command line and the seeds, then each model file read with its digest."""
    seeds = ", ".join(f"{name} {value}" for name, value in data.get("seeds", {}).items()) or "none"
    command = " ".join(data.get("argv", ())) or "(a library call)"
    return [f"tailor {data.get('tailor', '?')}; command: {command}; seeds: {seeds}",
            *(f"model read: {m['file']} (sha256 {m['sha256']})" for m in data.get("models", ()))]


def file_digest(path: Path | str) -> str:
    """The SHA-256 of a file's bytes, in hex (a model file that cannot be read is a ModelFileError naming it)."""
    try:
        with open(path, "rb") as handle:
            return hashlib.file_digest(handle, "sha256").hexdigest()
    except OSError as exc:
        raise ModelFileError(f"cannot read: {exc.strerror or exc}", file=str(path)) from None


def model_files(folder: Path | str) -> list[Path]:
    """Every model file (*.json) in `folder`, by name: what a command may read when its worker processes load
    the models they need (none where the folder does not exist)."""
    try:
        return sorted(path for path in Path(folder).glob("*.json") if path.is_file())
    except OSError:
        return []
