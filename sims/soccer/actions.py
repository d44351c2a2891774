"""The soccer actions (Sec. 2.2, App. A.1): pure functions from the belief state and the subgoal to [v, phidot].

Every action has the signature `(x, y, phi, v, xg, yg, phig, vg) -> (v_cmd, phidot_cmd)`: the robot's
dynamic pose (its ball point, heading, signed speed) as believed, and the goal pose. They keep no state, so
the simulator (or a real robot) may call them at any rate.

- goToPose: an intermediate point (IP) LURE_GAIN * dist behind the goal pose (at most LURE_MAX) is
  approached; as the robot closes in, the IP moves into the goal, luring the robot in with the goal heading.
  The speed follows a braking profile that arrives with vg.
- approachBall: goToPose to a pose at the ball (the ball lies at the goal), aware of the ball: unless the
  robot's axle is in a cone behind the ball, it first drives beside the ball, then to a point behind it.
- dribbleBall: goToPose limited so the ball stays in the guide: lateral acceleration, rotational speed and
  braking are bounded, so turns with the ball are slow.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from sims.soccer.dribble import dribbleBall
from sims.soccer.world import A_MAX, BALL_POINT_OFFSET, V_MAX, W_MAX, wrap

Command = tuple[float, float]
Action = Callable[[float, float, float, float, float, float, float, float], Command]

# --- goToPose --------------------------------------------------------------------------------------------
LURE_GAIN = 0.5  # IP distance behind the goal per metre of distance to the goal
LURE_MAX = 1.0  # m, the IP is never further behind the goal
K_HEADING = 3.0  # 1/s, rotational velocity command per radian of heading error
A_PLAN = 0.8 * A_MAX  # m/s^2, deceleration the speed profile plans with (below the limit, so it is followed)
ARRIVE_SLACK = 0.05  # m, the profile reaches vg this far before the goal (half the position tolerance)
ALIGN_RADIUS = 0.05  # m, within this distance the robot steers to the goal heading, not to the IP
TURN_MARGIN = 0.5  # share of W_MAX the speed limit for turning toward a target plans with
V_CREEP = 0.1  # m/s, minimum forward speed while turning, so that the robot turns in arcs, not on the spot

# --- approachBall ----------------------------------------------------------------------------------------
APPROACH_LURE_GAIN = 0.7  # a longer lure: the robot comes in straighter, so the ball enters the guide
CONE_APEX = 0.25  # m, apex of the cone behind the ball (axle positions from which the lure is safe)
SIDESTEP_LATERAL = 0.5  # m, an axle closer than this beside the ball (outside the cone) first steps aside
SIDESTEP_TARGET = (0.3, 0.9)  # m, (forward of the axle, lateral of the ball): where a sidestep heads
DETOUR_POINT = (-1.1, 0.7)  # m, (behind, beside) the ball: the point driven to along the ball's side

def _clip(value: float, bound: float) -> float:
    return -bound if value < -bound else bound if value > bound else value


def _lure(x: float, y: float, phi: float, xg: float, yg: float, phig: float,
          gain: float) -> tuple[float, float, float]:
    """Heading error toward the intermediate point behind the goal pose, the distance from the axle to
    that point, and the distance from the ball point to the goal."""
    dist = math.hypot(xg - x, yg - y)
    if dist < ALIGN_RADIUS:
        return wrap(phig - phi), BALL_POINT_OFFSET, dist
    lure = min(LURE_MAX, gain * dist)
    error, target_dist = _aim(x, y, phi, xg - lure * math.cos(phig), yg - lure * math.sin(phig))
    return error, target_dist, dist


def _aim(x: float, y: float, phi: float, tx: float, ty: float) -> tuple[float, float]:
    """Heading error toward a target as seen from the wheel axle, the centre of rotation, and its distance.

    Aiming from the axle (not the ball point ahead of it) keeps every target reachable by turning: a target
    inside the circle the ball point sweeps when turning on the spot could never be faced from the ball point.
    """
    ax, ay = x - BALL_POINT_OFFSET * math.cos(phi), y - BALL_POINT_OFFSET * math.sin(phi)
    return wrap(math.atan2(ty - ay, tx - ax) - phi), math.hypot(tx - ax, ty - ay)


def _profile_speed(dist: float, vg: float, v_top: float, decel: float) -> float:
    """Speed from which braking at `decel` arrives with vg ARRIVE_SLACK before the goal."""
    return min(v_top, math.sqrt(vg * vg + 2.0 * decel * max(0.0, dist - ARRIVE_SLACK)))


def _drive(heading_error: float, speed: float, target_dist: float) -> Command:
    """Turn toward the target; slow down with the heading error (down to a creep) and so far that the
    arc through the target (curvature 2 sin(error) / distance, pure pursuit) can be turned at TURN_MARGIN W_MAX.
    """
    v_cmd = speed * math.cos(heading_error)
    sin_e = abs(math.sin(heading_error))
    if sin_e > 1e-6:
        v_cmd = min(v_cmd, TURN_MARGIN * W_MAX * target_dist / (2.0 * sin_e))
    return max(v_cmd, min(speed, V_CREEP)), _clip(K_HEADING * heading_error, W_MAX)


def goToPose(x: float, y: float, phi: float, v: float, xg: float, yg: float, phig: float, vg: float) -> Command:
    """Navigate to the goal pose via the intermediate point behind it (App. A.1)."""
    error, target_dist, dist = _lure(x, y, phi, xg, yg, phig, LURE_GAIN)
    return _drive(error, _profile_speed(dist, vg, V_MAX, A_PLAN), target_dist)


def approachBall(x: float, y: float, phi: float, v: float, xg: float, yg: float, phig: float, vg: float) -> Command:
    """goToPose to the ball at (xg, yg), detouring around it unless the robot is already behind it."""
    c, s = math.cos(phig), math.sin(phig)
    ax, ay = x - BALL_POINT_OFFSET * math.cos(phi), y - BALL_POINT_OFFSET * math.sin(phi)  # wheel axle
    rx, ry = ax - xg, ay - yg
    along, lateral = rx * c + ry * s, -rx * s + ry * c  # axle in the goal frame (along < 0: behind)
    if along < -CONE_APEX - abs(lateral):
        error, target_dist, dist = _lure(x, y, phi, xg, yg, phig, APPROACH_LURE_GAIN)
        return _drive(error, _profile_speed(dist, vg, V_MAX, A_PLAN), target_dist)
    side = 1.0 if lateral >= 0.0 else -1.0
    if abs(lateral) < SIDESTEP_LATERAL:
        ta, tl = along + SIDESTEP_TARGET[0], side * SIDESTEP_TARGET[1]
    else:
        ta, tl = DETOUR_POINT[0], side * DETOUR_POINT[1]
    tx, ty = xg + ta * c - tl * s, yg + ta * s + tl * c
    error, target_dist = _aim(x, y, phi, tx, ty)
    dist = math.hypot(tx - x, ty - y) + math.hypot(tx - xg, ty - yg)  # the way still to go, via the target
    return _drive(error, _profile_speed(dist, vg, V_MAX, A_PLAN), target_dist)


ACTION_FUNCTIONS: dict[str, Action] = {"goToPose": goToPose, "approachBall": approachBall, "dribbleBall": dribbleBall}
