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

from sims.soccer.control import axle_pose, clip, in_frame, profile_speed
from sims.soccer.dubins import shortest_path
from sims.soccer.world import BALL_POINT_OFFSET, wrap

R_DRIBBLE = 0.6  # m, turning radius of the axle's path with the ball (the ball point's: 0.68 m)
A_LAT_DRIBBLE = 0.3  # m/s^2, lateral acceleration planned with (the guide holds about 0.45 at R = 0.6 m)
V_DRIBBLE = 0.8  # m/s, top speed with the ball on a straight
V_ARC = math.sqrt(A_LAT_DRIBBLE * R_DRIBBLE)  # m/s, speed cap on an arc (0.42)
V_CREEP_DRIBBLE = 0.15  # m/s, minimum speed on an arc: the ball is held only while it rolls
A_DRIBBLE_BRAKE = 0.3  # m/s^2, braking bound: below the ball's own rolling deceleration (0.49)
CONTROL_PERIOD = 0.05  # s, the control period the braking bound is spread over (the simulator's)
ARC_TAPER = 0.15  # rad, the last radians of an arc are turned with proportionally less curvature
NEAR_RANGE = 2.0 * R_DRIBBLE  # m, goal closer than this ahead: steer onto the goal line, no loop
NEAR_HEADING = math.radians(60.0)  # rad, heading error up to which the robot counts as roughly aligned
NEAR_LATERAL = 0.5 * R_DRIBBLE  # m, lateral offset from the goal line up to which that holds
NEAR_DETOUR = 0.5 * R_DRIBBLE  # m, Dubins paths longer than the distance by more than this are replaced
R_NEAR = 0.5  # m, tightest turn of the line follower (it runs slower there, near the goal)


def dribbleBall(x: float, y: float, phi: float, v: float, xg: float, yg: float, phig: float, vg: float
                ) -> tuple[float, float]:
    """Follow the shortest Dubins path to the goal pose with the ball in the guide; returns [v, phidot]."""
    start = axle_pose(x, y, phi)
    goal = (xg - BALL_POINT_OFFSET * math.cos(phig), yg - BALL_POINT_OFFSET * math.sin(phig), phig)
    path = shortest_path(start, goal, R_DRIBBLE)
    along, lateral = in_frame(goal, start[0], start[1])  # axle in the goal frame, along < 0: behind the goal
    heading_error = wrap(phi - phig)
    near = (-NEAR_RANGE < along < 0.0 and abs(lateral) < NEAR_LATERAL and abs(heading_error) < NEAR_HEADING
            and path.length > -along + NEAR_DETOUR)
    if near:
        remaining = math.hypot(along, lateral)
        # a critically damped line follower whose settling length shrinks with the distance to the goal
        gain = 4.0 / max(-along, 0.2)
        curvature = clip(-gain * gain * lateral - 2.0 * gain * math.sin(heading_error), 1.0 / R_NEAR)
        v_target = min(profile_speed(remaining, vg, V_DRIBBLE, A_DRIBBLE_BRAKE),
                       math.sqrt(A_LAT_DRIBBLE / max(abs(curvature), 1e-6)))
    else:
        curvature = path.curvature(0)
        if curvature != 0.0 and path.lengths[0] < ARC_TAPER * R_DRIBBLE:
            curvature *= path.lengths[0] / (ARC_TAPER * R_DRIBBLE)
        v_target = profile_speed(path.length, vg, V_DRIBBLE, A_DRIBBLE_BRAKE)
        travelled = 0.0
        for seg in range(3):  # slow down for the current and each upcoming arc in time
            if path.word[seg] != "S" and path.lengths[seg] > 0.0:
                v_target = min(v_target, math.sqrt(V_ARC * V_ARC + 2.0 * A_DRIBBLE_BRAKE * travelled))
            travelled += path.lengths[seg]
    if curvature != 0.0:
        v_target = max(v_target, V_CREEP_DRIBBLE)
    v_cmd = max(v_target, v - A_DRIBBLE_BRAKE * CONTROL_PERIOD, 0.0)
    return v_cmd, curvature * max(0.0, min(v, v_cmd))
