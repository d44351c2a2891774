"""Recorded executions of actions (a real robot's, another simulator's, or tailor's own) as a log that duration
models learn from without a simulator: format `tailor.action_log/1`, documented in docs/logs.md.

One row per executed action: its name, its parameters by name (observed, then internal: the values at its
start), its duration and outcome, a run id and a source, and optionally its measures (`measure.energy [J]`,
Episode.measures); optionally, rows of the state logged while it ran (column `t`, seconds since it started:
the observed parameters and `state.*` columns at that time), which give the intermediate examples of
Sec. 4.1.2.
Numeric columns name their unit, `x [m]`, which must be the one the domain's simulator declares. CSV always;
Parquet where pyarrow is installed (`pip install 'tailor[logs]'`).

Reading checks every row before anything is trained: an unknown action, a missing or non-finite value, a unit
other than the declared one, a column that is no parameter of the domain's actions: one DataError naming
file:row and the column.
"""

from __future__ import annotations

import csv
import io
import math
import re
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tailor.errors import DataError
from tailor.sims.episode import Episode
from tailor.sims.protocol import SimulatorEntry

FORMAT = "tailor.action_log/1"
FORMATS = ("csv", "parquet")
FIXED = ("log_format", "action", "run", "source", "execution", "t", "duration", "outcome")
REQUIRED = ("log_format", "action", "run", "source", "duration", "outcome")
TEXT = ("log_format", "action", "run", "source", "execution", "outcome")
SECONDS = ("t", "duration")
STATE = "state."
MEASURE = "measure."  # an execution row's measure (Episode.measures), e.g. `measure.energy [J]`
HEADER = re.compile(r"^(?P<name>[^\[\]]+?)\s*(\[(?P<unit>[^\[\]]*)\])?$")


@dataclass(frozen=True)
class Column:
    """A header cell: the name and the unit it declares (None: none written)."""

    name: str
    unit: str | None
    header: str


def header(name: str, unit: str) -> str:
    return f"{name} [{unit}]" if unit else name


def _parse_header(cell: str) -> Column:
    match = HEADER.match(cell.strip())
    if not match:
        return Column(cell, None, cell)
    return Column(match["name"].strip(), match["unit"].strip() if match["unit"] is not None else None, cell)


def parameter_units(entry: SimulatorEntry) -> dict[str, str]:
    """Every parameter of the simulator's actions -> the unit its quantity is declared in."""
    units: dict[str, str] = {}
    for spec in entry.actions.values():
        for name, quantity in zip(spec.parameters, spec.observed_quantities + spec.internal_quantities):
            units[name] = entry.quantity(quantity).unit
    return units


# --- writing -----------------------------------------------------------------------------------------------
def episode_rows(episodes: Sequence[Episode], entry: SimulatorEntry, run: str, source: str
                 ) -> tuple[list[str], list[dict]]:
    """The header and the rows (cells as text or numbers, "" where empty) of episodes of one action."""
    if not episodes:
        return [], []
    spec = entry.action(episodes[0].action)
    units = parameter_units(entry)
    observed = tuple(spec.observed)
    extra = [c for c in episodes[0].columns if c not in observed]
    measures = {m: header(MEASURE + m, entry.quantity(m).unit)  # every episode's, in order of appearance
                for m in dict.fromkeys(m for e in episodes for m in e.measures)}
    columns = ["log_format", "action", "run", "source", "execution", "t [s]", "duration [s]", "outcome",
               *(header(p, units.get(p, "")) for p in spec.parameters), *measures.values(),
               *(header(STATE + c, entry.quantity(c).unit) for c in extra)]
    rows = []
    for e in episodes:
        if e.action != spec.name or tuple(e.columns) != tuple(episodes[0].columns):
            raise DataError("a log holds episodes of one action with the same state columns")
        base = {"log_format": FORMAT, "action": e.action, "run": run, "source": source, "execution": str(e.seed)}
        row = {**base, "t [s]": "", "duration [s]": e.duration, "outcome": e.outcome}
        row.update({header(p, units.get(p, "")): float(v) for p, v in zip(spec.parameters, e.params)})
        row.update({measures[m]: float(v) for m, v in e.measures.items()})
        rows.append(row)
        index = {c: k for k, c in enumerate(e.columns)}
        for k, t in enumerate(e.t):
            state = {**base, "t [s]": float(t), "duration [s]": "", "outcome": ""}
            state.update({header(p, units.get(p, "")): float(e.state[k, index[p]]) for p in observed})
            state.update({header(STATE + c, entry.quantity(c).unit): float(e.state[k, index[c]]) for c in extra})
            rows.append(state)
    return columns, rows


def write_log(path: Path, columns: list[str], rows: list[dict], kind: str) -> None:
    """Write rows as CSV or Parquet, atomically (a temporary file renamed into place)."""
    from tailor.outputs import write_atomically

    if kind == "csv":
        def write(tmp: Path) -> None:
            with open(tmp, "w", newline="", encoding="utf-8") as f:
                writer = csv.writer(f)
                writer.writerow(columns)
                for row in rows:
                    writer.writerow([_cell(row.get(c, "")) for c in columns])
    elif kind == "parquet":
        pa, pq = _arrow()

        def write(tmp: Path) -> None:
            data = {}
            for c in columns:
                name = _parse_header(c).name
                values = [row.get(c, "") for row in rows]
                if name in TEXT:
                    data[c] = pa.array([str(v) for v in values], pa.string())
                else:
                    data[c] = pa.array([None if v == "" else float(v) for v in values], pa.float64())
            pq.write_table(pa.table(data), tmp)
    else:
        raise DataError(f"unknown log format {kind!r} (known: {', '.join(FORMATS)})")
    write_atomically(Path(path), write)


def _cell(value) -> str:
    return repr(float(value)) if isinstance(value, float) else str(value)  # repr: floats read back exactly


def _arrow():
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise DataError("Parquet logs need pyarrow: pip install 'tailor[logs]' (CSV needs nothing)") from None
    return pa, pq


# --- reading -----------------------------------------------------------------------------------------------
def _rows(path: Path) -> tuple[list[str], Iterator[tuple[int, list]]]:
    """The header cells and (row number, cells) of a CSV (row = file line) or Parquet (row = 1 + data row) file."""
    if path.suffix.lower() == ".parquet":
        _, pq = _arrow()
        try:
            table = pq.read_table(path)
        except Exception as exc:  # pyarrow raises its own errors for files that are no Parquet
            raise DataError(f"not a Parquet log: {exc}", file=str(path)) from None
        names = list(table.column_names)
        data = table.to_pydict()
        return names, ((k + 2, [data[n][k] for n in names]) for k in range(table.num_rows))
    try:
        text = path.read_text(encoding="utf-8-sig")  # (a spreadsheet's byte-order mark is no column name)
    except FileNotFoundError:
        raise DataError("log file not found", file=str(path)) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise DataError(f"cannot read the log: {exc}", file=str(path)) from None
    reader = csv.reader(io.StringIO(text, newline=""))  # (a quoted cell may hold a line break)
    try:
        names = next(reader)
    except StopIteration:
        raise DataError("empty log (no header row)", file=str(path)) from None
    return names, ((reader.line_num, row) for row in reader)


def read_logs(paths: Sequence[Path], entry: SimulatorEntry, actions: Sequence[str]) -> dict[str, list[Episode]]:
    """The executions of `actions` in the logs, as episodes in file order (other actions of the simulator are
    skipped); every row checked first (see the module doc)."""
    units = parameter_units(entry)
    out: dict[str, list[Episode]] = {a: [] for a in actions}
    for path in map(Path, paths):
        for episode in _episodes(path, entry, units):
            if episode.action in out:
                out[episode.action].append(episode)
    return out


def _episodes(path: Path, entry: SimulatorEntry, units: Mapping[str, str]) -> list[Episode]:
    names, rows = _rows(path)
    where = str(path)
    columns = [_parse_header(str(c)) for c in names]
    seen = set()
    for k, c in enumerate(columns):
        fail = lambda message, c=c: DataError(f"column {c.header!r}: {message}", file=where, line=1)  # noqa: E731
        if c.name in seen:
            raise fail("appears twice")
        seen.add(c.name)
        if c.name in TEXT:
            if c.unit is not None:
                raise fail("a text column has no unit")
        elif c.name in SECONDS:
            if c.unit != "s":
                raise fail(f"durations and times are in seconds: write '{c.name} [s]'")
        elif c.name.startswith((STATE, MEASURE)):
            prefix = STATE if c.name.startswith(STATE) else MEASURE
            if c.name == MEASURE:
                raise fail(f"names no measure ({MEASURE}NAME)")
            declared = entry.quantity(c.name[len(prefix):]).unit
            if (c.unit or "") != declared:
                raise fail(f"unit {c.unit or 'none'!r}, simulator {entry.name!r} declares {declared or 'none'!r}")
        elif c.name in units:
            if (c.unit or "") != units[c.name]:
                raise fail(f"unit {c.unit or 'none'!r}, simulator {entry.name!r} declares {units[c.name] or 'none'!r}"
                           f" for {c.name}")
        else:
            raise fail(f"is no parameter of an action of simulator {entry.name!r} (another domain's log?), nor a "
                       f"column of {FORMAT} ({', '.join(FIXED)}, {STATE}NAME, {MEASURE}NAME)")
    index = {c.name: k for k, c in enumerate(columns)}
    measures = [c.name for c in columns if c.name.startswith(MEASURE)]
    for name in REQUIRED:
        if name not in index:
            raise DataError(f"no column {name!r}: not a {FORMAT} log (docs/logs.md)", file=where, line=1)
    episodes: list[Episode] = []
    current: dict | None = None

    def finish() -> None:
        if current is not None:
            episodes.append(_episode(current))

    for line, cells in rows:
        if len(cells) != len(columns):
            raise DataError(f"{len(cells)} cells, the header has {len(columns)}", file=where, line=line)
        value = lambda name: cells[index[name]] if name in index else ""  # noqa: E731
        fail = lambda name, message: DataError(f"column {columns[index[name]].header!r}: {message}",  # noqa: E731
                                               file=where, line=line)
        if str(value("log_format")) != FORMAT:
            raise fail("log_format", f"{str(value('log_format'))[:40]!r} is not {FORMAT!r}")
        action = str(value("action"))
        if action not in entry.actions:
            raise fail("action", f"{action[:40]!r} is no action of simulator {entry.name!r} "
                                 f"(known: {', '.join(entry.actions)})")
        spec = entry.actions[action]
        t = value("t")
        state_row = t not in ("", None)
        for name, k in index.items():  # cells of other actions' parameters stay empty
            if name in units and name not in spec.parameters and cells[k] not in ("", None):
                raise fail(name, f"is no parameter of {action}")
        missing = [p for p in (spec.parameters if not state_row else spec.observed) if p not in index]
        if missing:
            raise DataError(f"column {header(missing[0], units.get(missing[0], ''))!r}: missing (a parameter of "
                            f"{action})", file=where, line=line)
        if not state_row:
            finish()
            params = np.array([_number(value(p), p, fail) for p in spec.parameters])
            duration = _number(value("duration"), "duration", fail)
            if duration < 0:
                raise fail("duration", f"negative duration {duration!r}")
            outcome = str(value("outcome") or "")
            if not outcome:
                raise fail("outcome", "missing: 'success' or the failure's name")
            measured = {m[len(MEASURE):]: _number(value(m), m, fail)  # an empty cell: not measured
                        for m in measures if value(m) not in ("", None)}
            current = {"action": action, "params": params, "duration": duration, "outcome": outcome,
                       "execution": str(value("execution") or ""), "spec": spec, "t": [], "state": [],
                       "extra": [c.name for c in columns if c.name.startswith(STATE)],
                       "number": len(episodes), "measures": measured}
            continue
        filled = next((m for m in measures if value(m) not in ("", None)), None)
        if filled is not None:
            raise fail(filled, "a measure belongs on its execution's row, not on a state row")
        if current is None or current["action"] != action or (
                "execution" in index and str(value("execution") or "") != current["execution"]):
            raise fail("t", "a state row must follow the row of the execution it belongs to (same action and "
                            "execution)")
        time_ = _number(t, "t", fail)
        observed = [_number(value(p), p, fail) for p in spec.observed]
        extra = [_number(value(c), c, fail, allow_nan=True) for c in current["extra"]]
        current["t"].append(time_)
        current["state"].append(observed + extra)
    finish()
    return episodes


def _number(cell, name: str, fail, allow_nan: bool = False) -> float:
    """A cell's number; missing, not a number or not finite is `fail(name, why)` (a state column may be NaN:
    an object the scene does not have, as in episode files)."""
    if cell in ("", None):
        if allow_nan:
            return math.nan
        raise fail(name, "missing value")
    try:
        value = float(cell)
    except (TypeError, ValueError):
        raise fail(name, f"not a number: {str(cell)[:40]!r}") from None
    if not math.isfinite(value) and not (allow_nan and math.isnan(value)):
        raise fail(name, f"not a finite number: {str(cell)[:40]!r}")
    return value


def _episode(e: dict) -> Episode:
    spec = e["spec"]
    k = len(spec.observed)
    columns = tuple(spec.observed) + tuple(c[len(STATE):] for c in e["extra"])
    if e["t"]:
        t, state = np.array(e["t"], dtype=float), np.array(e["state"], dtype=float).reshape(len(e["t"]), -1)
    else:  # no state logged while it ran: its start is the one example it gives
        t = np.zeros(1)
        state = np.concatenate([e["params"][:k], np.full(len(e["extra"]), np.nan)])[None, :]
    execution = e["execution"]
    seed = int(execution) if execution.isdigit() and int(execution) < 2 ** 63 else e["number"]
    return Episode(e["action"], e["params"], t, state, columns, e["outcome"], e["duration"], seed,
                   e["measures"])

