"""goToPose (App. A.1): navigate to a pose via an intermediate point behind it; blind to any ball.

A pure function of (x, y, phi, v, xg, yg, phig, vg), recomputed every control tick. The wheel axle is
steered to the axle goal pose (BALL_POINT_OFFSET behind the goal's ball point) in the first of four modes
that applies:

1. final approach: behind the goal in a corridor round its line (GOTO.in_corridor), or on the circle that
   ends tangentially in the pre-pose GOTO_STRAIGHT behind the goal: the line follower or the tracked circle
   of sims.soccer.follow brings it in with the goal heading and speed;
2. line: in a wider corridor (LURE_CORRIDOR: up to 0.9 m behind the goal, heading within 45 degrees) the
   same line follower takes over from the lure;
3. direct: where the shortest Dubins path onto the pre-pose (turning radius R_APPROACH) is at most
   MAX_DETOUR longer than the straight line to it, that path is followed (approachBall's follower);
4. lure: otherwise the robot heads for the intermediate point (IP) on the goal line, LURE_MIN plus
   LURE_GAIN times its own distance behind the goal behind the goal pose, turning on the spot while the
   IP lies behind it. As it closes in from behind, the IP approaches the goal pose and lures the robot in
   with the right heading (App. A.1); from in front or beside the goal, the IP lies just behind it, so the
   robot crosses the goal position on the way.

Why the lure, and why only there. A robot that must get round the goal to approach it from behind drives
straight across the goal position, which is what makes plain goToPose bump a ball lying at its goal in a
cone in front of the goal pose (Sec. 4.2.2, Fig. 4.8), whatever the noise: the collision classifier has a
geometric region to learn. Where no detour is needed the Dubins path is shorter and smooth. Mode 3 never
hands back to mode 4 on its own: following a Dubins path shortens it at the driven speed while the
straight line shortens at most as fast, so its detour never grows. An earlier goToPose that followed a
Dubins path all the way went round a ball at its goal, grazing it in 0.4-0.8% of episodes as noise
decided, which no classifier could predict.

The lure's constants were measured (2000 goToPose episodes each, gradient boosting's MAE on a quarter held
out): at LURE_MIN 0.3 m and LURE_GAIN 0.5 every episode succeeds and the MAE is 3.9% of the mean duration;
with LURE_MIN 0.2 m the robot can circle the IP until it times out (5% of episodes); with LURE_GAIN 0.3 the
MAE is 9.8% (and 1 timeout); with LURE_MIN 0.4 m it is 5.6%. The line corridor narrows to 5 cm at the goal:
at 30 cm a robot could stop beside the goal, its speed profile run out, and wait there until the timeout.
"""

from __future__ import annotations

import math
from dataclasses import replace

from tailor.sims.soccer.approach import APPROACH, R_APPROACH
from tailor.sims.soccer.control import Pose, axle_pose, clip, in_frame, profile_speed
from tailor.sims.soccer.dubins import DubinsPath, shortest_path_inside
from tailor.sims.soccer.world import wrap

GOTO_STRAIGHT = 0.1  # m, the Dubins path ends this little behind the goal
# a gentle first correction is driven at the speed its curvature allows, as approachBall and dribbleBall drive
# it (sims.soccer.follow): creeping along it at the arc speed cost 0.8 s of a 6.7 s goToPose on average
GOTO = replace(APPROACH, final_straight=GOTO_STRAIGHT)
LURE_CORRIDOR = replace(APPROACH, final_straight=0.3, corridor_extra=0.6, corridor_heading=math.radians(45.0),
                        corridor_width=0.05, corridor_slope=0.5)  # where the line follower takes over from the lure
MAX_DETOUR = 1.0  # m, a Dubins path at most this much longer than the straight line to its end is followed
LURE_MIN = 0.3  # m, the IP lies at least this far behind the (axle) goal ...
LURE_GAIN = 0.5  # ... plus this times the robot's own distance behind the goal (0 in front of it)
LURE_MAX = 2.0  # m, ... and at most this far
W_LURE = 2.0  # rad/s, turn rate toward the IP
K_LURE = 5.0  # 1/s, rotational command per radian of bearing error to the IP (until W_LURE)
V_CREEP = 0.1  # m/s, speed while the IP lies more than 90 degrees off the heading (a turn on the spot)


def goto_path(start: Pose, pre: Pose) -> DubinsPath:
    """The shortest Dubins path onto the pre-pose that stays on the field (blind to any ball)."""
    return shortest_path_inside(start, pre, R_APPROACH, GOTO.box)


def lure_point(start: Pose, goal: Pose, along: float | None = None) -> tuple[float, float]:
    """The IP: on the goal line behind the goal, nearer the goal the nearer the robot comes from behind
    (`along`: the robot's coordinate along the goal heading, if the caller has it)."""
    if along is None:
        along = in_frame(goal, start[0], start[1])[0]
    d = min(LURE_MAX, LURE_MIN + LURE_GAIN * max(0.0, -along))
    box = GOTO.box
    return (min(box[1], max(box[0], goal[0] - d * math.cos(goal[2]))),
            min(box[3], max(box[2], goal[1] - d * math.sin(goal[2]))))


def lure_command(start: Pose, v: float, goal: Pose, vg: float, along: float) -> tuple[float, float]:
    """[v, phidot] heading the axle for the IP: slower the more it must turn, on the spot if it lies behind."""
    ix, iy = lure_point(start, goal, along)
    bearing_error = wrap(math.atan2(iy - start[1], ix - start[0]) - start[2])
    rest = math.hypot(ix - start[0], iy - start[1]) + math.hypot(goal[0] - ix, goal[1] - iy)
    v_target = profile_speed(rest, vg, GOTO.v_top, GOTO.decel_plan)
    if abs(bearing_error) < 0.5 * math.pi:
        v_target = min(v_target, max(V_CREEP, GOTO.v_top * math.cos(bearing_error)))
    else:
        v_target = V_CREEP
    return GOTO.limited(v_target, clip(K_LURE * bearing_error, W_LURE), v)  # W_LURE < GOTO.w_limit


def goToPose(x: float, y: float, phi: float, v: float, xg: float, yg: float, phig: float, vg: float
             ) -> tuple[float, float]:
    """Navigate to the goal pose, arriving with heading phig and speed vg (App. A.1); returns [v, phidot].
    It knows nothing of a ball: on the way it may bump one."""
    start, goal = axle_pose(x, y, phi), axle_pose(xg, yg, phig)
    final = GOTO.final_command(start, v, goal, vg)
    if final is not None:
        return final
    along, lateral = in_frame(goal, start[0], start[1])
    heading_error = wrap(start[2] - goal[2])
    if LURE_CORRIDOR.in_corridor(along, lateral, heading_error):
        return LURE_CORRIDOR.line_command(along, lateral, heading_error, v, vg)
    pre = GOTO.pre_pose(goal)
    path = goto_path(start, pre)
    if path.length - math.hypot(pre[0] - start[0], pre[1] - start[1]) <= MAX_DETOUR:
        return GOTO.path_command(path, v, vg)
    return lure_command(start, v, goal, vg, along)
