"""Persisted experience: a folder of shards, each a compressed .npz of consecutive episodes of one scenario.

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
so the next run resumes after them.
"""

from __future__ import annotations

import logging
import os
import re
from dataclasses import dataclass, replace
from pathlib import Path

from tailor.errors import DataError
from tailor.sims.episode import Episode
from tailor.sims import experience, registry
from tailor.sims.experience import Origin, episode_seeds, load_episodes, read_origin, save_episodes

log = logging.getLogger(__name__)
SUFFIX = ".npz"
NAME = re.compile(r"^(?P<scenario>[^.]+)\.seed(?P<seed>-?\d+)\.(?P<first>\d+)-(?P<stop>\d+)\.npz$")


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


def stored_gather(directory: str | os.PathLike, simulator: str, name: str, episodes: int, seed: int, jobs: int = 1,
                  progress: bool = True, first: int = 0) -> list[Episode]:
    """Episodes first .. first + episodes - 1 of scenario `name`'s seed stream `seed`, like `gather`, but read
    from the shards in `directory` where they are there; the rest is simulated and written there as shards."""
    if episodes < 0 or first < 0:
        raise DataError(f"episodes {first}:{first + episodes} is not a range of episodes")
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
