"""The belief state of a problem (Sec. 5.3): continuous values of its PDDL objects, a TOML file beside it.

`problems/score.pddl` has its belief state in `problems/score.toml`:

    [objects.pos1]     # one table per PDDL object
    x = 0.0            # quantities of the domain's simulator (e.g. x, y in m, phi in rad, v in m/s)
    y = 1.0

Only the values the binding reads are required (for facts that hold in the initial state).
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

from tailor.refinement.binding import read_toml
from tailor.errors import BeliefError, is_finite, shown

SCHEMA = 1
BELIEF_SUFFIX = ".toml"


@dataclass(frozen=True)
class BeliefState:
    """Per PDDL object, the values of its quantities."""

    objects: Mapping[str, Mapping[str, float]]
    file: str | None = None

    def value(self, obj: str, quantity: str, needed_by: str = "") -> float:
        """The value of `quantity` of `obj`; if missing, a BeliefError naming both and the fact needing it."""
        values = self.objects.get(obj.lower())
        why = f" (needed by {needed_by})" if needed_by else ""
        if values is None:
            raise BeliefError(f"object '{obj}' has no [objects.{obj}] table{why}", file=self.file)
        if quantity not in values:
            raise BeliefError(f"object '{obj}' has no value for '{quantity}'{why}", file=self.file)
        return values[quantity]

    def check_objects(self, objects: Collection[str]) -> "BeliefState":
        """This belief, once the problem's `objects` are known (the plan carries them): a BeliefError naming the
        file for a table of an object the problem does not have."""
        known = {o.lower() for o in objects}
        for name in self.objects:
            if name not in known:
                raise BeliefError(f"[objects.{name}]: '{name}' is not an object of the problem "
                                  f"(objects: {', '.join(sorted(known))})", file=self.file)
        return self


def belief_path_for(problem_path: Path | str) -> Path:
    """The belief state file of a problem: beside it, same stem (`score.pddl` -> `score.toml`)."""
    return Path(problem_path).with_suffix(BELIEF_SUFFIX)


def load_belief(path: Path | str, objects: Collection[str] | None = None,
                quantities: Collection[str] | None = None) -> BeliefState:
    """Read and validate a belief state file; given the problem's `objects` (the simulator's `quantities`),
    reject any other object (quantity)."""
    file = str(path)
    data = read_toml(Path(path), BeliefError, "belief state")
    return parse_belief(data, file, objects, quantities)


def parse_belief(data: Mapping[str, Any], file: str | None = None,
                 objects: Collection[str] | None = None, quantities: Collection[str] | None = None) -> BeliefState:
    """Validate the parsed TOML of a belief state; every problem is a one-line BeliefError naming `file`."""

    def fail(message: str) -> BeliefError:
        return BeliefError(message, file=file)

    for key in data:
        if key not in ("schema", "objects"):
            raise fail(f"unknown top-level key '{key}' (expected [objects.NAME] tables)")
    if data.get("schema", SCHEMA) != SCHEMA:
        raise fail(f"unsupported schema {data['schema']!r} (expected {SCHEMA})")
    section = data.get("objects", {})
    if not isinstance(section, dict):
        raise fail("'objects' must be a table of tables ([objects.NAME])")
    known = None if objects is None else {o.lower() for o in objects}
    parsed: dict[str, Mapping[str, float]] = {}
    for name, table in section.items():
        if known is not None and name.lower() not in known:
            raise fail(f"[objects.{name}]: '{name}' is not an object of the problem "
                       f"(objects: {', '.join(sorted(known))})")
        if name.lower() in parsed:
            raise fail(f"[objects.{name}] given twice (object names are case-insensitive)")
        if not isinstance(table, dict):
            raise fail(f"[objects.{name}] must be a table of quantities")
        parsed[name.lower()] = MappingProxyType({q: _number(name, q, v, quantities, fail) for q, v in table.items()})
    return BeliefState(MappingProxyType(parsed), file)


def _number(obj: str, quantity: str, value: Any, quantities: Collection[str] | None, fail) -> float:
    where = f"[objects.{obj}] {quantity}"
    if quantities is not None and quantity not in quantities:
        raise fail(f"{where}: unknown quantity '{quantity}' (known: {', '.join(quantities)})")
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise fail(f"{where} = {shown(value)} is not a number")
    if not is_finite(value):
        raise fail(f"{where} = {shown(value)} is not a finite number")
    return float(value)
