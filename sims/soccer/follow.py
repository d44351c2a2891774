"""A reactive Dubins-path follower: the controller dribbleBall and approachBall share (a pure function).

Every control tick, from the believed state only, the wheel axle (a unicycle) is steered toward the axle
goal pose in one of three modes, checked in this order:

1. final straight: behind the goal on its line, roughly aligned -> a line follower onto the goal line;
2. final arc: on the circle of radius `radius` that ends tangentially in the pre-pose (`final_straight`
   behind the goal), heading along it -> that circle is tracked with feedback on the distance to it;
3. otherwise: the path `choose_path(start, pre_pose)` (a shortest Dubins path, possibly filtered) is
   followed along its first segment, curvature +-1/radius or 0.

Modes 1 and 2 exist because a replanned shortest Dubins path is fragile exactly where it is followed: a
robot a centimetre inside its last arc, or late for it, needs a full loop to reach the pose exactly. The
tracked circle and the line follower absorb such errors with the turning authority left beyond `radius`.
Speeds: a braking profile over the remaining length arrives with vg; arcs are driven at `w_plan * radius`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from tailor.sims.soccer.control import Pose, clip, in_frame, profile_speed
from tailor.sims.soccer.dubins import DubinsPath, word_bounds
from tailor.sims.soccer.world import wrap

CORRECTION_SHARE = 0.5  # a small first arc before a straight is turned within this share of the straight,
CORRECTION_MIN, CORRECTION_MAX = 0.05, 0.5  # m, ... within these bounds (so sensing noise does not chatter)
MIN_SEGMENT = 0.01  # m, shorter arcs are not slowed down for
K_RADIAL = 2.0  # rad/m, heading offset toward the tracked circle per metre off it (atan-limited)
K_TRACK = 2.0  # 1/s, rotational command per radian of heading error when tracking the circle


@dataclass(frozen=True)
class Follower:
    """Parameters of one use of the follower (SI units)."""

    radius: float  # m, turning radius of the axle's Dubins paths
    w_plan: float  # rad/s, turn rate arcs are driven at (speed on an arc: w_plan * radius)
    w_limit: float  # rad/s, the rotational command never exceeds this
    v_top: float  # m/s, top speed on a straight
    v_creep: float  # m/s, minimum speed while turning on an arc (0: may stop)
    decel_plan: float  # m/s^2, deceleration the speed profile plans with
    decel_limit: float  # m/s^2, the speed command never drops faster than this
    final_straight: float  # m, the Dubins path ends this far behind the goal, on its line
    corridor_heading: float  # rad, the line follower takes over within this heading error ...
    corridor_width: float  # m, ... this lateral offset plus corridor_slope per metre still to go ...
    corridor_slope: float
    corridor_extra: float  # m, ... and from final_straight + corridor_extra behind the goal
    r_line: float  # m, tightest turn of the line follower
    line_gain_max: float  # 1/m, the line follower's gain (4 / distance to go: settles on the way) at most
    capture_radial: float  # m, a robot this close to the final circle ...
    capture_heading: float  # rad, ... heading along it within this ...
    capture_angle: float  # rad, ... with at most this much of it to go, tracks it
    box: tuple[float, float, float, float]  # the region (xmin, xmax, ymin, ymax) the axle's path stays in
    lead_time: float = 0.1  # s, an arc after a straight is begun this early (the motors lag the command)
    control_period: float = 0.05  # s, the period decel_limit is spread over (the simulator's)
    # the speed command also stays below the profile braked at decel_limit (a function of the distance to go,
    # not of the sensed speed): without it, braking "decel_limit below the believed speed" is a random walk
    # under sensing and motor noise, which a run of same-signed draws turns into no braking at all
    bounded_braking: bool = False
    # a small first arc before a long straight is turned gently (a curvature below 1 / radius) and driven at the
    # speed that curvature allows at the arcs' lateral acceleration (w_plan * sqrt(radius / |curvature|)), not
    # crept along at the arc speed: creeping, a 0.19 rad error at the start of a 7 m dribble cost 3.3 s while the
    # gentle turn converged, a smooth valley in the start heading that no planned-path feature can see. Off only
    # for goToPose, whose models were not retrained for it (sims.soccer.goto)
    gentle_at_speed: bool = True

    def pre_pose(self, goal: Pose) -> Pose:
        """The pose on the goal line final_straight behind the (axle) goal, where the Dubins path ends."""
        d = self.final_straight
        return goal[0] - d * math.cos(goal[2]), goal[1] - d * math.sin(goal[2]), goal[2]

    def in_corridor(self, along: float, lateral: float, heading_error: float) -> bool:
        """Whether the axle (along, lateral in the goal frame) is on the final straight."""
        return (-(self.final_straight + self.corridor_extra) < along < 0.0
                and abs(heading_error) < self.corridor_heading
                and abs(lateral) < self.corridor_width + self.corridor_slope * -along)

    def final_arc(self, start: Pose, pre: Pose) -> tuple[float, float, float] | None:
        """(heading error, length to go, side) if the axle is on the circle ending tangentially in the
        pre-pose (side +1: a left turn), heading along it, and that arc stays in the box; else None."""
        x, y, phi = start
        r = self.radius
        sin_pre, cos_pre = math.sin(pre[2]), math.cos(pre[2])
        for side in (1.0, -1.0):
            cx, cy = pre[0] - side * r * sin_pre, pre[1] + side * r * cos_pre
            rho = math.hypot(x - cx, y - cy)
            if abs(rho - r) > self.capture_radial:
                continue
            at = math.atan2(y - cy, x - cx)
            tangent = at + side * 0.5 * math.pi
            if abs(wrap(tangent - phi)) > self.capture_heading:
                continue
            to_go = (side * (math.atan2(pre[1] - cy, pre[0] - cx) - at)) % (2.0 * math.pi)
            if to_go > self.capture_angle:
                continue
            x0, x1, y0, y1 = word_bounds(start, "LSL" if side > 0.0 else "RSR", (to_go * r, 0.0, 0.0), r)
            if x0 < self.box[0] or x1 > self.box[1] or y0 < self.box[2] or y1 > self.box[3]:
                continue
            # aim toward the circle when off it (outside: turn in more; inside: less)
            error = wrap(tangent + side * math.atan(K_RADIAL * (rho - r)) - phi)
            return error, to_go * r, side
        return None

    def final_command(self, start: Pose, v: float, goal: Pose, vg: float) -> tuple[float, float] | None:
        """[v, phidot] on the final straight (mode 1) or the final arc (mode 2); None elsewhere."""
        along, lateral = in_frame(goal, start[0], start[1])  # along < 0: behind the goal
        heading_error = wrap(start[2] - goal[2])
        if self.in_corridor(along, lateral, heading_error):
            return self.line_command(along, lateral, heading_error, v, vg)
        arc = self.final_arc(start, self.pre_pose(goal))
        if arc is None:
            return None
        error, to_go, side = arc
        to_goal = to_go + self.final_straight
        arc_speed = self.w_plan * self.radius
        v_target = max(min(arc_speed, profile_speed(to_goal, vg, self.v_top, self.decel_plan)), self.v_creep)
        bound = (max(min(arc_speed, profile_speed(to_goal, vg, self.v_top, self.decel_limit)), self.v_creep)
                 if self.bounded_braking else None)
        return self.limited(v_target, side * max(0.0, v) / self.radius + K_TRACK * error, v, bound)

    def line_command(self, along: float, lateral: float, heading_error: float, v: float, vg: float
                     ) -> tuple[float, float]:
        """[v, phidot] onto the goal line from (along, lateral, heading error) in the goal frame: a critically
        damped line follower whose settling length shrinks with the distance to the goal."""
        gain = min(self.line_gain_max, 4.0 / max(-along, 1e-3))
        curvature = clip(-gain * gain * lateral - 2.0 * gain * math.sin(heading_error), 1.0 / self.r_line)
        turn_speed = self.w_plan / max(abs(curvature), 1e-6)
        v_target = min(profile_speed(-along, vg, self.v_top, self.decel_plan), turn_speed)
        bound = (min(profile_speed(-along, vg, self.v_top, self.decel_limit), turn_speed)
                 if self.bounded_braking else None)
        return self.limited(v_target, curvature * min(max(0.0, v), v_target), v, bound)

    def command(self, start: Pose, v: float, goal: Pose, vg: float,
                choose_path: Callable[[Pose, Pose], DubinsPath]) -> tuple[float, float]:
        """[v, phidot] steering the axle pose `start` (speed v) to the axle pose `goal`, arriving with vg."""
        final = self.final_command(start, v, goal, vg)
        return final if final is not None else self.path_command(choose_path(start, self.pre_pose(goal)), v, vg)

    def path_command(self, path: DubinsPath, v: float, vg: float) -> tuple[float, float]:
        """[v, phidot] along the first segment of `path`, a Dubins path from the axle to the pre-pose (mode 3)."""
        curvature = self._path_curvature(path, v)
        v_target = self._path_speed(path, v, vg, self.decel_plan, curvature)
        bound = self._path_speed(path, v, vg, self.decel_limit, curvature) if self.bounded_braking else None
        return self.limited(v_target, curvature * max(0.0, v), v, bound)  # the actual speed: braking lags v_target

    def limited(self, v_target: float, w: float, v: float, bound: float | None = None) -> tuple[float, float]:
        """The command within the braking bound (per control period) and the rotational limit; with `bound`
        (bounded_braking: the profile braked at decel_limit), never above it."""
        braked = v - self.decel_limit * self.control_period
        if bound is not None and braked > bound:
            braked = bound
        return max(v_target, braked, 0.0), clip(w, self.w_limit)

    def _path_curvature(self, path: DubinsPath, v: float) -> float:
        """The curvature commanded on the first segment of a Dubins path ending at the pre-pose."""
        curvature = path.curvature(0)
        span = min(CORRECTION_MAX, max(CORRECTION_MIN, CORRECTION_SHARE * path.lengths[1]))
        if curvature != 0.0 and path.word[1] == "S" and path.lengths[1] > span:
            # a small correction before a long straight: gently (before a short one the next arc follows at
            # once, and a softened turn would drift off the circles until the word no longer exists)
            curvature = math.copysign(min(abs(curvature), path.lengths[0] / path.radius / span), curvature)
        elif curvature == 0.0 and path.lengths[0] < self.lead_time * v:
            curvature = path.curvature(1) * (1.0 - path.lengths[0] / (self.lead_time * v))
        return curvature

    def _path_speed(self, path: DubinsPath, v: float, vg: float, decel: float, curvature: float) -> float:
        """Target speed on that path, braking at `decel` in time for every arc and the end."""
        v_target = profile_speed(path.length + self.final_straight, vg, self.v_top, decel)
        arc_speed = self.w_plan * path.radius
        travelled = -self.lead_time * v  # the arc is begun this early
        for seg in range(3):  # slow down for the current and each upcoming arc in time
            if path.word[seg] != "S" and path.lengths[seg] > MIN_SEGMENT:
                slack = max(0.0, travelled)
                speed = arc_speed
                if seg == 0 and self.gentle_at_speed and curvature != 0.0:
                    speed = max(arc_speed, self.w_plan * math.sqrt(path.radius / abs(curvature)))
                v_target = min(v_target, math.sqrt(speed * speed + 2.0 * decel * slack))
            travelled += path.lengths[seg]
        if curvature != 0.0:
            v_target = max(v_target, self.v_creep)
        return v_target
