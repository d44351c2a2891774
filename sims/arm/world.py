"""The arm world: a PowerCube-like planar 2-DOF arm (App. A.4, Fig. 5.13(b)); all constants in SI units.

Two revolute joints of the arm move in the drawing plane: the shoulder a (at the base, the origin) and the
elbow b. theta_a is link A's angle from +x, theta_b the angle of link B relative to link A (counter-clockwise
positive), so the tip is at FK below. The plane is horizontal (gravity acts along the joint axes and is
carried by the bearings), so no gravity acts in the simulation.

Limits: each joint's angle stays within its (soft) limits: a joint leaving them stops the action
("joint_limit"). The reach controller plans its ramp profiles within OMEGA_MAX and ALPHA_MAX (the PowerCube
firmware's ramp speed and acceleration); the motors saturate at OMEGA_HARD, which leaves the PID headroom
to correct tracking errors while the profile cruises at OMEGA_MAX. With these limits a random reach of the
experience scenario takes about 2.9 s on average, like Table 4.3's PowerCube reach row.

Inverse kinematics uses one fixed elbow configuration, ELBOW_SIGN = +1: theta_b >= 0 ("elbow down": for a
tip on the +x axis the elbow lies below it), so every Cartesian point maps to one joint configuration.
"""

from __future__ import annotations

import math

from tailor.errors import SimError

# --- links (PowerCube modules and aluminium tubes) --------------------------------------------------------
LINK_A_LENGTH = 0.45  # m, shoulder axis to elbow axis
LINK_B_LENGTH = 0.40  # m, elbow axis to the pen tip
LINK_A_MASS = 3.0  # kg, upper arm with the elbow module
LINK_B_MASS = 1.5  # kg, forearm with the pen holder
REACH = LINK_A_LENGTH + LINK_B_LENGTH  # m, the largest tip distance from the shoulder (0.85)

# --- joints --------------------------------------------------------------------------------------------
THETA_A_LIMITS = (-2.3, 2.3)  # rad, shoulder angle range (soft limits)
THETA_B_LIMITS = (-2.6, 2.6)  # rad, elbow angle range (soft limits; the links would collide beyond)
OMEGA_MAX = 1.0  # rad/s, joint speed limit of the ramp profiles (and of goal velocities)
ALPHA_MAX = 2.0  # rad/s^2, joint acceleration limit of the ramp profiles
OMEGA_HARD = 1.5  # rad/s, motor saturation: executed joint speeds never exceed it
TORQUE_A_MAX = 40.0  # N m, shoulder motor torque limit
TORQUE_B_MAX = 20.0  # N m, elbow motor torque limit

ELBOW_SIGN = 1  # inverse kinematics returns theta_b with this sign (elbow down)


def forward(theta_a: float, theta_b: float) -> tuple[float, float]:
    """The tip (x, y) in m of joint angles (theta_a, theta_b) in rad."""
    ab = theta_a + theta_b
    return (LINK_A_LENGTH * math.cos(theta_a) + LINK_B_LENGTH * math.cos(ab),
            LINK_A_LENGTH * math.sin(theta_a) + LINK_B_LENGTH * math.sin(ab))


def elbow(theta_a: float) -> tuple[float, float]:
    """The elbow axis (x, y) in m for shoulder angle theta_a."""
    return LINK_A_LENGTH * math.cos(theta_a), LINK_A_LENGTH * math.sin(theta_a)


def inverse(x: float, y: float) -> tuple[float, float]:
    """Joint angles (theta_a, theta_b) putting the tip at (x, y), elbow configuration ELBOW_SIGN.

    A point out of the annulus the links can reach is a SimError."""
    r2 = x * x + y * y
    c = (r2 - LINK_A_LENGTH ** 2 - LINK_B_LENGTH ** 2) / (2.0 * LINK_A_LENGTH * LINK_B_LENGTH)
    if not math.isfinite(c) or abs(c) > 1.0:
        raise SimError(f"the arm cannot reach ({x:.3f}, {y:.3f}): its tip stays between "
                       f"{abs(LINK_A_LENGTH - LINK_B_LENGTH):.2f} and {REACH:.2f} m from the shoulder")
    theta_b = ELBOW_SIGN * math.acos(c)
    theta_a = math.atan2(y, x) - math.atan2(LINK_B_LENGTH * math.sin(theta_b),
                                            LINK_A_LENGTH + LINK_B_LENGTH * math.cos(theta_b))
    theta_a = (theta_a + math.pi) % (2.0 * math.pi) - math.pi
    return theta_a, theta_b


def within_limits(theta_a: float, theta_b: float, margin: float = 0.0) -> bool:
    """Whether both joint angles lie within their limits, shrunk by `margin` rad on each side."""
    return (THETA_A_LIMITS[0] + margin <= theta_a <= THETA_A_LIMITS[1] - margin
            and THETA_B_LIMITS[0] + margin <= theta_b <= THETA_B_LIMITS[1] - margin)
