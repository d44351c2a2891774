"""goToPosition (App. A.2): drive to a position, with no goal heading; the action of the other robot kind.

The dissertation's mixed team used another lab's robot whose navigation action takes no target orientation
and whose implementation was unknown (only its parameters were): a model is learned from its behaviour like
any other. Here it is a plain turn-and-go controller sized for the SPARROW dynamics (world.SPARROW): turn
toward the goal on the spot while it lies far off the heading, otherwise drive on a braking profile and steer
proportionally to the bearing error. A pure function of (x, y, phi, v, xg, yg, phig, vg); phig is ignored.
"""

from __future__ import annotations

import math

from tailor.sims.soccer.control import clip, profile_speed
from tailor.sims.soccer.world import SPARROW, wrap

K_BEARING = 3.0  # 1/s, rotational command per radian of bearing error (until SPARROW.w_max)
TURN_IN_PLACE = math.radians(60.0)  # rad, a goal further off the heading is turned to on the spot
DECEL_PLAN = 0.5 * SPARROW.a_max  # m/s^2, the braking profile's deceleration
V_CREEP = 0.05  # m/s, speed kept while turning on the spot (the goal still ahead of the axle)
STEER_RADIUS = 0.05  # m, nearer the goal the bearing is noise: no more steering there


def goToPosition(x: float, y: float, phi: float, v: float, xg: float, yg: float, phig: float, vg: float
                 ) -> tuple[float, float]:
    """Drive the ball point to (xg, yg), arriving with speed vg, whatever the heading; returns [v, phidot]."""
    dx, dy = xg - x, yg - y
    dist = math.hypot(dx, dy)
    bearing_error = wrap(math.atan2(dy, dx) - phi)
    v_profile = profile_speed(dist, vg, SPARROW.v_max, DECEL_PLAN)
    if abs(bearing_error) > TURN_IN_PLACE and dist > 2.0 * STEER_RADIUS:
        v_target = V_CREEP
    else:
        v_target = v_profile * max(0.0, math.cos(bearing_error))
    w = clip(K_BEARING * bearing_error, SPARROW.w_max) if dist > STEER_RADIUS else 0.0
    return v_target, w
