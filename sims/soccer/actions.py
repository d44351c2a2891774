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

from sims.soccer.world import A_MAX, BALL_POINT_OFFSET, ROLL_DECELERATION, V_MAX, W_MAX, wrap

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

# --- dribbleBall -----------------------------------------------------------------------------------------
V_DRIBBLE = 0.8  # m/s, top speed with the ball
A_DRIBBLE_BRAKE = 0.3  # m/s^2, braking bound: below the ball's own rolling deceleration (0.49)
A_LAT_DRIBBLE = 0.35  # m/s^2, bound on |phidot| * (|v| + LAT_SPEED_MARGIN): what the guide holds safely
LAT_SPEED_MARGIN = 0.5  # m/s, keeps the bound finite at low speed
R_DRIBBLE = 0.3  # m, tightest turn (radius of the axle's path) with the ball
DRIBBLE_CONTROL_PERIOD = 0.05  # s, the period the braking bound is spread over (the simulator's)


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


def dribbleBall(x: float, y: float, phi: float, v: float, xg: float, yg: float, phig: float, vg: float) -> Command:
    """goToPose with the ball in the guide: bounded lateral acceleration and braking, turns in arcs only.

    The rotational speed is bounded by |phidot| (v + LAT_SPEED_MARGIN) <= A_LAT_DRIBBLE (less while braking,
    which presses the ball into the guide less) and by v / R_DRIBBLE: only a rolling ball is pressed into the
    guide (by its rolling friction), so the robot never turns on the spot with it. The speed is reduced so the
    arc through the intermediate point needs no more than the bound: v (v + M) <= TURN_MARGIN A d / (2 sin e).
    An intermediate point inside the circle of the tightest turn is not reached by turning toward it: the
    robot then loops round the other way.
    """
    error, target_dist, dist = _lure(x, y, phi, xg, yg, phig, LURE_GAIN)
    v_cmd = _profile_speed(dist, vg, V_DRIBBLE, A_DRIBBLE_BRAKE) * max(0.0, math.cos(error))
    sin_e = abs(math.sin(error))
    if sin_e > 1e-6:
        q = TURN_MARGIN * A_LAT_DRIBBLE * target_dist / (2.0 * sin_e)
        v_cmd = min(v_cmd, 0.5 * (math.sqrt(LAT_SPEED_MARGIN ** 2 + 4.0 * q) - LAT_SPEED_MARGIN))
    w_cmd = _clip(K_HEADING * error, A_LAT_DRIBBLE / (v_cmd + LAT_SPEED_MARGIN))
    # only a rolling ball is pressed into the guide (by its rolling friction): turn in arcs, never on the spot
    v_cmd = max(v_cmd, abs(w_cmd) * R_DRIBBLE, v - A_DRIBBLE_BRAKE * DRIBBLE_CONTROL_PERIOD, 0.0)
    braking = max(0.0, v - v_cmd) / DRIBBLE_CONTROL_PERIOD
    w_bound = min(A_LAT_DRIBBLE * (1.0 - braking / ROLL_DECELERATION) / (v_cmd + LAT_SPEED_MARGIN),
                  v_cmd / R_DRIBBLE)
    w_cmd = _clip(w_cmd, w_bound)
    # an intermediate point inside the circle of the tightest turn is never reached by turning toward it
    ax, ay = x - BALL_POINT_OFFSET * math.cos(phi), y - BALL_POINT_OFFSET * math.sin(phi)
    side = 1.0 if error >= 0.0 else -1.0
    cx, cy = ax - side * R_DRIBBLE * math.sin(phi), ay + side * R_DRIBBLE * math.cos(phi)
    lure = min(LURE_MAX, LURE_GAIN * dist)
    tx, ty = xg - lure * math.cos(phig), yg - lure * math.sin(phig)
    if dist > ALIGN_RADIUS and math.hypot(tx - cx, ty - cy) < R_DRIBBLE:
        w_cmd = -side * w_bound  # loop round the other way
    return v_cmd, w_cmd


ACTION_FUNCTIONS: dict[str, Action] = {"goToPose": goToPose, "approachBall": approachBall, "dribbleBall": dribbleBall}
