"""What can change the arm's world and the arm itself (Ch. 8.1): a bump, and a payload in the gripper.

Disturbance "bump": someone bumps the arm once. The moment is drawn uniformly from BUMP_WINDOW, in seconds of
reaching (the control ticks of every reach of the simulator added up, whichever reach runs then; a run that
reaches for less never sees it), and strikes at the first control tick at or after it: each joint's velocity
jumps by a kick of magnitude uniform in BUMP_KICK with a random sign (a hand knocking the arm: the tip moves
at up to a few m/s for an instant). The torque-limited motors take the kick out within a few physics steps,
the arm pushed 0.05-0.25 rad off its ramp; the reach's PID and replanning bring it back (most reaches take
a few hundredths of a second longer, a few much longer), or it leaves a joint limit ("joint_limit"). Every
draw comes from the generator (seed, DISTURBANCE_STREAM), never from the motor and sensor noise, so a run with
the bump is the run without it up to the moment it strikes.

Variant "payload": a payload in the gripper, for which the ramps' acceleration is PAYLOAD_FACTOR of
world.ALPHA_MAX; the speed limit OMEGA_MAX stays, so every goal velocity the binding allows stays valid.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tailor.sims.arm import world as W

DISTURBANCE_STREAM = 2  # second seed word of the disturbances' generator (1 is the scenarios' sampling)
BUMP_WINDOW = (0.2, 2.0)  # s of reaching in which the bump strikes
BUMP_KICK = (2.0, 4.0)  # rad/s, magnitude of each joint's velocity kick
PAYLOAD_FACTOR = 0.7  # the payload's share of the ramps' acceleration limit

DISTURBANCES = {
    "bump": (f"once, {BUMP_WINDOW[0]:g}-{BUMP_WINDOW[1]:g} s into reaching, the arm is bumped: each joint's "
             f"velocity jumps by {BUMP_KICK[0]:g}-{BUMP_KICK[1]:g} rad/s, either way"),
}
VARIANTS = {
    "payload": (f"a payload in the gripper: the ramps' joint acceleration is x{PAYLOAD_FACTOR:g} "
                f"({PAYLOAD_FACTOR * W.ALPHA_MAX:g} rad/s^2), the speed limit stays {W.OMEGA_MAX:g} rad/s"),
}


@dataclass(frozen=True)
class Bump:
    """What the "bump" disturbance did: the kick (rad/s, shoulder and elbow), when it struck (the simulator's
    clock, s into the running reach, s of reaching in all) and the moment drawn from `window` (s of
    reaching)."""

    kick: tuple[float, float]
    time: float
    elapsed: float
    reaching: float
    moment: float
    window: tuple[float, float]


def bump_kick(rng: np.random.Generator) -> tuple[float, tuple[float, float]]:
    """The bump's moment (s of reaching) and its kick (rad/s per joint)."""
    moment = float(rng.uniform(*BUMP_WINDOW))
    size = rng.uniform(*BUMP_KICK, 2)
    sign = np.where(rng.random(2) < 0.5, -1.0, 1.0)
    return moment, (float(sign[0] * size[0]), float(sign[1] * size[1]))
