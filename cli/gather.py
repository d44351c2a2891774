"""`tailor gather DOMAIN --seeds A:B`: simulate a shard of a domain's experience, for `tailor train --experience`.

Episodes A .. B-1 of each experience scenario the domain's training recipe uses (episode i's seed depends only
on --seed and i), written as one shard per scenario; gathered on several machines or in several runs and put in
one folder, the shards are the episodes of one serial gather, which `tailor train --experience DIR` merges.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from tailor.cli.arguments import (MAX_EPISODES, MAX_SEED, add_backend_arguments, backend_session, seed,
                                             worker_count)



def seed_range(text: str) -> tuple[int, int]:
    """An argparse type: `A:B`, the episodes A .. B-1 (0 <= A < B)."""
    first, colon, stop = text.partition(":")
    try:
        if not colon:
            raise ValueError
        a, b = int(first), int(stop)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected A:B (episodes A to B-1), got {text!r}") from None
    if not 0 <= a < b <= MAX_SEED:
        raise argparse.ArgumentTypeError(f"expected 0 <= A < B <= {MAX_SEED}, got {text!r}")
    if b - a > MAX_EPISODES:
        raise argparse.ArgumentTypeError(f"at most {MAX_EPISODES} episodes at a time, got {text!r}")
    return a, b


seed_range.__name__ = "episode range"


def _export(out: Path, simulator: str, scenario: str, seed: int, first: int, stop: int, episodes, kind: str) -> Path:
    """Write the episodes as a log of executed actions (refinement.learning.logs)."""
    from tailor.refinement.learning.logs import episode_rows, write_log
    from tailor.sims import registry

    path = Path(out) / f"{scenario}.seed{seed}.{first}-{stop}.{kind}"
    columns, rows = episode_rows(episodes, registry.get(simulator), run=f"{scenario}.seed{seed}",
                                 source=f"simulator {simulator}, scenario {scenario}")
    write_log(path, columns, rows, kind)
    return path


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("domain", metavar="DOMAIN", help="bundled domain name, a domain folder, or its domain.pddl")
    parser.add_argument("--seeds", type=seed_range, required=True, metavar="A:B",
                        help="the episodes to simulate, A to B-1 of each scenario's seed stream (e.g. 0:3000 here and "
                             "3000:6000 elsewhere make the 6000 episodes of `tailor train --episodes 6000`)")
    parser.add_argument("--seed", type=seed, default=0, metavar="S",
                        help="the seed of the streams, as `tailor train --seed` (default 0)")
    parser.add_argument("--scenario", action="append", default=None, metavar="NAME",
                        help="only this experience scenario (repeatable; default: every one the recipe uses)")
    parser.add_argument("--out", type=Path, default=None, metavar="DIR",
                        help="the experience folder (default: <user data>/tailor/<domain>/experience, where "
                             "`tailor train` without --out looks; the installed domain folder is never written)")
    parser.add_argument("--format", dest="log_format", choices=("csv", "parquet"), default=None,
                        help="also export the episodes as a log of executed actions, one file per scenario beside "
                             "the shards (<scenario>.seed<S>.<A>-<B>.csv or .parquet, format tailor.action_log/1, "
                             "docs/logs.md), which `tailor train --log` learns from; parquet needs "
                             "pip install 'tailor[logs]'")
    parser.add_argument("--jobs", type=worker_count, default=1, metavar="J",
                        help="worker processes (default 1; at most the number of CPUs)")
    add_backend_arguments(parser)


def run(args: argparse.Namespace) -> int:
    from tailor.errors import DataError
    from tailor.planner_bridge import resolve_domain_dir
    from tailor.refinement.learning.recipe import load_recipe
    from tailor.outputs import check_output_dir
    from tailor.sims.shards import experience_lock, stored_gather

    recipe = load_recipe(resolve_domain_dir(args.domain))
    used = list(dict.fromkeys(s for m in (*recipe.models, *recipe.classifiers) for s in m.scenarios))
    scenarios = args.scenario or used
    for name in scenarios:
        if name not in used:
            raise DataError(f"{recipe.domain!r} trains on no experience scenario {name!r} (known: {', '.join(used)})")
    from tailor.refinement.model_store import default_training_out

    out = default_training_out(recipe.domain_dir) / "experience" if args.out is None else args.out
    check_output_dir(out)
    first, stop = args.seeds
    with backend_session(args), experience_lock(out):  # one run at a time gathers into a folder
        for name in scenarios:
            started = time.perf_counter()
            episodes = stored_gather(out, recipe.simulator, name, stop - first, args.seed, jobs=args.jobs,
                                     progress=getattr(args, "progress", True), first=first)
            seconds = time.perf_counter() - started
            print(f"{name}: episodes {first}:{stop} of seed {args.seed}, {len(episodes)} episodes "
                  f"({sum(e.succeeded for e in episodes)} succeeded) in {seconds:.1f} s")
            if args.log_format:
                path = _export(out, recipe.simulator, name, args.seed, first, stop, episodes, args.log_format)
                print(f"{name}: log of the executed actions in {path}")
    print(f"experience in {out}")
    sys.stdout.flush()
    return 0
