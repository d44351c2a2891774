"""Experience gathering (Sec. 4.1): episodes of a simulator's scenarios, in parallel, stored as compressed .npz.

A scenario (declared by the robot's package) draws a random initial and goal state and executes one action
in a fresh simulator (the "instant environment modification" of Sec. 4.1 replaces a preparatory action).
Episode i of `gather(simulator, scenario, n, seed)` depends only on (seed, i): `np.random.SeedSequence(seed)`
is spawned into one child per episode, so the data is identical whatever the number of worker processes.
"""

from __future__ import annotations

import math
import os
import stat
import tempfile
import zipfile
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tailor.progress import stage_bar
from tailor.sims import registry
from tailor.sims.episode import Episode
from tailor.errors import DataError, SimError
from tailor.sims.protocol import Scenario

# version of the .npz episode file (2: named state columns; 3: the origin, optional; 4: measures, optional)
SCHEMA = 4
EPISODES_PER_TASK = 10  # episodes one worker runs per joblib task
MAX_EPISODES = 1_000_000  # the most episodes a command or a binding asks of one scenario (a bound, not a hang)
MAX_SEED = 2**63 - 1  # the largest seed (or episode index) an episode file stores: as a 64-bit integer


def scenario(simulator: str, name: str) -> Scenario:
    """The experience scenario `name` of `simulator`; a SimError listing the known ones if there is none."""
    entry = registry.get(simulator)
    if name not in entry.scenarios:
        raise SimError(f"simulator {simulator!r} has no experience scenario {name!r}; "
                       f"known: {', '.join(entry.scenarios) or 'none'}")
    return entry.scenarios[name]


def run_episode(simulator: str, name: str, seed: int) -> Episode:
    """One episode of a scenario; the task and the simulator's noise both follow from `seed`."""
    return scenario(simulator, name).run(seed)


def episode_seeds(seed: int, episodes: int, first: int = 0) -> list[int]:
    """One seed per episode, derived from (seed, index) only: the seeds of episodes first .. first + episodes - 1
    (child `index` of `np.random.SeedSequence(seed)`, whatever else is spawned)."""
    return [int(np.random.SeedSequence(seed, spawn_key=(index,)).generate_state(1)[0])
            for index in range(first, first + episodes)]


def _run_batch(simulator: str, name: str, seeds: list[int]) -> list[Episode]:
    run = scenario(simulator, name).run
    return [run(s) for s in seeds]


def gather(simulator: str, name: str, episodes: int, seed: int, jobs: int = 1, progress: bool = True,
           first: int = 0, into: list[Episode] | None = None) -> list[Episode]:
    """Execute episodes first .. first + episodes - 1 of a scenario's seed stream, with a progress bar (log lines
    where stderr is not a terminal, tailor.progress.stage_bar), in `jobs` worker processes (or the workers of the backend session in force, tailor.sims.parallel).

    The episodes are appended to `into` (a new list by default) in order as batches finish, so a caller
    interrupted by Ctrl-C keeps the complete prefix. With workers the simulator is found through its entry
    point (a simulator registered only in-process with `register()` runs with jobs = 1 on loky)."""
    from tailor.sims.parallel import ordered_results

    scenario(simulator, name)
    if episodes < 0 or first < 0 or jobs < 1:
        raise SimError(f"gather needs episodes >= 0, first >= 0 and jobs >= 1, got {episodes}, {first} and {jobs}")
    seeds = episode_seeds(seed, episodes, first)
    batches = [(simulator, name, seeds[i:i + EPISODES_PER_TASK]) for i in range(0, episodes, EPISODES_PER_TASK)]
    out: list[Episode] = [] if into is None else into
    bar = stage_bar(episodes, f"gather {name}", "ep", progress)
    results = ordered_results(_run_batch, batches, jobs)
    try:
        for batch in results:  # in order, so the list is the same for any backend and number of workers
            out.extend(batch)
            bar.update(len(batch))
    finally:
        bar.close()
        results.close()  # on Ctrl-C this stops the workers before KeyboardInterrupt propagates
    return out


# --- storage -------------------------------------------------------------------------------------------
_KEYS = ("schema", "action", "params", "outcome", "duration", "seed", "offsets", "t", "state", "columns")
_ORIGIN_KEYS = ("simulator", "scenario", "stream_seed", "first", "stop")
# the episodes' measures (Episode.measures): the names (k,), the values (n, k), NaN where an episode has none
_MEASURE_KEYS = ("measure_names", "measures")
# 2 had no origin, 2 and 3 no measures (their episodes load with none); all hold the same episode arrays
READABLE_SCHEMAS = (2, 3, 4)
# no episode file may declare more bytes than the machine has memory (unknown: no bound)
_MEMORY_BYTES = (os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
                 if hasattr(os, "sysconf") and "SC_PHYS_PAGES" in os.sysconf_names else math.inf)


@dataclass(frozen=True)
class Origin:
    """Where a file's episodes come from: episodes first .. stop - 1 of `scenario`'s seed stream `seed`
    (`episode_seeds(seed, stop - first, first)`) in `simulator`."""

    simulator: str
    scenario: str
    seed: int
    first: int
    stop: int
    code: str = ""  # the simulator's code fingerprint (registry.code_fingerprint); "" for files without one

    @property
    def episodes(self) -> int:
        return self.stop - self.first


def save_episodes(path: str | os.PathLike, episodes: list[Episode], origin: Origin | None = None) -> None:
    """Write episodes of one action (same parameters and columns) to one compressed .npz, atomically (a
    temporary file renamed into place: Ctrl-C never leaves half a file), with their `origin` if given."""
    path = Path(path)
    if len({(e.action, len(e.params), e.columns) for e in episodes}) > 1:
        raise DataError("save_episodes takes episodes of one action with the same state columns", file=str(path))
    if origin is not None and origin.episodes != len(episodes):
        raise DataError(f"{len(episodes)} episodes cannot be episodes {origin.first}:{origin.stop}", file=str(path))
    columns = episodes[0].columns if episodes else ()
    n_params = len(episodes[0].params) if episodes else 0
    lengths = [len(e.t) for e in episodes]
    measures = list(dict.fromkeys(name for e in episodes for name in e.measures))  # in order of appearance
    arrays = dict(
        schema=np.array(SCHEMA),
        action=np.array([e.action for e in episodes], dtype=str),
        params=np.array([e.params for e in episodes], dtype=float).reshape(-1, n_params),
        outcome=np.array([e.outcome for e in episodes], dtype=str),
        duration=np.array([e.duration for e in episodes], dtype=float),
        seed=np.array([e.seed for e in episodes], dtype=np.int64),
        offsets=np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64),
        t=np.concatenate([e.t for e in episodes]) if episodes else np.zeros(0),
        state=np.concatenate([e.state for e in episodes]) if episodes else np.zeros((0, 0)),
        columns=np.array(columns, dtype=str),
    )
    if measures:
        values = [[e.measures.get(m, np.nan) for m in measures] for e in episodes]
        arrays.update(measure_names=np.array(measures, dtype=str), measures=np.array(values, dtype=float))
    if origin is not None:
        arrays.update(simulator=np.array(origin.simulator), scenario=np.array(origin.scenario),
                      stream_seed=np.array(origin.seed, dtype=np.int64), first=np.array(origin.first, dtype=np.int64),
                      stop=np.array(origin.stop, dtype=np.int64))
        if origin.code:
            arrays.update(simulator_code=np.array(origin.code))
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            np.savez_compressed(f, **arrays)
        os.chmod(tmp, 0o644)  # mkstemp makes files private; experience is data like any other
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def _open(path: str | os.PathLike):
    """np.load of an episode file whose schema is readable; DataError naming the file otherwise. Only a
    regular file is opened (a named pipe would block), and the sizes its arrays declare are checked before any
    is read."""
    name = str(path)
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):
            raise DataError("not an episode file (not a regular file)", file=name)
        data = np.load(path, allow_pickle=False)
    except (ValueError, EOFError, zipfile.BadZipFile):  # numpy takes bytes that are no .npz / .npy for pickled data
        raise DataError("not an episode file (not an .npz archive)", file=name) from None
    except OSError as exc:
        raise DataError(f"cannot read episode file: {exc.strerror or exc}", file=name) from None
    if not hasattr(data, "files"):
        raise DataError("not an episode file (one array, not an .npz archive)", file=name)
    try:
        _check_declared_sizes(data, name)
        missing = [k for k in _KEYS if k not in data.files]
        if missing:
            raise DataError(f"not an episode file (missing {', '.join(missing)})", file=name)
        schema = int(data["schema"])
        if schema not in READABLE_SCHEMAS:
            raise DataError(f"episode schema {schema}, expected {SCHEMA}", file=name)
    except BaseException:
        data.close()
        raise
    return data


def _check_declared_sizes(data, name: str) -> None:
    """A DataError, before numpy allocates anything, for an array whose header declares more values than its
    member of the archive holds (a header claiming 10**10 values would have numpy allocate 75 GiB first), or
    for arrays declaring more bytes together than this machine's memory."""
    total = 0
    for info in data.zip.infolist():
        try:
            with data.zip.open(info) as member:
                version = np.lib.format.read_magic(member)
                read_header = np.lib.format.read_array_header_1_0 if version == (1, 0) else \
                    np.lib.format.read_array_header_2_0
                shape, _, dtype = read_header(member)
                header = member.tell()
        except (ValueError, OSError, EOFError, zipfile.BadZipFile, zlib.error):
            raise DataError(f"not an episode file (its {info.filename} is not an array)", file=name) from None
        declared = math.prod(shape) * dtype.itemsize
        if declared != info.file_size - header:
            raise DataError(f"its {info.filename} declares {math.prod(shape)} values of {dtype.itemsize} bytes, "
                            f"but holds {max(0, info.file_size - header)} bytes", file=name)
        total += declared
    if total > _MEMORY_BYTES:
        raise DataError(f"its arrays declare {total / 2**30:.1f} GiB, more than this machine's memory",
                        file=name)


def read_origin(path: str | os.PathLike) -> Origin | None:
    """The origin stored in an episode file (None if it has none); reads only the small arrays."""
    try:
        with _open(path) as data:
            if not all(k in data.files for k in _ORIGIN_KEYS):
                return None
            return Origin(str(data["simulator"]), str(data["scenario"]), int(data["stream_seed"]),
                          int(data["first"]), int(data["stop"]),
                          str(data["simulator_code"]) if "simulator_code" in data.files else "")
    except DataError:
        raise
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
        raise DataError(f"cannot read episode file: {exc}", file=str(path)) from None


def load_episodes(path: str | os.PathLike) -> list[Episode]:
    """Read episodes written by save_episodes; a missing, malformed or foreign file raises DataError."""
    name = str(path)
    try:
        with _open(path) as data:
            a = {k: data[k] for k in _KEYS}
            stored = [k for k in _MEASURE_KEYS if k in data.files]
            if len(stored) == 1:
                missing = ({*_MEASURE_KEYS} - {*stored}).pop()
                raise DataError(f"it holds {stored[0]} without {missing}", file=name)
            a.update({k: data[k] for k in stored})
    except DataError:
        raise
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
        raise DataError(f"cannot read episode file: {exc}", file=name) from None
    n, off = len(a["action"]), a["offsets"]
    columns = tuple(str(c) for c in a["columns"])
    if (a["params"].ndim != 2 or len(a["params"]) != n or len(a["outcome"]) != n or len(a["duration"]) != n
            or len(a["seed"]) != n or off.shape != (n + 1,) or off[0] != 0 or np.any(np.diff(off) < 0)
            or off[-1] != len(a["t"]) or (n and a["state"].shape != (len(a["t"]), len(columns)))):
        raise DataError("inconsistent array shapes in episode file", file=name)
    for key in ("params", "duration", "t", "state", "seed"):
        if a[key].dtype.kind not in "fiu":
            raise DataError(f"its {key} are not numbers ({a[key].dtype})", file=name)
    for key in ("params", "duration", "t"):  # (a state column may be NaN: an object the scene does not have)
        if not np.all(np.isfinite(a[key])):
            raise DataError(f"its {key} hold values that are not finite (NaN or infinity)", file=name)
    if np.any(a["duration"] < 0):
        raise DataError(f"episode {int(np.argmin(a['duration']))} has a negative duration", file=name)
    measures = _measures(a, n, name)
    return [Episode(str(a["action"][i]), a["params"][i].copy(), a["t"][off[i]:off[i + 1]].copy(),
                    a["state"][off[i]:off[i + 1]].copy(), columns, str(a["outcome"][i]), float(a["duration"][i]),
                    int(a["seed"][i]), measures[i]) for i in range(n)]


def _measures(a: dict, n: int, name: str) -> list[dict[str, float]]:
    """Each of the n episodes' measures from a file's arrays (none where the file has none); a DataError
    naming the file for names that are not distinct, or values of the wrong shape or infinite."""
    if "measure_names" not in a:
        return [{} for _ in range(n)]
    names, values = [str(m) for m in a["measure_names"].reshape(-1)], a["measures"]
    if a["measure_names"].ndim != 1 or not all(names) or len(set(names)) != len(names):
        raise DataError(f"its measure_names are not distinct names: {names}", file=name)
    if values.dtype.kind not in "fiu" or values.shape != (n, len(names)):
        raise DataError(f"its measures are not {n} x {len(names)} numbers ({values.dtype}, shape "
                        f"{values.shape})", file=name)
    if np.any(np.isinf(values)):
        raise DataError("its measures hold infinite values", file=name)
    return [{m: float(v) for m, v in zip(names, row) if not math.isnan(v)} for row in values]
