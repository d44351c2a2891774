"""The arm's experience scenario (Sec. 4.1) and the random situations of its problems (Sec. 5.5).

Scenario "reach": the start and goal joint angles are uniform within the joint limits shrunk by
ANGLE_MARGIN, the start and goal joint velocities uniform in [-OMEGA_MAX, OMEGA_MAX]; one reach in a fresh
ArmSim. A start moving toward a near limit, or a goal near a limit approached from the far side, can overshoot
it: those episodes end with "joint_limit" (a few percent), the rest with "success" after 2.9 s on average.
Scenario "stroke": one leg of a random stroke (letters.random_stroke: way-points 0.1-0.4 m apart in the
letters' workspace), start and goal joint velocities uniform in [-OMEGA_MAX, OMEGA_MAX]: the short reaches a
letter is made of, at every way-point velocity refinement may choose.
The situations are random strokes of 4-6 way-points (letters.random_stroke), problems stroke-4/5/6.
Both scenarios' runs and subgoal_episode take `variant` (None, or one of the arm's VARIANTS): the same episode
on the changed arm, for experience of it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from tailor.sims.arm import world as W
from tailor.sims.arm.letters import STROKE_LENGTHS, belief_objects, random_stroke
from tailor.sims.episode import ActionCall, Episode

if TYPE_CHECKING:
    from tailor.sims.arm.simulator import Noise

ANGLE_MARGIN = 0.05  # rad, start and goal angles keep this distance to the joint limits
SAMPLING_STREAM = 1  # second seed word: the scenario's draws are independent of the simulator's noise


def sample_reach(rng: np.random.Generator) -> tuple[tuple[float, float, float, float], ActionCall]:
    """Draw a start state (theta_a, omega_a, theta_b, omega_b) and the reach call to a random goal state."""
    (lo_a, hi_a), (lo_b, hi_b) = W.THETA_A_LIMITS, W.THETA_B_LIMITS
    m, w = ANGLE_MARGIN, W.OMEGA_MAX
    theta_a = rng.uniform(lo_a + m, hi_a - m, 2)
    theta_b = rng.uniform(lo_b + m, hi_b - m, 2)
    omega = rng.uniform(-w, w, 4)
    start = (float(theta_a[0]), float(omega[0]), float(theta_b[0]), float(omega[1]))
    goal = (float(theta_a[1]), float(omega[2]), float(theta_b[1]), float(omega[3]))
    return start, ActionCall("reach", goal)


def sample_stroke_leg(rng: np.random.Generator) -> tuple[tuple[float, float, float, float], ActionCall]:
    """Draw one leg of a random stroke, with random joint velocities at both ends."""
    (a0, b0), (a1, b1) = (W.inverse(*p) for p in random_stroke(rng, 2))
    omega = rng.uniform(-W.OMEGA_MAX, W.OMEGA_MAX, 4)
    return (a0, float(omega[0]), b0, float(omega[1])), ActionCall("reach", (a1, float(omega[2]), b1, float(omega[3])))


def _episode(seed: int, start: tuple[float, float, float, float], call: ActionCall,
             noise: Noise | None = None, variant: str | None = None) -> Episode:
    """One reach from `start` in a fresh ArmSim."""
    from tailor.sims.arm.simulator import ArmSim, Noise  # deferred: pymunk loads when an episode runs

    sim = ArmSim(seed, Noise() if noise is None else noise, variant=variant)
    sim.place(*start)
    return sim.run(call)


def run_stroke_leg(seed: int, noise: Noise | None = None, *, variant: str | None = None) -> Episode:
    """One random stroke leg (see the module doc)."""
    start, call = sample_stroke_leg(np.random.default_rng((seed, SAMPLING_STREAM)))
    return _episode(seed, start, call, noise, variant)


def run_reach(seed: int, noise: Noise | None = None, *, variant: str | None = None) -> Episode:
    """One random reach: start and goal within the joint limits, any joint velocities (see the module doc)."""
    start, call = sample_reach(np.random.default_rng((seed, SAMPLING_STREAM)))
    return _episode(seed, start, call, noise, variant)


def subgoal_episode(action: str, params: np.ndarray, seed: int, variant: str | None = None) -> Episode:
    """An episode of `action` from a refined subgoal: `params` are one reach's start and goal states."""
    p = [float(v) for v in params]
    return _episode(seed, (p[0], p[1], p[2], p[3]), ActionCall(action, tuple(p[4:8])), variant=variant)


def letters(rng: np.random.Generator) -> tuple[str, dict[str, dict[str, float]]]:
    """A random letter: problem stroke-N (N way-points, 4 to 6) with the belief values of p1..pN."""
    n = int(rng.choice(STROKE_LENGTHS))
    return f"stroke-{n}", belief_objects("p", random_stroke(rng, n))


SITUATIONS = {"letters": letters}
