"""The soccer team scene (Ch. 7): several robots on the field around a ball, for implicit coordination.

Each robot runs in its own SoccerSim (robots do not touch one another: the poses they drive to are random and
the experiments are about who *would* go, so interference is excluded by construction, as in Fig. 7.6a). The
ball lies still. Two kinds of robot (Sec. 7.3): the Pioneer-like robot of every soccer action, which approaches
the ball with approachBall (arriving heading for the opponent goal) and navigates with goToPose, and a slower
SPARROW-like robot whose only navigation action is goToPosition (no goal heading, App. A.2), which is also how it
approaches the ball (the ball is not placed for it: goToPosition knows no ball, it drives to where it lies).

Perception (Sec. 7.4.1): a robot estimates its own pose, its teammates' poses and the ball with Gaussian noise;
teammates and ball are perceived only inside the field of view of its forward camera, centred on its heading
at its ball point.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from tailor.sims.episode import ActionCall
from tailor.sims.soccer.scenarios import RANGES
from tailor.sims.soccer.world import (CONTROL_HZ, FIELD_HALF_LENGTH, FIELD_HALF_WIDTH, LOG_HZ, PIONEER,
                                      SPARROW, Dynamics)
from tailor.sims.team import Observations, Perception, StaticSituation, TeamLog

if TYPE_CHECKING:
    from tailor.sims.soccer.simulator import SoccerSim

STATE = ("x", "y", "phi", "v")  # a robot's state in a team log: position (m), heading (rad), speed (m/s)
PERIOD = 1.0 / LOG_HZ  # s, the robots' decision (and message) period: 10 Hz
CONTROLS_PER_TICK = CONTROL_HZ // LOG_HZ
OPPONENT_GOAL = (FIELD_HALF_LENGTH, 0.0)  # the ball is approached heading for this point
APPROACH_SPEED = 0.1  # m/s, approachBall's arrival speed at the ball
MARGIN = 0.8  # m, random positions keep this distance to the field lines
SEPARATION = 1.0  # m, least distance between the robots and the ball in a random situation
ARRIVED = 0.15  # m, a navigating robot within this of its goal position gets a new one
NAVIGATION_TIMEOUT = 20.0  # s, ... as does one that has not arrived after this long
NAVIGATION_SPEEDS = (0.0, 0.3)  # m/s, speed at a random way-point of the dynamic experiment
SETTLE_TIMEOUT = 30.0  # s, in the static experiment robots stop where they are after this long
LOOK_RATE = 1.5  # rad/s, a waiting robot turns once on the spot at this rate to look around ...
WAIT = 1.0  # s, ... then stands still before the team decides


@dataclass(frozen=True)
class Kind:
    """A kind of robot: its motor limits, how it approaches the ball, how it drives about."""

    dynamics: Dynamics
    approach: str
    navigate: str


KINDS = {"pioneer": Kind(PIONEER, "approachBall", "goToPose"),
         "sparrow": Kind(SPARROW, "goToPosition", "goToPosition")}
DEFAULT_KIND, OTHER_KIND = "pioneer", "sparrow"


def _seed(*words: int) -> int:
    return int(np.random.SeedSequence([int(w) for w in words]).generate_state(1)[0])


def _point(rng: np.random.Generator) -> tuple[float, float]:
    return (float(rng.uniform(-FIELD_HALF_LENGTH + MARGIN, FIELD_HALF_LENGTH - MARGIN)),
            float(rng.uniform(-FIELD_HALF_WIDTH + MARGIN, FIELD_HALF_WIDTH - MARGIN)))


def _separated(rng: np.random.Generator, n: int, keep_from: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """n random field points SEPARATION from each other and from `keep_from`."""
    points: list[tuple[float, float]] = []
    while len(points) < n:
        p = _point(rng)
        if all(math.dist(p, q) >= SEPARATION for q in points + keep_from):
            points.append(p)
    return points


def visible(observer: np.ndarray, points: np.ndarray, field_of_view: float) -> np.ndarray:
    """Whether each point (..., 2) lies in the field of view (degrees) of each observer state (..., 4): within
    half of it either side of the heading, seen from the ball point. 0 sees nothing, 360 everything."""
    observer, points = np.asarray(observer, dtype=float), np.asarray(points, dtype=float)
    shape = np.broadcast_shapes(observer.shape[:-1], points.shape[:-1])
    if field_of_view >= 360.0:
        return np.ones(shape, dtype=bool)
    if field_of_view <= 0.0:
        return np.zeros(shape, dtype=bool)
    bearing = np.arctan2(points[..., 1] - observer[..., 1], points[..., 0] - observer[..., 0])
    off = np.abs(np.mod(bearing - observer[..., 2] + np.pi, 2 * np.pi) - np.pi)
    return off <= math.radians(field_of_view) / 2.0


class SoccerTeam:
    """The TeamScene of the soccer simulator (tailor.sims.team)."""

    kinds = {name: kind.approach for name, kind in KINDS.items()}
    bounds = (-FIELD_HALF_LENGTH, FIELD_HALF_LENGTH, -FIELD_HALF_WIDTH, FIELD_HALF_WIDTH)
    state = STATE
    perturbed = ("x", "y", "phi")  # Q4's added noise: on the pose (m, rad), not on the speed

    def team(self, robots: int, heterogeneous: bool) -> tuple[str, ...]:
        if robots < 2:
            raise ValueError(f"a team has at least 2 robots, got {robots}")
        return (DEFAULT_KIND,) * (robots - 1) + ((OTHER_KIND,) if heterogeneous else (DEFAULT_KIND,))

    # --- simulation -------------------------------------------------------------------------------------
    def _sims(self, kinds: tuple[str, ...], poses: list[tuple[float, float, float]], seed: int) -> list[SoccerSim]:
        from tailor.sims.soccer.simulator import Noise, SoccerSim  # deferred: pymunk loads when the team runs

        sims = []
        for k, (kind, pose) in enumerate(zip(kinds, poses)):
            sim = SoccerSim(_seed(seed, 2, k), Noise(), KINDS[kind].dynamics)
            sim.place((*pose, 0.0))
            sims.append(sim)
        return sims

    def dynamic(self, kinds: tuple[str, ...], duration: float, seed: int) -> TeamLog:
        rng = np.random.default_rng(_seed(seed, 1))
        ball = _point(rng)
        starts = _separated(rng, len(kinds), [ball])
        sims = self._sims(kinds, [(x, y, float(rng.uniform(-math.pi, math.pi))) for x, y in starts], seed)
        goals: list = [None] * len(kinds)
        since = [0.0] * len(kinds)
        ticks = int(round(duration / PERIOD))
        states = np.empty((ticks, len(kinds), 4))
        for tick in range(ticks):
            for k, sim in enumerate(sims):
                states[tick, k] = sim.true_state()[:4]
            for _ in range(CONTROLS_PER_TICK):
                for k, (kind, sim) in enumerate(zip(kinds, sims)):
                    x, y = sim.true_state()[:2]
                    if (goals[k] is None or math.hypot(goals[k][0] - x, goals[k][1] - y) < ARRIVED
                            or since[k] > NAVIGATION_TIMEOUT):
                        goals[k], since[k] = self._way_point(rng, kind, (x, y)), 0.0
                    sim.control_tick(KINDS[kind].navigate, goals[k])
                    since[k] += 1.0 / CONTROL_HZ
        return TeamLog(PERIOD, states, np.tile(ball, (ticks, 1)), tuple(kinds))

    @staticmethod
    def _way_point(rng: np.random.Generator, kind: str, here: tuple[float, float]) -> tuple[float, float, float, float]:
        while True:
            p = _point(rng)
            if math.dist(p, here) >= SEPARATION:
                break
        vg = 0.0 if KINDS[kind].navigate == "goToPosition" else float(rng.uniform(*NAVIGATION_SPEEDS))
        return p[0], p[1], float(rng.uniform(-math.pi, math.pi)), vg

    def static(self, kinds: tuple[str, ...], seed: int, repeats: int = 1) -> StaticSituation:
        """Drive to random waiting poses, look around once, stand WAIT; then each approaches alone (Fig. 7.7), and
        again `repeats` times under other noise."""
        rng = np.random.default_rng(_seed(seed, 1))
        ball = _point(rng)
        waiting = _separated(rng, len(kinds), [ball])
        starts = [_point(rng) for _ in kinds]
        sims = self._sims(kinds, [(x, y, float(rng.uniform(-math.pi, math.pi))) for x, y in starts], seed)
        goals = [(x, y, float(rng.uniform(-math.pi, math.pi)), 0.0) for x, y in waiting]
        arrived = [False] * len(kinds)
        rows: list[np.ndarray] = []
        t = 0.0
        while True:
            row = np.array([sim.true_state()[:4] for sim in sims])
            row[arrived, 3] = 0.0  # a robot that has arrived stands still
            rows.append(row)
            if all(arrived) or t >= SETTLE_TIMEOUT:
                break
            for _ in range(CONTROLS_PER_TICK):
                for k, (kind, sim) in enumerate(zip(kinds, sims)):
                    if arrived[k]:
                        continue
                    x, y, _, v = sim.true_state()[:4]
                    if math.hypot(goals[k][0] - x, goals[k][1] - y) < 0.1 and abs(v) < 0.15:
                        arrived[k] = True
                        continue
                    sim.control_tick(KINDS[kind].navigate, goals[k])
            t += PERIOD
        # every robot looks around once where it waits (a full turn on the spot, as a robot searching for the
        # ball does), so that the team's belief does not hinge on where its camera happened to point
        look = int(math.ceil(2 * math.pi / LOOK_RATE / PERIOD))
        for tick in range(look + int(round(1.0 / PERIOD))):  # the turn, then a second to come to rest
            rate = LOOK_RATE if tick < look else 0.0
            for _ in range(CONTROLS_PER_TICK):
                for sim in sims:
                    sim.motor_tick(0.0, rate)
            rows.append(np.array([sim.true_state()[:4] for sim in sims]))
        final = rows[-1].copy()
        final[:, 3] = 0.0
        rows += [final] * int(round(WAIT / PERIOD))
        states = np.array(rows)
        log = TeamLog(PERIOD, states, np.tile(ball, (len(states), 1)), tuple(kinds))
        measured, *repeated = (tuple(self.approach_time(kind, tuple(final[k]), ball, _seed(seed, stream, k))
                                     for k, kind in enumerate(kinds)) for stream in range(3, 4 + repeats))
        return StaticSituation(log, measured, tuple(repeated))

    @staticmethod
    def approach_time(kind: str, robot: tuple[float, float, float, float], ball: tuple[float, float],
                      seed: int) -> float | None:
        """Fig. 7.7b: the time robot `kind` takes from `robot` to the ball, alone; None if it fails."""
        from tailor.sims.soccer.simulator import Noise, SoccerSim  # deferred: pymunk loads when the team runs

        k = KINDS[kind]
        sim = SoccerSim(seed, Noise(), k.dynamics)
        sim.place((robot[0], robot[1], robot[2], 0.0), ball if k.approach == "approachBall" else None)
        goal = SoccerTeam.approach_goal(k.approach, np.array([ball]))[0]
        episode = sim.run(ActionCall(k.approach, tuple(float(g) for g in goal)))
        return episode.duration if episode.succeeded else None

    # --- perception and utilities -----------------------------------------------------------------------
    def observe(self, log: TeamLog, perception: Perception, rng: np.random.Generator) -> Observations:
        s, target = log.states, log.target
        T, N = s.shape[:2]
        p = perception
        own_noise = rng.standard_normal((T, N, 4)) * [p.self_noise, p.self_noise, p.self_heading_noise, p.speed_noise]
        other_noise = rng.standard_normal((T, N, N, 4)) * [p.teammate_noise, p.teammate_noise,
                                                            p.teammate_heading_noise, p.speed_noise]
        target_noise = rng.standard_normal((T, N, 2)) * p.target_noise
        own = s + own_noise
        others = s[:, None, :, :] + other_noise
        seen = visible(s[:, :, None, :], s[:, None, :, :2], p.field_of_view) & ~np.eye(N, dtype=bool)
        others[~seen] = np.nan
        ball = target[:, None, :] + target_noise
        ball[~visible(s, target[:, None, :], p.field_of_view)] = np.nan
        for a in (own[..., 2], others[..., 2]):
            a[...] = np.mod(a + np.pi, 2 * np.pi) - np.pi
        return Observations(own, others, ball)

    @staticmethod
    def approach_goal(action: str, target: np.ndarray) -> np.ndarray:
        """(M, 4) goals (xg, yg, phig, vg) of `action` at the ball positions (M, 2)."""
        target = np.asarray(target, dtype=float)
        heading = np.arctan2(OPPONENT_GOAL[1] - target[:, 1], OPPONENT_GOAL[0] - target[:, 0])
        speed = APPROACH_SPEED if action == "approachBall" else 0.0
        return np.column_stack([target, heading, np.full(len(target), speed)])

    def utility_parameters(self, kind: str, states: np.ndarray, target: np.ndarray) -> np.ndarray:
        action = KINDS[kind].approach
        states = np.asarray(states, dtype=float)
        # the model knows the start speeds of its experience (a moving robot is asked as if at that speed)
        speed = np.clip(states[:, 3], *RANGES[action].v_range)
        return np.column_stack([states[:, :3], speed, self.approach_goal(action, target)])

    def distance(self, states: np.ndarray, target: np.ndarray) -> np.ndarray:
        return np.hypot(target[:, 0] - states[:, 0], target[:, 1] - states[:, 1])

    def example(self) -> tuple[np.ndarray, tuple[str, ...], np.ndarray]:
        robots = np.array([[-2.0, 1.2, 0.0, 0.0], [0.3, -1.5, math.pi / 2, 0.0], [1.8, 1.6, -2.5, 0.0]])
        xs = np.arange(-3.5, 3.5 + 1e-9, 0.05)
        return robots, (DEFAULT_KIND,) * 3, np.column_stack([xs, np.zeros_like(xs)])


TEAM = SoccerTeam()
