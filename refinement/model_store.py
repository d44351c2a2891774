"""Where action models are read from and where training writes them.

The models bundled with a domain (`domains/<name>/models/`) are read-only defaults: `tailor train` never
writes into the installed package; it writes to `--out DIR` or, by default, to the user's data folder,
`<user data>/<domain>/` (platformdirs; e.g. ~/.local/share/tailor/<domain> on Linux), as `models/` and
`training/`. Refinement reads, in this order: `--models DIR` (a folder of `<action>.json`, or a training
output folder holding `models/`), then `$TAILOR_MODELS/<domain>/` when that folder exists (the variable names
a root laid out like the user data folder), then the bundled models; commands say which in one line.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from tailor.errors import ModelFileError

ENVIRONMENT_VARIABLE = "TAILOR_MODELS"
MODELS = "models"  # the folder of <action>.json inside a domain folder or a training output folder


@dataclass(frozen=True)
class ModelSource:
    """The folder a command reads action models from, and why that one."""

    path: Path
    origin: str  # "--models", "$TAILOR_MODELS" or "domain folder" (the bundled defaults)

    def describe(self) -> str:
        return f"action models: {self.path} ({self.origin})"


def user_root() -> Path:
    """The user's tailor data folder: one sub-folder per trained domain."""
    import platformdirs

    return Path(platformdirs.user_data_dir("tailor", appauthor=False))


def default_training_out(domain_dir: Path) -> Path:
    """Where `tailor train` writes a domain's models and reports without `--out`."""
    return user_root() / Path(domain_dir).name


def models_folder(path: Path) -> Path:
    """The folder of model files `path` names: itself, or its `models/` when it is a training output folder."""
    path = Path(path).expanduser()
    return path / MODELS if (path / MODELS).is_dir() else path


def resolve_models(domain_dir: Path, explicit: str | Path | None = None) -> ModelSource:
    """The model folder for the domain in `domain_dir`: `explicit` (must exist), else the environment
    variable's folder for this domain where it exists, else the bundled one."""
    if explicit is not None:
        folder = models_folder(Path(explicit))
        if not folder.is_dir():
            raise ModelFileError("no such model folder (--models)", file=str(explicit))
        return ModelSource(folder, "--models")
    root = os.environ.get(ENVIRONMENT_VARIABLE)
    if root:
        candidate = Path(root).expanduser() / Path(domain_dir).name
        if candidate.is_dir():
            return ModelSource(models_folder(candidate), f"${ENVIRONMENT_VARIABLE}")
    return ModelSource(Path(domain_dir) / MODELS, "domain folder")
