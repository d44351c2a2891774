"""The soccer actions (Sec. 2.2, App. A.1): pure functions from the belief state and the subgoal to [v, phidot].

Every action has the signature `(x, y, phi, v, xg, yg, phig, vg) -> (v_cmd, phidot_cmd)`: the robot's
dynamic pose (its ball point, heading, signed speed) as believed, and the goal pose. They keep no state, so
the simulator (or a real robot) may call them at any rate.

- goToPose (here): an intermediate point (IP) LURE_GAIN * dist behind the goal pose (at most LURE_MAX) is
  approached; as the robot closes in, the IP moves into the goal, luring the robot in with the goal heading.
  The speed follows a braking profile that arrives with vg. While the robot faces away from the goal heading
  the IP stays at least LURE_MIN behind the goal: an IP next to the robot would be circled for ever.
- approachBall (sims.soccer.approach): a Dubins path round the ball to a pre-pose behind it, then straight in.
- dribbleBall (sims.soccer.dribble): a Dubins path with a wide turning radius and slow arcs, ball in the guide.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from sims.soccer.approach import approachBall
from sims.soccer.control import ARRIVE_SLACK, axle_pose, clip, profile_speed
from sims.soccer.dribble import dribbleBall
from sims.soccer.world import A_MAX, BALL_POINT_OFFSET, V_MAX, W_MAX, wrap

Command = tuple[float, float]
Action = Callable[[float, float, float, float, float, float, float, float], Command]

LURE_GAIN = 0.5  # IP distance behind the goal per metre of distance to the goal
LURE_MAX = 1.0  # m, the IP is never further behind the goal
LURE_MIN = 0.6  # m, least IP distance while the robot faces more than LURE_TURN_ANGLE away from phig
LURE_TURN_ANGLE = math.pi / 2  # rad
K_HEADING = 3.0  # 1/s, rotational velocity command per radian of heading error
A_PLAN = 0.8 * A_MAX  # m/s^2, deceleration the speed profile plans with (below the limit, so it is followed)
ALIGN_RADIUS = ARRIVE_SLACK  # m, within this distance the robot steers to the goal heading, not to the IP
TURN_MARGIN = 0.5  # share of W_MAX the speed limit for turning toward a target plans with
V_CREEP = 0.1  # m/s, minimum forward speed while turning, so that the robot turns in arcs, not on the spot


def _lure(x: float, y: float, phi: float, xg: float, yg: float, phig: float) -> tuple[float, float, float]:
    """Heading error toward the intermediate point behind the goal pose, the distance from the axle to
    that point, and the distance from the ball point to the goal."""
    dist = math.hypot(xg - x, yg - y)
    if dist < ALIGN_RADIUS:
        return wrap(phig - phi), BALL_POINT_OFFSET, dist
    lure = min(LURE_MAX, LURE_GAIN * dist)
    if abs(wrap(phig - phi)) > LURE_TURN_ANGLE:
        lure = max(lure, LURE_MIN)
    error, target_dist = _aim(x, y, phi, xg - lure * math.cos(phig), yg - lure * math.sin(phig))
    return error, target_dist, dist


def _aim(x: float, y: float, phi: float, tx: float, ty: float) -> tuple[float, float]:
    """Heading error toward a target as seen from the wheel axle, the centre of rotation, and its distance.

    Aiming from the axle (not the ball point ahead of it) keeps every target reachable by turning: a target
    inside the circle the ball point sweeps when turning on the spot could never be faced from the ball point.
    """
    ax, ay, _ = axle_pose(x, y, phi)
    return wrap(math.atan2(ty - ay, tx - ax) - phi), math.hypot(tx - ax, ty - ay)


def _drive(heading_error: float, speed: float, target_dist: float) -> Command:
    """Turn toward the target; slow down with the heading error (down to a creep) and so far that the arc
    through the target (curvature 2 sin(error) / distance, pure pursuit) can be turned at TURN_MARGIN W_MAX.
    """
    v_cmd = speed * math.cos(heading_error)
    sin_e = abs(math.sin(heading_error))
    if sin_e > 1e-6:
        v_cmd = min(v_cmd, TURN_MARGIN * W_MAX * target_dist / (2.0 * sin_e))
    return max(v_cmd, min(speed, V_CREEP)), clip(K_HEADING * heading_error, W_MAX)


def goToPose(x: float, y: float, phi: float, v: float, xg: float, yg: float, phig: float, vg: float) -> Command:
    """Navigate to the goal pose via the intermediate point behind it (App. A.1)."""
    error, target_dist, dist = _lure(x, y, phi, xg, yg, phig)
    return _drive(error, profile_speed(dist, vg, V_MAX, A_PLAN), target_dist)


ACTION_FUNCTIONS: dict[str, Action] = {
    "goToPose": goToPose, "approachBall": approachBall, "dribbleBall": dribbleBall,
}
