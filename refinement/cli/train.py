"""`tailor train DOMAIN`: learn the domain's action models from simulated experience (Chapter 4)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

HELP = "gather experience in the simulator and learn the action models (durations, success classifiers)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("domain", help="bundled domain name, a domain folder, or its domain.pddl")
    parser.add_argument("--episodes", type=int, default=None, metavar="N",
                        help="episodes gathered per scenario (default: the domain's [training] episodes)")
    parser.add_argument("--fresh-episodes", type=int, default=None, metavar="M",
                        help="fresh episodes each success classifier is evaluated on (default: the domain's)")
    parser.add_argument("--seed", type=int, default=0, help="seed of experience and training (default 0)")
    parser.add_argument("--jobs", type=int, default=1, metavar="J", help="simulator worker processes (default 1)")
    parser.add_argument("--out", type=Path, default=None, metavar="DIR",
                        help="write DIR/models/*.json and DIR/training/ (default: the domain's folder)")
    parser.add_argument("--n-i", type=_positive_ints, default=None, metavar="LIST",
                        help="candidate examples per episode n_i, comma-separated (default 1,2,3,5,10,20,30,50)")
    parser.add_argument("--json", action="store_true", help="print the report as JSON on stdout")


def _positive_ints(text: str) -> tuple[int, ...]:
    try:
        values = tuple(int(part) for part in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated integers, got {text!r}") from None
    if not values or min(values) < 1:
        raise argparse.ArgumentTypeError(f"n_i candidates must be positive, got {text!r}")
    return values


def run(args: argparse.Namespace) -> int:
    from tailor.planner_bridge import resolve_domain_dir
    from tailor.refinement.errors import DataError
    from tailor.refinement.learning.protocol import N_I_CANDIDATES
    from tailor.refinement.learning.recipe import load_recipe
    from tailor.refinement.learning.training import train_domain

    recipe = load_recipe(resolve_domain_dir(args.domain))
    episodes = recipe.episodes if args.episodes is None else args.episodes
    if episodes < 8:
        raise DataError(f"--episodes must be at least 8 (a quarter of them is the test set), got {episodes}")
    if args.fresh_episodes is not None and args.fresh_episodes < 1:
        raise DataError(f"--fresh-episodes must be positive, got {args.fresh_episodes}")
    if args.jobs < 1:
        raise DataError(f"--jobs must be positive, got {args.jobs}")
    out = recipe.domain_dir if args.out is None else args.out
    report = train_domain(recipe, episodes, args.seed, out, jobs=args.jobs, fresh_episodes=args.fresh_episodes,
                          n_i_candidates=args.n_i or N_I_CANDIDATES, progress=True)
    if args.json:
        json.dump(report, sys.stdout, indent=1)
        sys.stdout.write("\n")
    else:
        print((out / "training" / "report.txt").read_text(encoding="utf-8"), end="")
        print(f"wrote {out / 'models'} and {out / 'training'}")
    return 0
