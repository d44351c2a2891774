"""dribbleBall: a reactive Dubins-path follower that keeps the ball in the guide (Sec. 2.2).

A pure function of (x, y, phi, v, xg, yg, phig, vg), recomputed every control tick (sims.soccer.follow).
The wheel axle is a unicycle, so paths are planned for it: to the axle pose of the goal (the same heading,
BALL_POINT_OFFSET behind the goal's ball point), via the shortest Dubins path with turning radius R_DRIBBLE
that keeps the ball clear of the walls, then a final straight of FINAL_STRAIGHT.

What the guide holds (measured in this simulator, steady turns at constant speed, no noise): the ball stays
up to a turn rate of about 0.8 rad/s whatever the radius (0.22 m/s at R = 0.3 m, 0.5 m/s at 0.6 m, 0.98 m/s
at 1.2 m), i.e. a lateral acceleration of about 0.8 rad/s * v; less while braking. So arcs are driven at
W_DRIBBLE * R_DRIBBLE (0.24 m/s; the lateral-acceleration bound A_LAT_DRIBBLE = W_DRIBBLE^2 R_DRIBBLE) and the
rotational command never exceeds W_HOLD. The radius is tight because a turn of angle a takes a / W_DRIBBLE
whatever the radius, while a wide radius forces loops (a full one takes 2 pi / W_DRIBBLE, 10 s) for goals
near the start, which make durations hard to predict: at R_DRIBBLE = 0.7 m the learned duration model erred
by 5.8% of the mean duration, at 0.4 m by about 4%. Only a rolling ball is pressed into the V (by its rolling
friction), so the robot never turns on the spot: the rotational command is the curvature times the current
speed, at least V_CREEP_DRIBBLE on an arc. Braking never exceeds A_DRIBBLE_BRAKE, below the ball's own
rolling deceleration, so the ball is not lost ahead, and the speed never exceeds the profile braked at that
bound (a function of the distance to go): braking relative to the sensed speed alone let a run of same-signed
noise draws keep the robot at full speed into its last arc, where the ball was lost.
"""

from __future__ import annotations

import math

from tailor.sims.soccer.control import Pose, axle_pose
from tailor.sims.soccer.dubins import DubinsPath, shortest_path_inside
from tailor.sims.soccer.follow import Follower
from tailor.sims.soccer.world import BALL_POINT_OFFSET, BALL_RADIUS, FIELD_HALF_LENGTH, FIELD_HALF_WIDTH, WALL_RUNOFF

R_DRIBBLE = 0.4  # m, turning radius of the axle's path with the ball (the ball point's: 0.51 m)
W_DRIBBLE = 0.6  # rad/s, turn rate arcs are driven at with the ball
A_LAT_DRIBBLE = W_DRIBBLE * W_DRIBBLE * R_DRIBBLE  # m/s^2, the lateral acceleration that means (0.144)
W_HOLD = 0.75  # rad/s, the rotational command never exceeds this with the ball
V_DRIBBLE = 0.8  # m/s, top speed with the ball on a straight
V_CREEP_DRIBBLE = 0.15  # m/s, minimum speed on an arc: the ball is held only while it rolls
A_DRIBBLE_BRAKE = 0.3  # m/s^2, braking bound: below the ball's own rolling deceleration (0.49)
A_DRIBBLE_PLAN = 0.15  # m/s^2, deceleration the speed profile plans with (below the bound, so it is kept)
FINAL_STRAIGHT = 0.5  # m, the Dubins path ends on the goal line this far behind the goal
WALL_MARGIN = BALL_POINT_OFFSET + BALL_RADIUS + 0.15  # m, the axle's path keeps the ball this clear of walls
_HX = FIELD_HALF_LENGTH + WALL_RUNOFF - WALL_MARGIN
_HY = FIELD_HALF_WIDTH + WALL_RUNOFF - WALL_MARGIN

DRIBBLE = Follower(
    radius=R_DRIBBLE, w_plan=W_DRIBBLE, w_limit=W_HOLD, v_top=V_DRIBBLE, v_creep=V_CREEP_DRIBBLE,
    decel_plan=A_DRIBBLE_PLAN, decel_limit=A_DRIBBLE_BRAKE, final_straight=FINAL_STRAIGHT,
    corridor_heading=math.radians(50.0), corridor_width=0.1, corridor_slope=0.3, corridor_extra=0.3,
    r_line=0.5, line_gain_max=20.0, capture_radial=0.2, capture_heading=0.6, capture_angle=2.0 * math.pi,
    box=(-_HX, _HX, -_HY, _HY), bounded_braking=True,
)


def dribble_path(start: Pose, pre: Pose) -> DubinsPath:
    """The shortest Dubins path with the ball from the axle pose `start` to `pre`, clear of the walls."""
    return shortest_path_inside(start, pre, R_DRIBBLE, DRIBBLE.box)


def dribbleBall(x: float, y: float, phi: float, v: float, xg: float, yg: float, phig: float, vg: float
                ) -> tuple[float, float]:
    """Dribble the ball (in the guide) to the goal pose along a Dubins path; returns [v, phidot]."""
    return DRIBBLE.command(axle_pose(x, y, phi), v, axle_pose(xg, yg, phig), vg, dribble_path)
