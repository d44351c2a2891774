"""approachBall: drive to the ball lying at (xg, yg) so that it arrives with heading phig and speed vg,
without touching the ball before (Sec. 2.2); a pure function of the believed state and the subgoal.

A reactive Dubins-path follower (sims.soccer.follow) for the robot without a ball (turning radius
R_APPROACH): the axle is driven to a pre-pose PRE_DISTANCE behind the ball on the line of phig, then straight
in. Of the six Dubins words the shortest whose path keeps the axle AXLE_CLEARANCE from the ball (or no
closer than it already is) is taken; when none does (the ball lies between the robot and the pre-pose), the
robot first drives to one of VIA_POSES beside the ball, the one with the shortest way on to the pre-pose.
"""

from __future__ import annotations

import math

from tailor.sims.soccer.control import Pose, axle_pose
from tailor.sims.soccer.dubins import (DubinsPath, all_paths, candidates, surely_inside, word_bounds,
                                       word_distance)
from tailor.sims.soccer.follow import Follower
from tailor.sims.soccer.world import (A_MAX, BALL_RADIUS, FIELD_HALF_LENGTH, FIELD_HALF_WIDTH,
                               ROBOT_HALF_LENGTH, V_MAX, W_MAX, WALL_RUNOFF, ALPHA_MAX)

R_APPROACH = 0.4  # m, turning radius of the axle's path without the ball
W_APPROACH = 1.5  # rad/s, turn rate arcs are driven at (0.6 m/s on an arc)
PRE_DISTANCE = 0.5  # m, the Dubins path ends this far (ball point to ball) behind the ball
ROBOT_REACH = 0.36  # m, the farthest point of the body or the guide arms from the axle
AXLE_CLEARANCE = ROBOT_REACH + BALL_RADIUS + 0.05  # m, least distance of the axle's path from the ball (0.52)
VIA_POSES = ((-0.2, 0.8, math.pi), (-0.2, -0.8, math.pi), (0.4, 0.8, 0.0), (0.4, -0.8, 0.0))
# (along phig from the ball, lateral, heading relative to phig): where a detour round the ball leads
_MARGIN = math.hypot(ROBOT_HALF_LENGTH, ROBOT_HALF_LENGTH) + 0.05  # m, keeps the body off the walls
_HX = FIELD_HALF_LENGTH + WALL_RUNOFF - _MARGIN
_HY = FIELD_HALF_WIDTH + WALL_RUNOFF - _MARGIN

APPROACH = Follower(
    radius=R_APPROACH, w_plan=W_APPROACH, w_limit=W_MAX, v_top=V_MAX, v_creep=0.1,
    decel_plan=0.5 * A_MAX, decel_limit=10.0 * A_MAX, final_straight=PRE_DISTANCE,
    corridor_heading=math.radians(30.0), corridor_width=0.05, corridor_slope=0.2, corridor_extra=0.2,
    r_line=0.3, line_gain_max=5.0, capture_radial=0.1, capture_heading=0.5, capture_angle=math.pi,
    box=(-_HX, _HX, -_HY, _HY), lead_time=0.5 * W_APPROACH / ALPHA_MAX + 0.05,
)


def _clear_path(start: Pose, goal: Pose, ball: tuple[float, float], clearance: float) -> DubinsPath | None:
    """The shortest Dubins path from start to goal keeping `clearance` from the ball, inside the box."""
    box = APPROACH.box
    check_box = not surely_inside(start, goal, R_APPROACH, box)
    for _, word, lengths, exact in candidates(start, goal, R_APPROACH):
        if check_box:
            x0, x1, y0, y1 = word_bounds(start, word, lengths, R_APPROACH)
            if x0 < box[0] or x1 > box[1] or y0 < box[2] or y1 > box[3]:
                continue
        if word_distance(start, word, lengths, R_APPROACH, ball) >= clearance:
            return DubinsPath(word, lengths, R_APPROACH, exact)
    return None


def approach_path(start: Pose, pre: Pose, ball: tuple[float, float]) -> DubinsPath:
    """The path the robot follows now: to the pre-pose if one clears the ball, else to the best via pose."""
    clearance = min(AXLE_CLEARANCE, math.hypot(start[0] - ball[0], start[1] - ball[1]) - 0.02)
    path = _clear_path(start, pre, ball, clearance)
    if path is not None:
        return path
    best, best_length = None, math.inf
    c, s = math.cos(pre[2]), math.sin(pre[2])
    for along, lateral, turn in VIA_POSES:
        via = (ball[0] + along * c - lateral * s, ball[1] + along * s + lateral * c, pre[2] + turn)
        first = _clear_path(start, via, ball, clearance)
        if first is None:
            continue
        second = _clear_path(via, pre, ball, AXLE_CLEARANCE)
        length = first.length + (second.length if second is not None else 10.0)
        if length < best_length:
            best, best_length = first, length
    if best is None:  # nothing clears: the shortest path (the robot is boxed in by the ball and a wall)
        return all_paths(start, pre, R_APPROACH)[0]
    return best


def approachBall(x: float, y: float, phi: float, v: float, xg: float, yg: float, phig: float, vg: float
                 ) -> tuple[float, float]:
    """Drive round the ball at (xg, yg) and onto it with heading phig and speed vg; returns [v, phidot]."""
    ball = (xg, yg)
    return APPROACH.command(axle_pose(x, y, phi), v, axle_pose(xg, yg, phig), vg,
                            lambda start, pre: approach_path(start, pre, ball))
