"""Experience gathering (Sec. 4.1): episodes of a simulator's scenarios, in parallel, stored as one .npz file.

A scenario (declared by the robot's package) draws a random initial and goal state and executes one action
in a fresh simulator (the "instant environment modification" of Sec. 4.1 replaces a preparatory action).
Episode i of `gather(simulator, scenario, n, seed)` depends only on (seed, i): `np.random.SeedSequence(seed)`
is spawned into one child per episode, so the data is identical whatever the number of worker processes.
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

import numpy as np

from tailor.sims import registry
from tailor.sims.episode import Episode
from tailor.errors import SimError
from tailor.sims.protocol import Scenario

SCHEMA = 2  # version of the .npz episode file (2: named state columns)
EPISODES_PER_TASK = 10  # episodes one worker runs per joblib task


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


def episode_seeds(seed: int, episodes: int) -> list[int]:
    """One seed per episode, derived from (seed, index) only."""
    return [int(child.generate_state(1)[0]) for child in np.random.SeedSequence(seed).spawn(episodes)]


def _run_batch(simulator: str, name: str, seeds: list[int]) -> list[Episode]:
    run = scenario(simulator, name).run
    return [run(s) for s in seeds]


def gather(simulator: str, name: str, episodes: int, seed: int, jobs: int = 1, progress: bool = True) -> list[Episode]:
    """Execute `episodes` random episodes of a scenario in `jobs` processes (joblib), with a progress bar.

    With jobs > 1 the workers find the simulator through its entry point (a simulator registered only
    in-process with `register()` runs with jobs = 1)."""
    from joblib import Parallel, delayed
    from tqdm import tqdm

    scenario(simulator, name)
    if episodes < 0 or jobs < 1:
        raise SimError(f"gather needs episodes >= 0 and jobs >= 1, got {episodes} and {jobs}")
    seeds = episode_seeds(seed, episodes)
    batches = [seeds[i:i + EPISODES_PER_TASK] for i in range(0, episodes, EPISODES_PER_TASK)]
    out: list[Episode] = []
    bar = tqdm(total=episodes, desc=f"gather {name}", unit="ep", file=sys.stderr,
               disable=None if progress else True)  # None: a bar on a terminal only
    if jobs == 1:
        try:
            for batch in batches:
                out.extend(_run_batch(simulator, name, batch))
                bar.update(len(batch))
        finally:
            bar.close()
        return out
    results = Parallel(n_jobs=jobs, return_as="generator")(delayed(_run_batch)(simulator, name, b) for b in batches)
    try:
        for batch in results:  # in order, so the list is the same for any number of jobs
            out.extend(batch)
            bar.update(len(batch))
    finally:
        bar.close()
        results.close()  # on Ctrl-C this stops the workers before KeyboardInterrupt propagates
    return out


# --- storage -------------------------------------------------------------------------------------------
_KEYS = ("schema", "action", "params", "outcome", "duration", "seed", "offsets", "t", "state", "columns")


def save_episodes(path: str | os.PathLike, episodes: list[Episode]) -> None:
    """Write episodes of one action (same parameters and columns) to one compressed .npz, atomically."""
    path = Path(path)
    if len({(e.action, len(e.params), e.columns) for e in episodes}) > 1:
        raise SimError("save_episodes takes episodes of one action with the same state columns", file=str(path))
    columns = episodes[0].columns if episodes else ()
    n_params = len(episodes[0].params) if episodes else 0
    lengths = [len(e.t) for e in episodes]
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
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            np.savez_compressed(f, **arrays)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def load_episodes(path: str | os.PathLike) -> list[Episode]:
    """Read episodes written by save_episodes; a missing, malformed or foreign file raises SimError."""
    name = str(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            missing = [k for k in _KEYS if k not in data.files]
            if missing:
                raise SimError(f"not an episode file (missing {', '.join(missing)})", file=name)
            if int(data["schema"]) != SCHEMA:
                raise SimError(f"episode schema {int(data['schema'])}, expected {SCHEMA}", file=name)
            a = {k: data[k] for k in _KEYS}
    except SimError:
        raise
    except (OSError, ValueError, KeyError, EOFError) as exc:
        raise SimError(f"cannot read episode file: {exc}", file=name) from None
    n, off = len(a["action"]), a["offsets"]
    columns = tuple(str(c) for c in a["columns"])
    if (a["params"].ndim != 2 or len(a["params"]) != n or len(a["outcome"]) != n or len(a["duration"]) != n
            or len(a["seed"]) != n or off.shape != (n + 1,) or off[0] != 0 or np.any(np.diff(off) < 0)
            or off[-1] != len(a["t"]) or (n and a["state"].shape != (len(a["t"]), len(columns)))):
        raise SimError("inconsistent array shapes in episode file", file=name)
    return [Episode(str(a["action"][i]), a["params"][i].copy(), a["t"][off[i]:off[i + 1]].copy(),
                    a["state"][off[i]:off[i + 1]].copy(), columns, str(a["outcome"][i]), float(a["duration"][i]),
                    int(a["seed"][i])) for i in range(n)]
