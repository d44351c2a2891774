"""Where action models are read from and where training writes them.

The models bundled with a domain (`domains/<name>/models/`) are read-only defaults: `tailor train` never
writes into the installed package; it writes to `--out DIR` or, by default, to the user's data folder,
`<user data>/<domain>/` (platformdirs; e.g. ~/.local/share/tailor/<domain> on Linux), as `models/` and
`training/`, where <domain> is the folder's `domain_key`: a bundled domain's name, another folder's name with
a digest of its path, so two folders of one name never share models or experience. Refinement reads, in this
order: `--models DIR` (a folder of `<action>.json`, or a training output folder holding `models/`), then
`$TAILOR_MODELS/<domain>/` when that folder exists (the variable names a root laid out like the user data
folder), then `<user data>/<domain>/models/` when training wrote model files there, then the bundled models;
commands say which in one line.
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass
from pathlib import Path

from tailor.errors import ModelFileError

ENVIRONMENT_VARIABLE = "TAILOR_MODELS"
MODELS = "models"  # the folder of <action>.json inside a domain folder or a training output folder
MODEL_SUFFIX = ".json"  # of every model file (<action>.json, <action>.collision.json, meta.json)
USER_DATA = "user data folder"  # the origin of models `tailor train` wrote there without --out


@dataclass(frozen=True)
class ModelSource:
    """The folder a command reads action models from, and why that one."""

    path: Path
    origin: str  # "--models", "$TAILOR_MODELS", USER_DATA or "domain folder" (the bundled defaults)

    def describe(self) -> str:
        return f"action models: {self.path} ({self.origin})"


def user_root() -> Path:
    """The user's tailor data folder: one sub-folder per trained domain."""
    import platformdirs

    return Path(platformdirs.user_data_dir("tailor", appauthor=False))


def domain_key(domain_dir: Path) -> str:
    """The name of a domain's folder in the user data folder (and under $TAILOR_MODELS): a bundled domain's
    name; for any other domain folder its name and the first 8 hex digits of the SHA-256 of its resolved path
    (`robot-1a2b3c4d`): two folders named alike (`a/robot` and `b/robot`, a copy named like a bundled domain)
    never share models or experience."""
    from tailor.planner_bridge.bundled import DOMAINS_DIR

    folder = Path(domain_dir).resolve()
    if folder.parent == DOMAINS_DIR.resolve():
        return folder.name
    return f"{folder.name}-{hashlib.sha256(str(folder).encode()).hexdigest()[:8]}"


def default_training_out(domain_dir: Path) -> Path:
    """Where `tailor train` writes a domain's models and reports without `--out`."""
    return user_root() / domain_key(domain_dir)


def models_folder(path: Path) -> Path:
    """The folder of model files `path` names: itself, or its `models/` when it is a training output folder."""
    path = Path(path).expanduser()
    return path / MODELS if (path / MODELS).is_dir() else path


def resolve_models(domain_dir: Path, explicit: str | Path | None = None) -> ModelSource:
    """The model folder for the domain in `domain_dir`: `explicit` (must exist), else the environment
    variable's folder for this domain where it exists, else the user data folder's models of this domain where
    `tailor train` wrote model files (its default output), else the bundled one. Every model file name in it
    must name a regular file (checked before any is opened: a named pipe would block its reader forever)."""
    if explicit is not None:
        folder = models_folder(Path(explicit))
        if not folder.is_dir():
            raise ModelFileError("no such model folder (--models)", file=str(explicit))
        return _checked(ModelSource(folder, "--models"))
    root = os.environ.get(ENVIRONMENT_VARIABLE)
    if root:
        candidate = Path(root).expanduser() / domain_key(domain_dir)
        if candidate.is_dir():
            return _checked(ModelSource(models_folder(candidate), f"${ENVIRONMENT_VARIABLE}"))
    trained = default_training_out(domain_dir) / MODELS
    if _holds_models(trained):
        return _checked(ModelSource(trained, USER_DATA))
    return _checked(ModelSource(Path(domain_dir) / MODELS, "domain folder"))


def _holds_models(folder: Path) -> bool:
    """Whether `folder` is a folder with at least one model file in it (training wrote there)."""
    try:
        return any(entry.name.endswith(MODEL_SUFFIX) for entry in os.scandir(folder))
    except OSError:  # no such folder, or one that cannot be listed: nothing trained there
        return False


def _checked(source: ModelSource) -> ModelSource:
    """`source`, once every `*.json` in its folder is known to be a regular file (or a ModelFileError naming the
    first that is not, or that cannot be looked at)."""
    try:
        entries = sorted(os.scandir(source.path), key=lambda entry: entry.name)
    except OSError:  # no such folder (the bundled one of a domain without models): the loaders say so
        return source
    for entry in entries:
        if not entry.name.endswith(MODEL_SUFFIX):
            continue
        try:
            regular = entry.is_file()  # (following a symbolic link)
        except OSError as exc:
            raise ModelFileError(f"cannot read: {exc.strerror or exc}", file=entry.path) from None
        if not regular and not entry.is_dir():
            raise ModelFileError("not a regular file (a named pipe, a device or a socket, or a broken link): "
                                 "model files are read from regular files only", file=entry.path)
    return source
