"""The experiments of Sec. 7.4 on a team scene, one situation at a time (so they run in parallel), and their
tables: Table 7.1 (Q1 agreement, Q2 chose the quickest, Q3 the distance baseline), Fig. 7.9 (Q4 agreement as
estimation noise grows), Fig. 7.10 / 7.11 (Q5 predicting coordination failure), Fig. 7.12 (Q6 communication
quality x field of view for three strategies).

- dynamic (Fig. 7.6): the robots navigate to random poses for DURATION seconds; every robot logs at 10 Hz
  whom it thinks should go, for every strategy, perception and added noise (all on the same course, the
  same perception noise and the same channel draws: the settings are compared pairwise);
- static (Fig. 7.7): the robots drive to random poses and wait; they decide; then each, alone from there,
  really approaches the target, and the quickest is known.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from tailor.refinement.evaluation.coordination import (
    NOBODY,
    STRATEGIES,
    Predictor,
    agreed,
    chose_quickest,
    choices,
    failure_features,
    going,
    learn_failure_tree,
    team_view,
)
from tailor.refinement.situations import stream_seed
from tailor.sims.team import Perception, TeamScene

DURATION = 30.0  # s of one dynamic episode (300 decisions of each robot)
WARMUP = 3.0  # s at the start of an episode not counted: the robots have not looked around yet
NOISE_LEVELS = (0.0, 0.1, 0.2, 0.4, 0.8, 1.6)  # m (and rad on headings) added to teammate estimates (Q4)
COMMUNICATION_LEVELS = (0.0, 0.25, 0.5, 0.75, 1.0)  # share of packets that arrive (Q6)
FIELD_OF_VIEW_LEVELS = (0.0, 90.0, 180.0, 270.0, 360.0)  # degrees (Q6)
Q6_STRATEGIES = ("explicit", "implicit", "shared")
TRAIN_SHARE = 2.0 / 3.0  # Q5: the failure tree learns from the first episodes, is tested on the rest
# Q5 learns when perspective taking fails from estimates alone: implicit coordination without communication and
# with an omnidirectional camera, so that a failure comes from estimation errors in the situation, not from a
# teammate out of sight (with the shared belief of the default perception failures are too rare to learn from)
FAILURE_STRATEGY, FAILURE_FIELD_OF_VIEW, FAILURE_COMMUNICATION = "implicit", 360.0, 0.0
DYNAMIC_STREAM, STATIC_STREAM, NOISE_STREAM, ORACLE_STREAM = 1, 2, 3, 4


@dataclass(frozen=True)
class Setup:
    """One experiment's team and settings; the default perception is Sec. 7.4.1's."""

    kinds: tuple[str, ...]
    seed: int
    perception: Perception = field(default_factory=Perception)
    duration: float = DURATION
    warmup: float = WARMUP
    repeats: int = 1  # static: each approach again under this many other noise seeds


def dynamic_episode(scene: TeamScene, predictor: Predictor, setup: Setup, index: int) -> dict:
    """One dynamic episode: per strategy the ticks agreed and the robots going, Q4's noise levels, Q5's
    situation features with the outcome of FAILURE_STRATEGY, Q6's grid of successes."""
    seed = stream_seed(setup.seed, DYNAMIC_STREAM, index)
    log = scene.dynamic(setup.kinds, setup.duration, seed)
    keep = slice(min(log.ticks, int(round(setup.warmup / log.period))), None)
    robots = len(setup.kinds)
    view = team_view(log, scene, setup.perception, seed)

    def counts(chosen: np.ndarray) -> dict:
        return {"agreed": int(agreed(chosen).sum()),
                "going": np.bincount(going(chosen), minlength=robots + 1).tolist()}

    chosen = {s: choices(view.utilities(s, predictor))[keep] for s in STRATEGIES}
    row = {"index": index, "ticks": int(len(chosen["shared"])), "strategies": {s: counts(c) for s, c in chosen.items()}}
    row["noise"] = [counts(choices(view.utilities("shared", predictor, sigma,
                                                  np.random.default_rng([seed, NOISE_STREAM, k])))[keep])["going"]
                    for k, sigma in enumerate(NOISE_LEVELS)]
    row["features"] = failure_features(log.at(keep), predictor).tolist()
    omni = team_view(log, scene, replace(setup.perception, field_of_view=FAILURE_FIELD_OF_VIEW,
                                         communication=FAILURE_COMMUNICATION), seed)
    row["success"] = (going(choices(omni.utilities(FAILURE_STRATEGY, predictor))[keep]) == 1).tolist()
    grid = {s: np.zeros((len(COMMUNICATION_LEVELS), len(FIELD_OF_VIEW_LEVELS)), dtype=int) for s in Q6_STRATEGIES}
    for a, quality in enumerate(COMMUNICATION_LEVELS):
        for b, fov in enumerate(FIELD_OF_VIEW_LEVELS):
            cell = team_view(log, scene, replace(setup.perception, communication=quality, field_of_view=fov), seed)
            for s in Q6_STRATEGIES:
                grid[s][a, b] = int((going(choices(cell.utilities(s, predictor))[keep]) == 1).sum())
    row["grid"] = {s: g.tolist() for s, g in grid.items()}
    return row


def static_situation(scene: TeamScene, predictor: Predictor, setup: Setup, index: int) -> dict:
    """One static situation: whom each robot chose (models, and distance) when they stood still, and the time
    each robot then really took to the target (None where it failed)."""
    seed = stream_seed(setup.seed, STATIC_STREAM, index)
    situation = scene.static(setup.kinds, seed, setup.repeats)
    view = team_view(situation.log, scene, setup.perception, seed)
    last = situation.log.at(slice(-1, None))
    truth = predictor.times(np.array(last.kinds), last.states[0], np.repeat(last.target, len(last.kinds), axis=0))
    return {"index": index, "seed": seed,
            "believed": _believed_runs(scene, setup, view, seed) if setup.repeats >= 2 else None,
            "chosen": choices(view.utilities("shared", predictor))[-1].tolist(),
            "chosen_distance": choices(view.utilities("distance", predictor))[-1].tolist(),
            "chosen_true_states": int(np.argmin(truth)),
            "predicted": truth.tolist(),
            "measured": [None if t is None else float(t) for t in situation.measured],
            "repeated": [[None if t is None else float(t) for t in run] for run in situation.repeated]}


def _believed_runs(scene: TeamScene, setup: Setup, view, seed: int) -> list[list[float | None]] | None:
    """The oracle fed the team's belief: each robot's approach simulated repeats + 1 times from the states and
    the target the first robot believes at the static decision (its shared belief); None where it knows no
    target, a None time where it knows no state of that robot or the approach failed."""
    belief = view.beliefs("shared")
    states, target = belief.states[-1, 0], belief.target[-1, 0]
    if not np.isfinite(target).all():
        return None

    def run(r: int, k: int, kind: str) -> float | None:
        if not np.isfinite(states[k]).all():
            return None
        t = scene.approach_time(kind, tuple(map(float, states[k])), tuple(map(float, target)),
                                stream_seed(seed, ORACLE_STREAM, r, k))
        return None if t is None else float(t)

    return [[run(r, k, kind) for k, kind in enumerate(setup.kinds)] for r in range(setup.repeats + 1)]


def _times(runs: list) -> np.ndarray:
    """(runs, robots) approach times, inf where an approach failed (None)."""
    return np.array([[np.inf if t is None else t for t in run] for run in runs], dtype=float).reshape(len(runs), -1)


def _share(values) -> float | None:
    values = np.asarray(values, dtype=float)
    return float(values.mean()) if values.size else None


def _repeat_statistics(usable: list[dict], chosen: np.ndarray) -> tuple[float | None, ...]:
    """From each situation's runs (the measured one and its repeats under other noise): how often two runs have
    the same quickest robot; how often an oracle of the expected times (the mean of the other runs, from the true
    states) chose the quickest of the held-out run, the best any predictor can do from the true states; how
    often the robots' own choices did, over the same held-out runs (chose_quickest, with less noise in its
    label); and how often the oracle fed the team's belief did (the mean of its runs from the believed states),
    the best any predictor of the expected time can do from that belief."""
    pairs, oracle, every, believed = [], [], [], []
    for row, choice in zip(usable, chosen):
        if not row["repeated"]:
            continue
        runs = _times([row["measured"], *row["repeated"]])
        quickest = np.argmin(runs, axis=1)
        pairs += [quickest[0] == q for q in quickest[1:]]
        for h in range(len(runs)):
            others = np.delete(runs, h, axis=0).mean(axis=0)
            oracle.append(np.argmin(others) == quickest[h])
            every += list(choice == quickest[h])
        if row.get("believed") is not None:
            guess = np.argmin(_times(row["believed"]).mean(axis=0))
            believed += list(guess == quickest)
    return _share(pairs), _share(oracle), _share(every), _share(believed)


def summarize_static(rows: list[dict]) -> dict:
    """Table 7.1 from the static situations: agreement and chose-the-quickest, with models and by distance."""
    usable = [r for r in rows if any(t is not None for t in r["measured"])]
    measured = _times([r["measured"] for r in usable])
    quickest = np.argmin(measured, axis=1) if len(usable) else np.array([], dtype=int)

    def stats(key: str) -> tuple[float | None, float | None]:
        chosen = np.array([r[key] for r in usable]).reshape(len(usable), -1)
        return _share(agreed(chosen)), _share(chose_quickest(chosen, measured))

    agreement, quick = stats("chosen")
    known = np.array([not all(c == NOBODY for c in r["chosen"]) for r in usable], dtype=bool)
    chosen = np.array([r["chosen"] for r in usable]).reshape(len(usable), -1)
    agreement_distance, quick_distance = stats("chosen_distance")
    predicted = np.array([r["predicted"] for r in usable]).reshape(len(usable), -1)
    again, oracle, every, believed = _repeat_statistics(usable, chosen)
    ok = np.isfinite(measured)
    return {
        "situations": len(rows), "usable": len(usable),
        "decisions": int(measured.size),
        "approach_failures": int((~ok).sum()),
        "target_unknown": sum(all(c == NOBODY for c in r["chosen"]) for r in rows),
        "agreement": agreement, "chose_quickest": quick,
        "agreement_distance": agreement_distance, "chose_quickest_distance": quick_distance,
        "chose_quickest_target_known": _share(chose_quickest(chosen, measured)[known]),
        "quickest_repeatable": again,
        "repeats": min((len(r["repeated"]) for r in usable), default=0),
        "chose_quickest_every_run": every,
        "chose_quickest_oracle": oracle,
        "chose_quickest_oracle_belief": believed,
        "chose_quickest_true_states": _share([r["chosen_true_states"] for r in usable] == quickest),
        "prediction_mae": _share(np.abs(predicted[ok] - measured[ok])),
        "mean_time": _share(measured[ok]),
    }


def summarize_dynamic(rows: list[dict], robots: int, seed: int) -> dict:
    """Q1 (per strategy), Q4, Q5 and Q6 from the dynamic episodes."""
    ticks = sum(r["ticks"] for r in rows)
    strategies = {}
    for s in STRATEGIES:
        going_counts = np.sum([r["strategies"][s]["going"] for r in rows], axis=0) if rows else np.zeros(robots + 1)
        strategies[s] = {"agreement": sum(r["strategies"][s]["agreed"] for r in rows) / ticks if ticks else None,
                         "success": float(going_counts[1] / ticks) if ticks else None,
                         "going_shares": (going_counts / max(1, ticks)).tolist()}
    noise = []
    for k, sigma in enumerate(NOISE_LEVELS):
        counts = np.sum([r["noise"][k] for r in rows], axis=0) if rows else np.zeros(robots + 1)
        noise.append({"sigma": sigma, "going_shares": (counts / max(1, ticks)).tolist()})
    grid = {s: (np.sum([r["grid"][s] for r in rows], axis=0) / max(1, ticks)).tolist() if rows else None
            for s in Q6_STRATEGIES}
    failure = None
    if rows:
        features = np.concatenate([np.asarray(r["features"], dtype=float).reshape(-1, 3) for r in rows])
        success = np.concatenate([np.asarray(r["success"], dtype=bool) for r in rows])
        cut = int(np.ceil(TRAIN_SHARE * len(rows)))
        train = np.concatenate([np.full(r["ticks"], k < cut) for k, r in enumerate(rows)])
        if train.any() and (~train).any():
            failure = learn_failure_tree(features, success, train, seed)
    return {
        "episodes": len(rows), "ticks": ticks,
        "agreement": strategies["shared"]["agreement"],
        "strategies": strategies,
        "noise": noise,
        "failure_tree": None if failure is None else {
            "strategy": FAILURE_STRATEGY, "field_of_view": FAILURE_FIELD_OF_VIEW,
            "communication": FAILURE_COMMUNICATION, **failure.report},
        "communication_fov": {"communication": list(COMMUNICATION_LEVELS),
                              "field_of_view": list(FIELD_OF_VIEW_LEVELS), "success": grid},
        "_failure": failure,
    }


def example(scene: TeamScene, predictor: Predictor, failure) -> dict:
    """Fig. 7.11: robots standing still, the target at points along a line; who is chosen at each point (true
    states) and where the failure tree predicts that coordination might fail."""
    robots, kinds, targets = scene.example()
    n, k = len(robots), len(targets)
    times = predictor.times(np.tile(np.array(kinds), k), np.tile(robots, (k, 1)),
                            np.repeat(targets, n, axis=0)).reshape(k, n)
    order = np.argsort(times, axis=1)
    distances = np.sort(scene.distance(np.tile(robots, (k, 1)), np.repeat(targets, n, axis=0)).reshape(k, n), axis=1)
    sorted_times = np.take_along_axis(times, order, axis=1)
    features = np.column_stack([sorted_times[:, 1] - sorted_times[:, 0], sorted_times[:, 0],
                                distances[:, 1] - distances[:, 0]])
    fails = ~failure.predict_success(features) if failure is not None else np.zeros(k, dtype=bool)
    return {"robots": robots.tolist(), "kinds": list(kinds), "targets": targets.tolist(),
            "chosen": order[:, 0].tolist(), "runner_up": order[:, 1].tolist(), "predicted_failure": fails.tolist()}
