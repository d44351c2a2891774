"""Synthetic soccer episodes for the learning tests: a robot that turns towards the goal and drives to it.

Durations follow a known formula (turn at TURN_RATE, then drive at SPEED, then turn to the goal heading), so
the learning pipeline can be tested without the simulator; `gather` has the signature of
`sims.experience.gather`. Each episode also reports an energy (J, growing with the distance and the arrival
speed) and an end error (m, growing with the arrival speed), as the simulators' measures (Ch. 8.1). The episodes log the soccer simulator's named state columns (COLUMNS, no ball).
"""

from __future__ import annotations

import math

import numpy as np

from tailor.sims.soccer.pose import norm
from tailor.sims.episode import Episode
from tailor.sims.experience import scenario as find_scenario

COLUMNS = ("x", "y", "phi", "v", "ball_x", "ball_y")  # the soccer simulator's logged state

SPEED = 0.8  # m/s
TURN_RATE = 2.0  # rad/s
LOG_PERIOD = 0.1  # s
NOISE = 0.05  # s, Gaussian noise on the duration


def random_params(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.column_stack([
        rng.uniform(-4, 4, n), rng.uniform(-3, 3, n), rng.uniform(-math.pi, math.pi, n), rng.uniform(0, 1, n),
        rng.uniform(-4, 4, n), rng.uniform(-3, 3, n), rng.uniform(-math.pi, math.pi, n), rng.uniform(0, 1, n),
    ])


def synthetic_duration(params: np.ndarray) -> np.ndarray:
    """Turn to face the goal, drive there, turn to the goal heading."""
    params = np.atleast_2d(params)
    dx, dy = params[:, 4] - params[:, 0], params[:, 5] - params[:, 1]
    bearing = np.arctan2(dy, dx)
    turn_in = np.abs(norm(bearing - params[:, 2]))
    turn_out = np.abs(norm(params[:, 6] - bearing))
    return (turn_in + turn_out) / TURN_RATE + np.hypot(dx, dy) / SPEED


def synthetic_episode(action: str, seed: int, collide_beyond: float | None = None) -> Episode:
    """One episode; with `collide_beyond`, it ends in a collision when |angle_at| exceeds that angle (rad)."""
    rng = np.random.default_rng(seed)
    params = np.concatenate([rng.uniform(-3, 3, 2), rng.uniform(-np.pi, np.pi, 1), rng.uniform(0, 0.5, 1),
                             rng.uniform(-3, 3, 2), rng.uniform(-np.pi, np.pi, 1), rng.uniform(0, 0.5, 1)])
    duration = float(synthetic_duration(params)[0] + rng.normal(0.0, NOISE))
    duration = max(duration, 2 * LOG_PERIOD)
    t = np.arange(0.0, duration, LOG_PERIOD)
    share = (t / duration)[:, None]
    robot = np.empty((len(t), 4))
    robot[:, :2] = params[:2] + share * (params[4:6] - params[:2])
    robot[:, 2] = params[2] + share[:, 0] * norm(params[6] - params[2])
    robot[:, 3] = params[3] + share[:, 0] * (params[7] - params[3])
    state = np.column_stack([robot, np.full((len(t), 2), np.nan)])  # no ball
    outcome = "success"
    if collide_beyond is not None:
        bearing = np.arctan2(params[5] - params[1], params[4] - params[0])
        if abs(norm(params[6] - bearing)) > collide_beyond:
            outcome = "collision"
    measures = {"energy": float(synthetic_energy(params)[0] + abs(rng.normal(0.0, 0.1))),
                "error": float(synthetic_error(params)[0] + abs(rng.normal(0.0, 0.001)))}
    return Episode(action, params, t, state, COLUMNS, outcome, duration, seed, measures)


def synthetic_energy(params: np.ndarray) -> np.ndarray:
    """J: 4 J per metre driven, and 30 J per m/s of the speed arrived at."""
    params = np.atleast_2d(params)
    return 4.0 * np.hypot(params[:, 4] - params[:, 0], params[:, 5] - params[:, 1]) + 30.0 * params[:, 7]


def synthetic_error(params: np.ndarray) -> np.ndarray:
    """m: 1 cm, and 10 cm per m/s of the speed arrived at (a faster arrival overshoots)."""
    return 0.01 + 0.1 * np.atleast_2d(params)[:, 7]


def gather(simulator: str, scenario: str, episodes: int, seed: int, jobs: int = 1,
           progress: bool = True, first: int = 0, into: list[Episode] | None = None) -> list[Episode]:
    """Stand-in for sims.experience.gather: episodes of the scenario's action (looked up in the simulator's
    registry entry), one seed per episode, derived from `seed`."""
    action = find_scenario(simulator, scenario).action
    collide = 2.0 if scenario == "goToPoseAtBall" else None
    out = [] if into is None else into
    out.extend(synthetic_episode(action, seed * 100_003 + i, collide) for i in range(first, first + episodes))
    return out
