"""Measure the soccer actions: outcomes per experience scenario, subgoal-chain success, duration spread.

    python -m tailor.sims.soccer.measure scenarios [--episodes 200] [--seed 0] [--jobs 2]
    python -m tailor.sims.soccer.measure chains [--episodes 200] [--seed 0] [--jobs 2]
    python -m tailor.sims.soccer.measure spread [--episodes 20]

`scenarios`: per experience scenario of the soccer simulator (scenarios.RANGES), the outcome counts and the mean and standard
deviation of the duration of the successful episodes (the episodes of `gather(scenario, n, seed)`).
`chains`: random approachBall -> dribbleBall chains (sims.experience.sample_chain) and how many succeed.
`spread`: one fixed parameterization per action executed with `--episodes` noise seeds: std / mean duration.
"""

from __future__ import annotations

import argparse
import collections
import math

import numpy as np

from tailor.sims.episode import ActionCall
from tailor.sims.experience import episode_seeds, run_episode
from tailor.sims.soccer.scenarios import RANGES, run_chain
from tailor.sims.soccer.simulator import SoccerSim

# (robot start, ball, call) per action for `spread`: a parameterization with a turn at the start
SPREAD_CASES = {
    "goToPose": ((-2.0, -1.0, 0.0, 0.0), None, ActionCall("goToPose", (1.5, 1.0, math.pi / 2, 0.2))),
    "approachBall": ((-2.0, -1.0, 0.0, 0.0), (1.0, 0.5),
                     ActionCall("approachBall", (1.0, 0.5, math.pi, 0.2))),
    "dribbleBall": ((-2.0, -1.0, math.pi / 2, 0.0), (-2.0, -1.0),
                    ActionCall("dribbleBall", (1.5, 1.0, -math.pi / 2, 0.0))),
}


def _episode(scenario: str, seed: int) -> tuple[str, float]:
    episode = run_episode("soccer", scenario, seed)
    return episode.outcome, episode.duration


def _chain(seed: int) -> tuple[tuple[str, ...], float]:
    result = run_chain(seed)
    return tuple(r.outcome for r in result.results), result.duration


def measure_scenarios(episodes: int, seed: int, jobs: int) -> None:
    from joblib import Parallel, delayed

    for scenario in RANGES:
        runs = Parallel(n_jobs=jobs)(delayed(_episode)(scenario, s) for s in episode_seeds(seed, episodes))
        counts = collections.Counter(outcome for outcome, _ in runs)
        done = np.array([d for outcome, d in runs if outcome == "success"])
        print(f"{scenario:15s} {dict(sorted(counts.items()))}  success duration mean {done.mean():.2f} s, "
              f"std {done.std():.2f} s")


def measure_chains(episodes: int, seed: int, jobs: int) -> None:
    from joblib import Parallel, delayed

    runs = Parallel(n_jobs=jobs)(delayed(_chain)(s) for s in episode_seeds(seed, episodes))
    ok = [d for outcomes, d in runs if outcomes == ("success", "success")]
    print(f"chains approachBall -> dribbleBall: {len(ok)} / {episodes} succeeded "
          f"(mean duration {np.mean(ok):.2f} s); failures: "
          f"{dict(collections.Counter(o for o, _ in runs if o != ('success', 'success')))}")


def measure_spread(episodes: int) -> None:
    for action, (robot, ball, call) in SPREAD_CASES.items():
        durations, outcomes = [], []
        for seed in range(episodes):
            sim = SoccerSim(seed)
            sim.place(robot, ball)
            episode = sim.run(call)
            durations.append(episode.duration)
            outcomes.append(episode.outcome)
        d = np.array(durations)
        print(f"{action:13s} {call.goal} from {robot}: mean {d.mean():.2f} s, std {d.std():.3f} s, "
              f"std/mean {d.std() / d.mean():.3f}, {outcomes.count('success')}/{episodes} succeeded")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tailor.sims.soccer.measure", description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("scenarios", "chains", "spread"))
    parser.add_argument("--episodes", type=int, default=None)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args(argv)
    if args.what == "scenarios":
        measure_scenarios(args.episodes or 200, args.seed, args.jobs)
    elif args.what == "chains":
        measure_chains(args.episodes or 200, args.seed, args.jobs)
    else:
        measure_spread(args.episodes or 20)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
