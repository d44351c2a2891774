"""The soccer world: field, Pioneer-like robot with a passive ball guide, ball; all constants in SI units.

Coordinates: metres, radians, seconds; x along the field's length, phi counter-clockwise from +x.

Field (RoboCup mid-size, Sec. 1.2.1): the playing area is x in [-FIELD_HALF_LENGTH, FIELD_HALF_LENGTH],
y in [-FIELD_HALF_WIDTH, FIELD_HALF_WIDTH] (8 x 6 m); walls stand WALL_RUNOFF beyond the lines, as the carpet
of a real field extends past them. Walls reflect the ball; the robot is a kinematic body that walls do not
stop (experience ranges keep it on the field with a margin; a position clamp keeps it inside the walls).

Robot (Pioneer I with its passive guide rail, App. B.1): differential drive, motor commands [v, phidot]
(Sec. 2.1) limited to |v| <= V_MAX, |phidot| <= W_MAX and changed no faster than A_MAX, ALPHA_MAX. Its
reference point, the pose (x, y) in every soccer action, parameter and log, is the *ball point*: the centre
of the V-shaped guide on its front, where a dribbled ball sits, BALL_POINT_OFFSET ahead of the wheel axle
(the centre of rotation). A V lets a ball pushed sideways slide forward along an arm and out: a turn too
sharp for the rolling friction that presses the ball into the V loses it, and so does braking harder than
the ball decelerates by itself (ROLL_DECELERATION).

Energy (the "energy" measure of an action, sims.episode): the robot is given a mass ROBOT_MASS and a moment of
inertia ROBOT_MOMENT about its axle; the physics never reads them (the body is kinematic).

Ball: a RoboCup ball (BALL_RADIUS) that slides without spin (infinite moment) and loses speed at the
constant rolling-friction deceleration mu_r * g, so it stops after v0^2 / (2 mu_r g).

What may differ from the world the actions were learned in (Ch. 8.1; the simulator declares them, SIMULATOR):
the disturbance "nudge" (an opponent pushes the ball once, NUDGE_WINDOW after the start, so that it rolls
NUDGE_ROLL) and the robot variants of VARIANTS ("weak_motors": accelerations times WEAK_MOTOR_FACTOR).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

from tailor.errors import SimError

# --- field (m) -------------------------------------------------------------------------------------------
FIELD_HALF_LENGTH = 4.0  # m, playing area x in [-4, 4]
FIELD_HALF_WIDTH = 3.0  # m, playing area y in [-3, 3]
WALL_RUNOFF = 1.0  # m, walls stand this far outside the lines
WALL_ELASTICITY = 0.5  # ball bounce off the walls

# --- timing (the simulator's rates; here so that the team scene reads them without loading the physics) --
PHYSICS_HZ = 100  # Hz, fixed physics step
CONTROL_HZ = 20  # Hz, controller rate (must divide PHYSICS_HZ)
LOG_HZ = 10  # Hz, logging rate (must divide CONTROL_HZ)

# --- robot (Pioneer-like differential drive) ------------------------------------------------------------
V_MAX = 1.0  # m/s, translational velocity limit (forward and backward)
W_MAX = 3.0  # rad/s, rotational velocity limit
A_MAX = 1.0  # m/s^2, translational acceleration limit (speeding up and braking)
ALPHA_MAX = 6.0  # rad/s^2, rotational acceleration limit


@dataclass(frozen=True)
class Dynamics:
    """The motor limits of a robot kind: |v| <= v_max (m/s), |phidot| <= w_max (rad/s), changed no faster
    than a_max (m/s^2) and alpha_max (rad/s^2)."""

    v_max: float
    w_max: float
    a_max: float
    alpha_max: float


PIONEER = Dynamics(V_MAX, W_MAX, A_MAX, ALPHA_MAX)  # the robot every soccer action was designed for
# Another kind (Sec. 7.3, App. A.2): slower and less agile; its only navigation action is goToPosition.
SPARROW = Dynamics(v_max=0.6, w_max=2.0, a_max=0.5, alpha_max=3.0)

ROBOT_HALF_LENGTH = 0.2  # m, body: 0.4 x 0.4 m square centred on the wheel axle
ROBOT_HALF_WIDTH = 0.2  # m
# The robot's inertia, for the energy measure only (its body is kinematic: the physics never reads them). Both
# kinds of robot (PIONEER, SPARROW) and the variants have it: a Pioneer-class base with its guide.
ROBOT_MASS = 9.0  # kg
# kg m^2, about the wheel axle (its centre of mass): a uniform 0.4 x 0.4 m square, m (l^2 + w^2) / 12 (0.24)
ROBOT_MOMENT = ROBOT_MASS * ((2 * ROBOT_HALF_LENGTH) ** 2 + (2 * ROBOT_HALF_WIDTH) ** 2) / 12.0

# --- ball ------------------------------------------------------------------------------------------------
BALL_RADIUS = 0.11  # m, FIFA size-5 ball used in the mid-size league
BALL_MASS = 0.45  # kg
GRAVITY = 9.81  # m/s^2
MU_ROLL = 0.05  # rolling-friction coefficient of a ball on carpet (dimensionless)
ROLL_DECELERATION = MU_ROLL * GRAVITY  # m/s^2, constant deceleration of a free rolling ball (0.49)

# --- ball guide (a V of two arms on the robot's front) --------------------------------------------------
GUIDE_HALF_ANGLE = math.radians(15.0)  # rad, angle between the driving direction and each arm
GUIDE_CLEARANCE = 0.005  # m, gap between a seated ball and the front plate / arms
GUIDE_ARM_LENGTH = 0.12  # m, length of each arm from the front plate's corner outward
BALL_POINT_OFFSET = ROBOT_HALF_LENGTH + BALL_RADIUS + GUIDE_CLEARANCE  # m, axle -> ball point (0.315)


def guide_arms() -> list[tuple[tuple[float, float], tuple[float, float]]]:
    """The two arm segments in the robot frame (axle at the origin, +x forward), tangent to a seated ball.

    An arm leaves the front plate where it is tangent (with clearance) to a ball centred on the ball point
    and opens outward at GUIDE_HALF_ANGLE from the driving direction.
    """
    arms = []
    r = BALL_RADIUS + GUIDE_CLEARANCE
    for side in (1.0, -1.0):
        # the arm line is at distance r from the ball point, its direction (cos a, side * sin a)
        a = GUIDE_HALF_ANGLE
        nx, ny = -math.sin(a), side * math.cos(a)  # outward normal of the arm line, pointing sideways
        # points p on the line satisfy (p - ball_point) . n = r; start where the line meets the front plate
        px0 = ROBOT_HALF_LENGTH
        py0 = (r - (px0 - BALL_POINT_OFFSET) * nx) / ny
        dx, dy = math.cos(a), side * math.sin(a)
        arms.append(((px0, py0), (px0 + GUIDE_ARM_LENGTH * dx, py0 + GUIDE_ARM_LENGTH * dy)))
    return arms


def wrap(angle: float) -> float:
    """The angle normalized to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


# --- changed robots (variants, Ch. 8.1): the learned models know only PIONEER ----------------------------
WEAK_MOTOR_FACTOR = 0.75  # the weak motors' share of the accelerations (25% weaker)


WEAK_TOP_SPEED = 0.8  # the weak motors' share of the top speeds, v_max and w_max (0.8 m/s: every way-point and
# ball speed the soccer binding allows, up to 0.6 m/s, stays reachable)


def weak_motors(dynamics: Dynamics) -> Dynamics:
    """The robot with motors 25% weaker: a_max and alpha_max WEAK_MOTOR_FACTOR as large, the top speeds v_max and
    w_max WEAK_TOP_SPEED as large (a start faster than the weak robot drives is taken at its top speed)."""
    return replace(dynamics, a_max=WEAK_MOTOR_FACTOR * dynamics.a_max,
                   alpha_max=WEAK_MOTOR_FACTOR * dynamics.alpha_max, v_max=WEAK_TOP_SPEED * dynamics.v_max,
                   w_max=WEAK_TOP_SPEED * dynamics.w_max)


WEAK_PIONEER = weak_motors(PIONEER)  # the soccer robot of variant "weak_motors"
VARIANTS: dict[str, Callable[[Dynamics], Dynamics]] = {"weak_motors": weak_motors}


def variant_dynamics(variant: str | None, dynamics: Dynamics = PIONEER) -> Dynamics:
    """The motor limits of robot `dynamics` changed as `variant` (None: unchanged) says; a SimError names the
    known variants."""
    if variant is None:
        return dynamics
    if variant not in VARIANTS:
        raise SimError(f"the soccer robot has no variant {variant!r} (known: {', '.join(VARIANTS)})")
    return VARIANTS[variant](dynamics)


# --- disturbances (Ch. 8.1): seeded events of the world that refinement does not know in advance ----------
NUDGE = "nudge"  # an opponent pushes the ball once (sims.soccer.simulator.Nudge)
DISTURBANCES = (NUDGE,)
# s, the push comes at a uniform time in this window of the simulator's clock (physics steps since the
# simulator was made; a reset does not rewind it): inside the approach of a `score` situation (refined, it took
# 2.2-9.2 s in 100 random ones, so the push came during it in all of them)
NUDGE_WINDOW = (0.5, 3.0)
NUDGE_ROLL = (0.3, 0.8)  # m, a ball at rest rolls a uniform distance in this range before friction stops it
# rad, a ball in the guide is knocked out ahead, within this angle of the robot's heading: pushed anywhere
# ahead (within 90 degrees), a sixth of 200 dribbles kept the ball, all pushed 60 degrees or more off the
# heading (it slid along an arm back into the V); within 45 degrees 1 of 200 kept it
NUDGE_KNOCK_CONE = math.radians(45.0)
NUDGE_STREAM = 2  # second seed word of the push's own random draws (the noise stream stays that of the seed)
