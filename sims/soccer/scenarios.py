"""The soccer robot's experience scenarios (Sec. 4.1) and the random situations of its problems (Sec. 5.5).

Each scenario draws the initial state (robot, ball) and the goal from documented ranges (all positions keep
FIELD_MARGIN to the field lines; the goal lies DIST_RANGE from the start) and executes one action in a fresh
SoccerSim; `variant` (a name of world.VARIANTS, e.g. "weak_motors") runs it on the changed robot, the
experience of that robot (Ch. 8.1). The situations are random belief states of the bundled problems `score`,
`waypoints` and `approach`, which `tailor evaluate soccer` refines and dispatches.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from tailor.sims.episode import ActionCall, Episode
from tailor.sims.soccer.world import (FIELD_HALF_LENGTH, FIELD_HALF_WIDTH, PIONEER, SPARROW, V_MAX, Dynamics,
                                      variant_dynamics, wrap)

if TYPE_CHECKING:
    from tailor.sims.episode import SequenceResult
    from tailor.sims.soccer.simulator import Noise

FIELD_MARGIN = 0.5  # m, start and goal positions keep this distance to the field lines
BALL_CLEARANCE = 0.8  # m, minimum start distance of the ball point to a ball lying at the goal
# m, the longest distance between two field points: experience covers every distance a task on the field has
# (an upper bound of 5-6 m left a tenth of the soccer evaluation's dribbles outside the learned range)
FIELD_DIAGONAL = math.hypot(2 * (FIELD_HALF_LENGTH - FIELD_MARGIN), 2 * (FIELD_HALF_WIDTH - FIELD_MARGIN))
SAMPLING_STREAM = 1  # second seed word: the scenario's draws are independent of the simulator's noise
# goToPoseFarSide, the collision-rich ball approaches (Table 4.4 like for like): the ball approached from its far
# side, the robot starting ahead of the goal pose (|angle_at| at least 90 degrees: to arrive with the goal heading
# it must go round the ball) and near it. Plain goToPose collided in 41.9% of 2000 of them (goToPoseAtBall, poses
# anywhere on the field: 19.9%; the dissertation's experience: 52%), the more the nearer the ball: 51% at 0.8-1.2 m,
# 34% at 2.5-3 m; with starts anywhere on the field 37% (600 episodes). `tailor evaluate soccer --classifier
# goToPoseAtBall,goToPoseFarSide --episodes 2000` measures it.
FAR_SIDE = (0.5 * math.pi, math.pi)  # rad, |angle_at|
NEAR_BALL = 3.0  # m, the half-size of Fig. 4.8's square round the goal pose, where the collision regions lie


@dataclass(frozen=True)
class Ranges:
    """Random ranges of an experience scenario; the action runs from (start, v) to (goal, phig, vg).

    ball: "none" (no ball in the scene), "goal" (at rest at the goal position), "guide" (at rest in the
    robot's guide at the start). Speeds in m/s, distances in m; headings are uniform in [-pi, pi).
    dynamics: the kind of robot that runs the action (world.PIONEER or world.SPARROW).
    angle_at: where given, the goal heading is drawn instead relative to the bearing from the start to the goal
    (the angle of approach, Table 4.1's angle_at): its size uniform in this range (rad), its sign at random.
    """

    name: str
    action: str
    ball: str
    v_range: tuple[float, float]
    vg_range: tuple[float, float]
    dist_range: tuple[float, float]
    dynamics: Dynamics = PIONEER
    angle_at: tuple[float, float] | None = None

    def ball_at(self, start: tuple[float, float], goal: tuple[float, float]) -> tuple[float, float] | None:
        """Where the ball lies at the start of an episode from position `start` to `goal` (None: no ball)."""
        return {"none": None, "goal": goal, "guide": start}[self.ball]

    def run(self, seed: int, noise: Noise | None = None, variant: str | None = None) -> Episode:
        """One episode; the task and the simulator's noise both follow from `seed` (the task is the same for
        every `variant` of the robot)."""
        robot, ball, call = sample_task(self, np.random.default_rng((seed, SAMPLING_STREAM)))
        return _episode(seed, robot, ball, call, noise, variant_dynamics(variant, self.dynamics))


RANGES: dict[str, Ranges] = {
    # navigation without a ball: random start and goal poses anywhere on the field
    "goToPose": Ranges("goToPose", "goToPose", "none", (0.0, 0.8 * V_MAX), (0.0, 0.6), (0.5, FIELD_DIAGONAL)),
    # ball-aware approach to a ball lying at the goal position, arriving slowly
    "approachBall": Ranges("approachBall", "approachBall", "goal", (0.0, 0.6), (0.0, 0.3),
                           (BALL_CLEARANCE, FIELD_DIAGONAL)),
    # dribbling from standstill or the speed after an approach, ending slowly
    "dribbleBall": Ranges("dribbleBall", "dribbleBall", "guide", (0.0, 0.3), (0.0, 0.2), (0.5, FIELD_DIAGONAL)),
    # plain (ball-unaware) goToPose to a ball at the goal: the data of the collision classifier (Sec. 4.2.2)
    "goToPoseAtBall": Ranges("goToPoseAtBall", "goToPose", "goal", (0.0, 0.6), (0.0, 0.3),
                             (BALL_CLEARANCE, FIELD_DIAGONAL)),
    # the same approach from the ball's far side, near it: the collision-rich approaches (Table 4.4 like for like)
    "goToPoseFarSide": Ranges("goToPoseFarSide", "goToPose", "goal", (0.0, 0.6), (0.0, 0.3),
                              (BALL_CLEARANCE, NEAR_BALL), angle_at=FAR_SIDE),
    # the other robot kind (Sec. 7.3) driving to a position (its ball approach): no ball, stop there
    "goToPosition": Ranges("goToPosition", "goToPosition", "none", (0.0, SPARROW.v_max), (0.0, 0.0),
                           (BALL_CLEARANCE, FIELD_DIAGONAL), SPARROW),
}


def _episode(seed: int, robot: tuple[float, float, float, float], ball: tuple[float, float] | None,
             call: ActionCall, noise: Noise | None = None, dynamics: Dynamics = PIONEER) -> Episode:
    """One action from (robot, ball) in a fresh SoccerSim."""
    from tailor.sims.soccer.simulator import Noise, SoccerSim  # deferred: pymunk loads when an episode runs

    sim = SoccerSim(seed, Noise() if noise is None else noise, dynamics)
    sim.place(robot, ball)
    return sim.run(call)


def _field_point(rng: np.random.Generator) -> tuple[float, float]:
    hx, hy = FIELD_HALF_LENGTH - FIELD_MARGIN, FIELD_HALF_WIDTH - FIELD_MARGIN
    return float(rng.uniform(-hx, hx)), float(rng.uniform(-hy, hy))


def sample_task(ranges: Ranges, rng: np.random.Generator):
    """Draw (robot, ball, call): the start (x, y, phi, v), the ball position or None, the ActionCall."""
    lo, hi = ranges.dist_range
    while True:  # rejection sampling: both points on the field, their distance in range
        start, goal = _field_point(rng), _field_point(rng)
        if lo <= math.hypot(goal[0] - start[0], goal[1] - start[1]) <= hi:
            break
    phi, phig = (float(a) for a in rng.uniform(-math.pi, math.pi, 2))
    v, vg = float(rng.uniform(*ranges.v_range)), float(rng.uniform(*ranges.vg_range))
    if ranges.angle_at is not None:  # drawn after the others: the scenarios without it keep their tasks
        bearing = math.atan2(goal[1] - start[1], goal[0] - start[0])
        phig = wrap(bearing + float(rng.choice((-1.0, 1.0))) * float(rng.uniform(*ranges.angle_at)))
    ball = ranges.ball_at(start, goal)
    return (start[0], start[1], phi, v), ball, ActionCall(ranges.action, (goal[0], goal[1], phig, vg))


def subgoal_episode(action: str, params: np.ndarray, seed: int, variant: str | None = None) -> Episode:
    """An episode of `action` from a refined subgoal (start and goal in `params`), the ball placed as in the
    action's experience scenario (in the guide for dribbleBall), on the robot `variant` (None: the modelled
    one): the on-line experience of Sec. 8.1."""
    p = [float(v) for v in params]
    ball = RANGES[action].ball_at((p[0], p[1]), (p[4], p[5]))
    return _episode(seed, (p[0], p[1], p[2], p[3]), ball, ActionCall(action, tuple(p[4:])), None,
                    variant_dynamics(variant))


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


def run_chain(seed: int, noise: Noise | None = None) -> SequenceResult:
    """One random approachBall -> dribbleBall chain (sample_chain), dispatched without stopping."""
    from tailor.sims.soccer.simulator import simulate_sequence  # deferred: pymunk loads when a chain runs

    robot, ball, calls = sample_chain(np.random.default_rng((seed, SAMPLING_STREAM)))
    return simulate_sequence(robot, ball, calls, seed, noise)


# --- random situations of the bundled problems (tailor evaluate soccer) -----------------------------------
FIELD_X = (-FIELD_HALF_LENGTH, FIELD_HALF_LENGTH)  # m
FIELD_Y = (-FIELD_HALF_WIDTH, FIELD_HALF_WIDTH)
MARGIN = 0.8  # m kept free between random positions and the walls
MIN_GAP = 1.0  # m between consecutive random positions


def _point(rng: np.random.Generator, margin: float = MARGIN) -> tuple[float, float]:
    return (float(rng.uniform(FIELD_X[0] + margin, FIELD_X[1] - margin)),
            float(rng.uniform(FIELD_Y[0] + margin, FIELD_Y[1] - margin)))


def _points(rng: np.random.Generator, n: int, margin: float = MARGIN) -> list[tuple[float, float]]:
    """n random positions on the field, `margin` inside its lines, each at least MIN_GAP from the one before."""
    points = [_point(rng, margin)]
    while len(points) < n:
        p = _point(rng, margin)
        if math.dist(p, points[-1]) >= MIN_GAP:
            points.append(p)
    return points


def score_belief(rng: np.random.Generator, margin: float = MARGIN) -> tuple[str, dict[str, dict[str, float]]]:
    """A random situation of problem `score`: robot at rest at pos1, the ball at pos2, the target pose pos3."""
    robot, ball, target = _points(rng, 3, margin)
    heading = lambda: float(rng.uniform(-math.pi, math.pi))  # noqa: E731
    return "score", {"pos1": {"x": robot[0], "y": robot[1], "phi": heading(), "v": 0.0},
                     "pos2": {"x": ball[0], "y": ball[1]},
                     "pos3": {"x": target[0], "y": target[1], "phi": heading(), "v": 0.0}}


def score_anywhere_belief(rng: np.random.Generator) -> tuple[str, dict[str, dict[str, float]]]:
    """A situation of problem `score` drawn anywhere on the field: as score_belief, but the robot, ball and
    target may lie on the very lines (1 m from the walls), where the walls shape the approach and the dribble."""
    return score_belief(rng, margin=0.0)


def waypoints_belief(rng: np.random.Generator) -> tuple[str, dict[str, dict[str, float]]]:
    """A random situation of problem `waypoints`: start p0 at rest, way-points w1..w4, stop at w4."""
    points = _points(rng, 5)
    objects = {"p0": {"x": points[0][0], "y": points[0][1], "phi": float(rng.uniform(-math.pi, math.pi)), "v": 0.0}}
    for k in range(1, 5):
        objects[f"w{k}"] = {"x": points[k][0], "y": points[k][1]}
    objects["w4"].update(phi=float(rng.uniform(-math.pi, math.pi)), v=0.0)
    return "waypoints", objects


def _approach(scenario: str, rng: np.random.Generator) -> tuple[str, dict[str, dict[str, float]]]:
    """A ball approach of problem `approach` drawn as the experience scenario `scenario` draws its tasks."""
    robot, _ball, call = sample_task(RANGES[scenario], rng)
    xg, yg, phig, vg = call.goal
    return "approach", {"pos1": {"x": robot[0], "y": robot[1], "phi": robot[2], "v": robot[3]},
                        "pos2": {"x": xg, "y": yg, "phi": phig, "v": vg}}


def approach_belief(rng: np.random.Generator) -> tuple[str, dict[str, dict[str, float]]]:
    """A random ball approach of problem `approach` (Sec. 6.3): start and ball anywhere on the field, the
    approach heading random, drawn as the goToPose collision classifier's experience (goToPoseAtBall)."""
    return _approach("goToPoseAtBall", rng)


def approach_far_side_belief(rng: np.random.Generator) -> tuple[str, dict[str, dict[str, float]]]:
    """A collision-rich ball approach of problem `approach`: the ball approached from its far side, the robot at
    most NEAR_BALL from it, drawn as goToPoseFarSide (plain goToPose collides in about 42% of them)."""
    return _approach("goToPoseFarSide", rng)


SITUATIONS = {"score": score_belief, "score_anywhere": score_anywhere_belief, "waypoints": waypoints_belief,
              "approach": approach_belief, "approach_far_side": approach_far_side_belief}
