"""dribbleBall: a reactive Dubins-path follower that keeps the ball in the guide (Sec. 2.2).

A pure function of (x, y, phi, v, xg, yg, phig, vg), recomputed every control tick. The wheel axle is a
unicycle, so the path is planned for it: from the current axle pose to the axle pose of the goal (the same
heading, BALL_POINT_OFFSET behind the goal's ball point), the shortest Dubins path with the turning radius
R_DRIBBLE. The robot steers along the path's first segment (curvature +-1/R_DRIBBLE or 0); replanning every
tick is the feedback that keeps noise from accumulating. Only a rolling ball is pressed into the V of the
guide (by its rolling friction), so the robot never turns on the spot: the rotational command is the
curvature times the current speed, and the speed stays at least V_CREEP_DRIBBLE on an arc.

Speed: a braking profile over the remaining path length arrives with vg; on an arc (and before an upcoming
one) it is capped by the lateral-acceleration bound sqrt(A_LAT_DRIBBLE * R_DRIBBLE); braking never exceeds
A_DRIBBLE_BRAKE, below the ball's own rolling deceleration, so the ball is not lost ahead.

Near the goal (within NEAR_RANGE ahead, roughly aligned) a small lateral or heading error would make the
shortest Dubins path a full loop; there a line follower steers onto the goal line instead, and only a real
overshoot (the goal behind the robot) loops.
"""

from __future__ import annotations

import math

from sims.soccer.control import Pose, axle_pose, clip, in_frame, profile_speed
from sims.soccer.dubins import DubinsPath, shortest_path
from sims.soccer.world import BALL_POINT_OFFSET, wrap

R_DRIBBLE = 0.6  # m, turning radius of the axle's path with the ball (the ball point's: 0.68 m)
A_LAT_DRIBBLE = 0.3  # m/s^2, lateral acceleration planned with (the guide holds about 0.45 at R = 0.6 m)
V_DRIBBLE = 0.8  # m/s, top speed with the ball on a straight
V_CREEP_DRIBBLE = 0.15  # m/s, minimum speed on an arc: the ball is held only while it rolls
A_DRIBBLE_BRAKE = 0.3  # m/s^2, braking bound: below the ball's own rolling deceleration (0.49)
A_DRIBBLE_PLAN = 0.2  # m/s^2, deceleration the speed profile plans with (below the bound, so it is kept)
A_LAT_HOLD = 0.4  # m/s^2, the curvature command never asks for more lateral acceleration than this
CONTROL_PERIOD = 0.05  # s, the control period the braking bound is spread over (the simulator's)
K_ARC_END = 2.0  # 1/s, heading gain at the end of an arc: phidot <= K_ARC_END * (heading still to turn)
LEAD_TIME = 0.1  # s, an arc after a straight is begun this early (the motors lag the command)
MIN_SEGMENT = 0.01  # m, shorter arcs are not slowed down for
FINAL_STRAIGHT = 0.4  # m, the Dubins path ends this far behind the goal; the rest is a line follower
CORRIDOR_LENGTH = FINAL_STRAIGHT + 0.3  # m, the line follower takes over this far behind the goal ...
CORRIDOR_WIDTH = 0.1  # m, ... within this lateral offset plus CORRIDOR_SLOPE per metre still to go ...
CORRIDOR_SLOPE = 0.3
CORRIDOR_HEADING = math.radians(40.0)  # rad, ... and this heading error
R_NEAR = 0.4  # m, tightest turn of the line follower (it runs slower there)


def dribble_path(start: Pose, goal: Pose) -> DubinsPath:
    """The Dubins path the robot follows from the axle pose `start` to the axle pose `goal`."""
    pre = (goal[0] - FINAL_STRAIGHT * math.cos(goal[2]), goal[1] - FINAL_STRAIGHT * math.sin(goal[2]), goal[2])
    return shortest_path(start, pre, R_DRIBBLE)


def in_corridor(along: float, lateral: float, heading_error: float) -> bool:
    """Whether the axle (along, lateral in the goal frame) is on the final approach the line follower takes."""
    return (-CORRIDOR_LENGTH < along < 0.0 and abs(heading_error) < CORRIDOR_HEADING
            and abs(lateral) < CORRIDOR_WIDTH + CORRIDOR_SLOPE * -along)


def dribbleBall(x: float, y: float, phi: float, v: float, xg: float, yg: float, phig: float, vg: float
                ) -> tuple[float, float]:
    """Follow the shortest Dubins path to the goal pose with the ball in the guide; returns [v, phidot]."""
    start = axle_pose(x, y, phi)
    goal = (xg - BALL_POINT_OFFSET * math.cos(phig), yg - BALL_POINT_OFFSET * math.sin(phig), phig)
    along, lateral = in_frame(goal, start[0], start[1])  # axle in the goal frame, along < 0: behind the goal
    heading_error = wrap(phi - phig)
    if in_corridor(along, lateral, heading_error):
        # a critically damped line follower whose settling length shrinks with the distance to the goal
        gain = 4.0 / max(-along, 0.2)
        curvature = clip(-gain * gain * lateral - 2.0 * gain * math.sin(heading_error), 1.0 / R_NEAR)
        v_target = min(profile_speed(-along, vg, V_DRIBBLE, A_DRIBBLE_PLAN),
                       math.sqrt(A_LAT_DRIBBLE / max(abs(curvature), 1e-6)))
    else:
        path = dribble_path(start, goal)
        curvature = path.curvature(0)
        if curvature != 0.0:  # turn the last radians of an arc more gently, so noise does not chatter
            curvature = math.copysign(min(abs(curvature), K_ARC_END * path.lengths[0] / path.radius / max(v, 0.05)),
                                      curvature)
        elif path.lengths[0] < LEAD_TIME * v:
            curvature = path.curvature(1) * (1.0 - path.lengths[0] / (LEAD_TIME * v))
        remaining = path.length + FINAL_STRAIGHT
        v_target = profile_speed(remaining, vg, V_DRIBBLE, A_DRIBBLE_PLAN)
        v_arc = math.sqrt(A_LAT_DRIBBLE * path.radius)
        travelled = 0.0
        for seg in range(3):  # slow down for the current and each upcoming arc in time
            if path.word[seg] != "S" and path.lengths[seg] > MIN_SEGMENT:
                v_target = min(v_target, math.sqrt(v_arc * v_arc + 2.0 * A_DRIBBLE_PLAN * travelled))
            travelled += path.lengths[seg]
        if curvature != 0.0:
            v_target = max(v_target, V_CREEP_DRIBBLE)
    v_cmd = max(v_target, v - A_DRIBBLE_BRAKE * CONTROL_PERIOD, 0.0)
    speed = max(0.0, min(v, v_cmd))
    if speed > 0.0:  # a turn too sharp for the current speed would lose the ball: turn wider
        curvature = clip(curvature, A_LAT_HOLD / (speed * speed))
    return v_cmd, curvature * speed
