"""The registry of simulators: built-in robots and installed packages, found by entry point.

A package adds a robot without editing tailor by declaring, in its pyproject.toml,

    [project.entry-points."tailor.simulators"]
    pointmass = "my_package.sim:SIMULATOR"     # a SimulatorEntry, or a function returning one

or, in-process, by calling `register(entry)`. The bundled robots register through the same entry-point group.
"""

from __future__ import annotations

import functools
import hashlib
import importlib
import inspect
import sys
from importlib.metadata import entry_points
from pathlib import Path

from tailor.errors import SimError
from tailor.sims.protocol import SimulatorEntry

ENTRY_POINT_GROUP = "tailor.simulators"

_REGISTRY: dict[str, SimulatorEntry] = {}
_FAILED: dict[str, str] = {}  # entry-point name -> why it could not be loaded
_discovered = False


def register(entry: SimulatorEntry, replace: bool = False) -> SimulatorEntry:
    """Add a simulator; a second one of the same name is an error unless `replace`."""
    if not isinstance(entry, SimulatorEntry):
        raise SimError(f"register() needs a SimulatorEntry, got {type(entry).__name__}")
    if entry.name in _REGISTRY and _REGISTRY[entry.name] is not entry and not replace:
        raise SimError(f"a simulator named {entry.name!r} is already registered")
    _REGISTRY[entry.name] = entry
    return entry


def unregister(name: str) -> None:
    _REGISTRY.pop(name, None)


def _discover() -> None:
    """Load every `tailor.simulators` entry point once; one that fails is remembered, not fatal."""
    global _discovered
    if _discovered:
        return
    _discovered = True
    for point in entry_points(group=ENTRY_POINT_GROUP):
        if point.name in _REGISTRY:
            continue
        try:
            value = point.load()
            entry = value() if callable(value) and not isinstance(value, SimulatorEntry) else value
            if not isinstance(entry, SimulatorEntry):
                raise TypeError(f"{point.value} is not a SimulatorEntry")
            if entry.name != point.name:
                raise ValueError(f"{point.value} is named {entry.name!r}, not {point.name!r}")
            _REGISTRY.setdefault(entry.name, entry)
        except Exception as exc:  # a broken plug-in must not break the other robots
            _FAILED[point.name] = f"{type(exc).__name__}: {exc}"


def simulators() -> dict[str, SimulatorEntry]:
    """Every registered simulator by name (entry points loaded on first use)."""
    _discover()
    return dict(sorted(_REGISTRY.items()))


def failed() -> dict[str, str]:
    """Entry points that could not be loaded, with the reason."""
    _discover()
    return dict(_FAILED)


def get(name: str) -> SimulatorEntry:
    """The simulator `name`; a SimError listing the known ones if there is none."""
    _discover()
    if name in _REGISTRY:
        return _REGISTRY[name]
    why = f" (its entry point failed: {_FAILED[name]})" if name in _FAILED else ""
    known = ", ".join(sorted(_REGISTRY)) or "none"
    raise SimError(f"no simulator {name!r} is installed{why} (known: {known})")


@functools.lru_cache(maxsize=None)
def code_fingerprint(name: str) -> str:
    """A fingerprint of the simulator `name`'s code: the first 16 hex digits of a SHA-256 over the Python files of
    the package its `create` comes from (paths and contents); "" where that cannot be found. Experience gathered
    by other code (an edited controller, a changed constant) is not this simulator's experience."""
    create = get(name).create
    module = inspect.getmodule(getattr(create, "func", create))  # (a functools.partial: its function's module)
    source = getattr(module, "__file__", None)
    if not source:
        return ""
    root = Path(source).parent if module.__package__ else None  # a module of a package: the package's folder
    files = sorted(root.rglob("*.py")) if root is not None else [Path(source)]
    digest = hashlib.sha256()
    for path in files:  # (compiled files in __pycache__ are not *.py)
        digest.update(str(path.relative_to(root) if root is not None else path.name).encode())
        digest.update(b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


def deferred_names(package: str, module: str, names: tuple[str, ...]):
    """A module `__getattr__` for a robot's package: `names` of its `module` (the simulator, whose physics library
    loads slowly) are imported on first use, so declaring the robot (its SimulatorEntry) loads no physics."""

    def __getattr__(name: str):
        if name in names:
            value = getattr(importlib.import_module(f"{package}.{module}"), name)
            setattr(sys.modules[package], name, value)
            return value
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    return __getattr__
