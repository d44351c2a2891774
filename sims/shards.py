"""Persisted experience: a folder of shards, each a compressed .npz of consecutive episodes of one scenario (with
their measures, sims.experience: a shard written before measures existed loads with none).

A shard holds episodes first .. stop - 1 of a scenario's seed stream (episode i's seed depends only on the
stream's seed and i, tailor.sims.experience.episode_seeds), so shards gathered apart, on other machines or
with other workers, merge into exactly the episodes of one serial gather. File name and content agree:
`<scenario>.seed<seed>.<first>-<stop>.npz`, its origin (simulator, scenario, seed, range) stored inside.

`stored_gather` is `gather` with such a folder: the episodes already there are loaded, the missing ranges
(gaps between shards, or past the last one) are simulated and written as new shards, and the merged list is
returned in episode order. Two shards of one stream that overlap are an error naming both files (which one
is right cannot be told); a shard of another simulator, a file whose content does not match its name, of an
unknown schema or not a shard at all is an error naming the file, and so is a shard the simulator's code of now
did not gather (its code fingerprint differs: an edited controller would otherwise train stale models). On
Ctrl-C the episodes finished so far are written as a shard of their own (a complete file, renamed into place),
so the next run resumes after them. One run at a time gathers into a folder (`experience_lock`, an advisory
lock): two at once would both simulate the episodes missing when they started, and write overlapping shards.
"""

from __future__ import annotations

import contextlib
import errno
import logging
import os
import re
import threading
from collections.abc import Iterator
from dataclasses import dataclass, replace
from pathlib import Path

try:
    import fcntl
except ImportError:  # (not on Windows: no lock there)
    fcntl = None

from tailor.errors import DataError, OutputFileError
from tailor.sims.episode import Episode
from tailor.sims import experience, registry
from tailor.sims.experience import Origin, episode_seeds, load_episodes, read_origin, save_episodes

log = logging.getLogger(__name__)
SUFFIX = ".npz"
NAME = re.compile(r"^(?P<scenario>[^.]+)\.seed(?P<seed>-?\d+)\.(?P<first>\d+)-(?P<stop>\d+)\.npz$")
LOCK_FILE = ".tailor.lock"  # in an experience folder while a run writes there: flock'ed, holding the run's pid
LOCK_TRIES = 10  # attempts at taking a lock file that its holder removes meanwhile
_held: dict[Path, list[int]] = {}  # folder -> [the thread holding its lock, times it entered]
_held_guard = threading.Lock()


@dataclass(frozen=True)
class Shard:
    """One shard file and the episodes it holds."""

    path: Path
    origin: Origin


def shard_name(origin: Origin) -> str:
    return f"{origin.scenario}.seed{origin.seed}.{origin.first}-{origin.stop}{SUFFIX}"


def write_shard(directory: str | os.PathLike, origin: Origin, episodes: list[Episode]) -> Shard:
    """Write `episodes` (those of `origin`, in order) as a shard in `directory`, atomically, stamped with the
    simulator's code fingerprint where `origin` has none."""
    if not origin.code:
        origin = replace(origin, code=registry.code_fingerprint(origin.simulator))
    path = Path(directory) / shard_name(origin)
    save_episodes(path, episodes, origin)
    return Shard(path, origin)


def find_shards(directory: str | os.PathLike, simulator: str) -> list[Shard]:
    """Every shard in `directory` (none if it does not exist). Each .npz file must be a shard of `simulator`,
    gathered by its code of now, whose content matches its name; anything else is a DataError naming the file."""
    directory = Path(directory)
    if not directory.is_dir():
        return []
    shards = []
    for path in sorted(directory.glob(f"*{SUFFIX}")):
        origin = read_origin(path)  # a DataError naming the file if it is not an episode file of a known schema
        if origin is None:
            raise DataError("an episode file without its origin (simulator, scenario, seed range) is not a shard: "
                            "move it out of the experience folder", file=str(path))
        if origin.simulator != simulator:
            raise DataError(f"a shard of simulator {origin.simulator!r}, not {simulator!r}: one experience folder "
                            "per simulator", file=str(path))
        code = registry.code_fingerprint(simulator)
        if origin.code != code:
            when = f"by simulator code {origin.code}" if origin.code else "before tailor recorded the simulator's code"
            raise DataError(f"gathered {when}, and {simulator!r} is code {code} now: its episodes would train stale "
                            "models; move the folder's shards away (or give another --experience / --out) to gather "
                            "anew", file=str(path))
        if path.name != shard_name(origin):
            raise DataError(f"holds episodes {origin.first}:{origin.stop} of {origin.scenario} seed {origin.seed}, "
                            f"which its name does not say (expected {shard_name(origin)})", file=str(path))
        shards.append(Shard(path, origin))
    return shards


def stream_shards(shards: list[Shard], scenario: str, seed: int) -> list[Shard]:
    """The shards of one seed stream of one scenario, by first episode; overlapping ones are a DataError."""
    mine = sorted((s for s in shards if s.origin.scenario == scenario and s.origin.seed == seed),
                  key=lambda s: (s.origin.first, s.origin.stop))
    for a, b in zip(mine, mine[1:]):
        if b.origin.first < a.origin.stop:
            raise DataError(f"overlaps {b.path.name} (episodes {b.origin.first}:{min(a.origin.stop, b.origin.stop)} "
                            "are in both): remove one of them", file=str(a.path))
    return mine


@dataclass(frozen=True)
class Piece:
    """Episodes first .. stop - 1 of a stream: read from `shard` (which may hold more), or simulated if None."""

    first: int
    stop: int
    shard: Shard | None


def cover(shards: list[Shard], first: int, stop: int) -> list[Piece]:
    """Episodes first .. stop - 1 as consecutive pieces: from the (non-overlapping, sorted) shards where they
    hold them, the gaps left to simulate."""
    pieces, at = [], first
    for shard in shards:
        lo, hi = max(at, shard.origin.first), min(stop, shard.origin.stop)
        if lo >= hi:
            continue
        if lo > at:
            pieces.append(Piece(at, lo, None))
        pieces.append(Piece(lo, hi, shard))
        at = hi
    if at < stop:
        pieces.append(Piece(at, stop, None))
    return pieces


def load_piece(piece: Piece) -> list[Episode]:
    """The episodes of a stored piece, checked against the seeds the shard's origin implies."""
    origin = piece.shard.origin
    episodes = load_episodes(piece.shard.path)
    path = str(piece.shard.path)
    if len(episodes) != origin.episodes:
        raise DataError(f"holds {len(episodes)} episodes, its origin says {origin.episodes}", file=path)
    entry = registry.get(origin.simulator)
    scenario = entry.scenarios.get(origin.scenario)
    if scenario is not None:  # every episode one of the scenario's action, with that action's parameters
        spec = entry.actions[scenario.action]
        for i, episode in enumerate(episodes):
            if episode.action != scenario.action or len(episode.params) != len(spec.parameters):
                raise DataError(f"episode {origin.first + i} is {episode.action!r} with {len(episode.params)} "
                                f"parameters, not {scenario.action!r} of scenario {origin.scenario} with "
                                f"{len(spec.parameters)}", file=path)
    chosen = episodes[piece.first - origin.first:piece.stop - origin.first]
    if [e.seed for e in chosen] != episode_seeds(origin.seed, piece.stop - piece.first, piece.first):
        raise DataError(f"its episodes' seeds are not those of {origin.scenario} seed {origin.seed}, episodes "
                        f"{piece.first}:{piece.stop} (a file altered or gathered by another version)", file=path)
    return chosen


@contextlib.contextmanager
def experience_lock(directory: str | os.PathLike) -> Iterator[None]:
    """Hold the experience folder's advisory lock (fcntl.flock on LOCK_FILE in it, made if need be) for the
    block: another run, or another thread, gathering into the same folder meanwhile is an OutputFileError
    naming the folder and the process holding it. Entered again by the thread holding it, it holds on. The
    kernel lets go of the lock when its process ends, however it ends: a lock is never left stale (a file left
    by a process killed with SIGKILL is taken over by the next run)."""
    folder = Path(os.path.abspath(directory))
    me = threading.get_ident()
    with _held_guard:
        held = _held.get(folder)
        mine = held is not None and held[0] == me
        if mine:
            held[1] += 1
    if mine:
        try:
            yield
        finally:
            with _held_guard:
                held[1] -= 1
        return
    if held is not None:
        raise OutputFileError("another thread of this process is gathering experience into this folder",
                              file=str(folder))
    fd = _lock(folder)
    with _held_guard:
        _held[folder] = [me, 1]
    try:
        yield
    finally:
        with _held_guard:
            del _held[folder]
        _unlock(folder, fd)


def _lock(folder: Path) -> int | None:
    """The open LOCK_FILE of `folder`, locked; None where there is no lock to take (no fcntl, or a folder we
    cannot write in: then we will not write shards there either). The holder removes the file when it lets
    go (_unlock), so a lock taken on a file that is gone by then, or replaced, is taken again on the new one."""
    if fcntl is None:
        return None
    path = folder / LOCK_FILE
    for _ in range(LOCK_TRIES):
        try:
            folder.mkdir(parents=True, exist_ok=True)
            fd = os.open(path, os.O_RDWR | os.O_CREAT | getattr(os, "O_CLOEXEC", 0), 0o644)
        except OSError as exc:
            if exc.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
                return None
            raise OutputFileError(f"cannot write here: {exc.strerror or exc}", file=str(folder)) from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:  # (BlockingIOError: another open file holds it)
            holder = os.read(fd, 32).decode("ascii", "replace").strip()
            os.close(fd)
            who = f"process {holder}" if holder.isdigit() else "another process"
            raise OutputFileError(f"another tailor run ({who}) is gathering experience into this folder: wait "
                                  "for it to end, or give another folder", file=str(folder)) from None
        try:
            current = os.stat(path).st_ino
        except FileNotFoundError:
            current = None
        if current == os.fstat(fd).st_ino:
            os.ftruncate(fd, 0)
            os.write(fd, f"{os.getpid()}\n".encode("ascii"))
            return fd
        os.close(fd)  # the holder before us removed it as we opened it: take the new one
    raise OutputFileError(f"cannot take the lock {LOCK_FILE} (it keeps changing)", file=str(folder))


def _unlock(folder: Path, fd: int | None) -> None:
    """Let go of the lock _lock took: remove the file while holding it (nothing is left in the folder), then
    close it (which lets go)."""
    if fd is None:
        return
    try:
        (folder / LOCK_FILE).unlink(missing_ok=True)
    finally:
        os.close(fd)


def stored_gather(directory: str | os.PathLike, simulator: str, name: str, episodes: int, seed: int, jobs: int = 1,
                  progress: bool = True, first: int = 0) -> list[Episode]:
    """Episodes first .. first + episodes - 1 of scenario `name`'s seed stream `seed`, like `gather`, but read
    from the shards in `directory` where they are there; the rest is simulated and written there as shards,
    under the folder's lock (experience_lock)."""
    if episodes < 0 or first < 0:
        raise DataError(f"episodes {first}:{first + episodes} is not a range of episodes")
    with experience_lock(directory):
        return _stored_gather(directory, simulator, name, episodes, seed, jobs, progress, first)


def _stored_gather(directory: str | os.PathLike, simulator: str, name: str, episodes: int, seed: int, jobs: int,
                   progress: bool, first: int) -> list[Episode]:
    pieces = cover(stream_shards(find_shards(directory, simulator), name, seed), first, first + episodes)
    stored = sum(p.stop - p.first for p in pieces if p.shard is not None)
    if stored:  # notes, which the command line's -q silences
        files = len({p.shard.path for p in pieces if p.shard is not None})
        log.info("experience: %d episodes of %s (seed %d) read from %d shard(s) in %s", stored, name, seed, files,
                 directory)
    out: list[Episode] = []
    for piece in pieces:
        if piece.shard is not None:
            out.extend(load_piece(piece))
            continue
        done: list[Episode] = []
        try:
            experience.gather(simulator, name, piece.stop - piece.first, seed, jobs=jobs, progress=progress,
                              first=piece.first, into=done)
        except KeyboardInterrupt:
            if done:  # keep what is finished: a complete shard of its own; the next run resumes after it
                kept = write_shard(directory, Origin(simulator, name, seed, piece.first, piece.first + len(done)),
                                   done)
                log.warning("experience: kept the %d finished episodes in %s", len(done), kept.path)
            raise
        shard = write_shard(directory, Origin(simulator, name, seed, piece.first, piece.stop), done)
        log.info("experience: wrote %s", shard.path)
        out.extend(done)
    return out
