"""Experience gathering (Sec. 4.1): episodes with random initial and goal states, stored as one .npz file.

Each scenario draws the initial state (robot, ball) and the goal from documented ranges (all positions keep
FIELD_MARGIN to the field lines; the goal lies DIST_RANGE from the start) and executes one action in a
fresh SoccerSim (the "instant environment modification" of Sec. 4.1 replaces a preparatory action).
Episode i of `gather(scenario, n, seed)` depends only on (seed, i): `np.random.SeedSequence(seed)` is
spawned into one child per episode, so the data is identical whatever the number of worker processes.
"""

from __future__ import annotations

import math
import os
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tailor.sims.episode import ActionCall, Episode
from tailor.sims.errors import SimError
from tailor.sims.soccer.simulator import Noise, SoccerSim
from tailor.sims.soccer.world import FIELD_HALF_LENGTH, FIELD_HALF_WIDTH, V_MAX

SCHEMA = 1  # version of the .npz episode file
FIELD_MARGIN = 0.5  # m, start and goal positions keep this distance to the field lines
BALL_CLEARANCE = 0.8  # m, minimum start distance of the ball point to a ball lying at the goal
# m, the longest distance between two field points: experience covers every distance a task on the field has
# (an upper bound of 5-6 m left a tenth of the soccer evaluation's dribbles outside the learned range)
FIELD_DIAGONAL = math.hypot(2 * (FIELD_HALF_LENGTH - FIELD_MARGIN), 2 * (FIELD_HALF_WIDTH - FIELD_MARGIN))
EPISODES_PER_TASK = 10  # episodes one worker runs per joblib task
_SAMPLING_STREAM = 1  # second seed word: the scenario's draws are independent of the simulator's noise


@dataclass(frozen=True)
class Scenario:
    """Random ranges of an experience scenario; the action runs from (start, v) to (goal, phig, vg).

    ball: "none" (no ball in the scene), "goal" (at rest at the goal position), "guide" (at rest in the
    robot's guide at the start). Speeds in m/s, distances in m; headings are uniform in [-pi, pi).
    """

    name: str
    action: str
    ball: str
    v_range: tuple[float, float]
    vg_range: tuple[float, float]
    dist_range: tuple[float, float]

    def ball_at(self, start: tuple[float, float], goal: tuple[float, float]) -> tuple[float, float] | None:
        """Where the ball lies at the start of an episode from position `start` to `goal` (None: no ball)."""
        return {"none": None, "goal": goal, "guide": start}[self.ball]


SCENARIOS: dict[str, Scenario] = {
    # navigation without a ball: random start and goal poses anywhere on the field
    "goToPose": Scenario("goToPose", "goToPose", "none", (0.0, 0.8 * V_MAX), (0.0, 0.6), (0.5, FIELD_DIAGONAL)),
    # ball-aware approach to a ball lying at the goal position, arriving slowly
    "approachBall": Scenario("approachBall", "approachBall", "goal", (0.0, 0.6), (0.0, 0.3),
                             (BALL_CLEARANCE, FIELD_DIAGONAL)),
    # dribbling from standstill or the speed after an approach, ending slowly
    "dribbleBall": Scenario("dribbleBall", "dribbleBall", "guide", (0.0, 0.3), (0.0, 0.2),
                            (0.5, FIELD_DIAGONAL)),
    # plain (ball-unaware) goToPose to a ball at the goal: the data of the collision classifier (Sec. 4.2.2)
    "goToPoseAtBall": Scenario("goToPoseAtBall", "goToPose", "goal", (0.0, 0.6), (0.0, 0.3),
                               (BALL_CLEARANCE, FIELD_DIAGONAL)),
}


def _field_point(rng: np.random.Generator) -> tuple[float, float]:
    hx, hy = FIELD_HALF_LENGTH - FIELD_MARGIN, FIELD_HALF_WIDTH - FIELD_MARGIN
    return float(rng.uniform(-hx, hx)), float(rng.uniform(-hy, hy))


def sample_task(scenario: Scenario, rng: np.random.Generator):
    """Draw (robot, ball, call): the start (x, y, phi, v), the ball position or None, the ActionCall."""
    lo, hi = scenario.dist_range
    while True:  # rejection sampling: both points on the field, their distance in range
        start, goal = _field_point(rng), _field_point(rng)
        if lo <= math.hypot(goal[0] - start[0], goal[1] - start[1]) <= hi:
            break
    phi, phig = (float(a) for a in rng.uniform(-math.pi, math.pi, 2))
    v, vg = float(rng.uniform(*scenario.v_range)), float(rng.uniform(*scenario.vg_range))
    ball = scenario.ball_at(start, goal)
    return (start[0], start[1], phi, v), ball, ActionCall(scenario.action, (goal[0], goal[1], phig, vg))


CHAIN_SEPARATION = 1.0  # m, least distance between robot, ball and target in a random chain
CHAIN_VG_RANGE = (0.0, 0.3)  # m/s, speed at which the robot arrives at the ball


def sample_chain(rng: np.random.Generator):
    """Draw a subgoal chain approachBall -> dribbleBall: (robot, ball, [approach call, dribble call]).

    Robot, ball and target anywhere on the field (FIELD_MARGIN to the lines), pairwise CHAIN_SEPARATION
    apart; the robot starts at rest with a random heading, arrives at the ball with a random heading phig and
    speed vg in CHAIN_VG_RANGE, and dribbles to the target with a random heading, stopping there (vg = 0).
    """
    while True:
        points = [_field_point(rng) for _ in range(3)]
        if all(math.dist(a, b) >= CHAIN_SEPARATION for i, a in enumerate(points) for b in points[i + 1:]):
            break
    (x, y), ball, target = points
    phi, phig, phit = (float(a) for a in rng.uniform(-math.pi, math.pi, 3))
    vg = float(rng.uniform(*CHAIN_VG_RANGE))
    calls = [ActionCall("approachBall", (ball[0], ball[1], phig, vg)),
             ActionCall("dribbleBall", (target[0], target[1], phit, 0.0))]
    return (x, y, phi, 0.0), ball, calls


def run_chain(seed: int, noise: Noise | None = None):
    """One random approachBall -> dribbleBall chain (sample_chain), dispatched without stopping."""
    from tailor.sims.soccer.simulator import simulate_sequence

    robot, ball, calls = sample_chain(np.random.default_rng((seed, _SAMPLING_STREAM)))
    return simulate_sequence(robot, ball, calls, seed, noise)


def run_episode(scenario: str, seed: int, noise: Noise | None = None) -> Episode:
    """One episode of a scenario; the task and the simulator's noise both follow from `seed`."""
    spec = _scenario(scenario)
    robot, ball, call = sample_task(spec, np.random.default_rng((seed, _SAMPLING_STREAM)))
    sim = SoccerSim(seed, Noise() if noise is None else noise)
    sim.reset(robot, ball)
    return sim.run(call)


def episode_seeds(seed: int, episodes: int) -> list[int]:
    """One seed per episode, derived from (seed, index) only."""
    return [int(child.generate_state(1)[0]) for child in np.random.SeedSequence(seed).spawn(episodes)]


def _run_batch(scenario: str, seeds: list[int]) -> list[Episode]:
    return [run_episode(scenario, s) for s in seeds]


def gather(scenario: str, episodes: int, seed: int, jobs: int = 1, progress: bool = True) -> list[Episode]:
    """Execute `episodes` random episodes of a scenario in `jobs` processes (joblib), with a progress bar."""
    from joblib import Parallel, delayed
    from tqdm import tqdm

    _scenario(scenario)
    if episodes < 0 or jobs < 1:
        raise SimError(f"gather needs episodes >= 0 and jobs >= 1, got {episodes} and {jobs}")
    seeds = episode_seeds(seed, episodes)
    batches = [seeds[i:i + EPISODES_PER_TASK] for i in range(0, episodes, EPISODES_PER_TASK)]
    out: list[Episode] = []
    bar = tqdm(total=episodes, desc=f"gather {scenario}", unit="ep", file=sys.stderr, disable=not progress)
    results = Parallel(n_jobs=jobs, return_as="generator")(delayed(_run_batch)(scenario, b) for b in batches)
    try:
        for batch in results:  # in order, so the list is the same for any number of jobs
            out.extend(batch)
            bar.update(len(batch))
    finally:
        bar.close()
        results.close()  # on Ctrl-C this stops the workers before KeyboardInterrupt propagates
    return out


def _scenario(name: str) -> Scenario:
    if name not in SCENARIOS:
        raise SimError(f"unknown experience scenario {name!r}; known: {', '.join(SCENARIOS)}")
    return SCENARIOS[name]


# --- storage -------------------------------------------------------------------------------------------
_KEYS = ("schema", "action", "params", "outcome", "duration", "seed", "offsets", "t", "robot", "ball")


def save_episodes(path: str | os.PathLike, episodes: list[Episode]) -> None:
    """Write the episodes to one compressed .npz (logs concatenated, with offsets), atomically."""
    path = Path(path)
    lengths = [len(e.t) for e in episodes]
    arrays = dict(
        schema=np.array(SCHEMA),
        action=np.array([e.action for e in episodes], dtype=str),
        params=np.array([e.params for e in episodes], dtype=float).reshape(-1, 8),
        outcome=np.array([e.outcome for e in episodes], dtype=str),
        duration=np.array([e.duration for e in episodes], dtype=float),
        seed=np.array([e.seed for e in episodes], dtype=np.int64),
        offsets=np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64),
        t=np.concatenate([e.t for e in episodes]) if episodes else np.zeros(0),
        robot=np.concatenate([e.robot for e in episodes]) if episodes else np.zeros((0, 4)),
        ball=np.concatenate([e.ball for e in episodes]) if episodes else np.zeros((0, 2)),
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
    if (a["params"].shape != (n, 8) or len(a["outcome"]) != n or len(a["duration"]) != n or len(a["seed"]) != n
            or off.shape != (n + 1,) or off[0] != 0 or np.any(np.diff(off) < 0) or off[-1] != len(a["t"])
            or a["robot"].shape != (len(a["t"]), 4) or a["ball"].shape != (len(a["t"]), 2)):
        raise SimError("inconsistent array shapes in episode file", file=name)
    return [Episode(str(a["action"][i]), a["params"][i].copy(), a["t"][off[i]:off[i + 1]].copy(),
                    a["robot"][off[i]:off[i + 1]].copy(), a["ball"][off[i]:off[i + 1]].copy(),
                    str(a["outcome"][i]), float(a["duration"][i]), int(a["seed"][i])) for i in range(n)]
