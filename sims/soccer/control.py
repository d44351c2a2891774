"""Helpers the soccer actions share: the wheel-axle pose behind the ball point, speed profiles, clipping."""

from __future__ import annotations

import math

from tailor.sims.soccer.world import BALL_POINT_OFFSET

Pose = tuple[float, float, float]
ARRIVE_SLACK = 0.05  # m, a braking profile reaches vg this far before the goal (half the position tolerance)


def clip(value: float, bound: float) -> float:
    return -bound if value < -bound else bound if value > bound else value


def axle_pose(x: float, y: float, phi: float) -> Pose:
    """The wheel axle (centre of rotation, a true unicycle) behind the ball point (x, y) at heading phi."""
    return x - BALL_POINT_OFFSET * math.cos(phi), y - BALL_POINT_OFFSET * math.sin(phi), phi


def profile_speed(dist: float, vg: float, v_top: float, decel: float) -> float:
    """Speed from which braking at `decel` arrives with vg ARRIVE_SLACK before the end of `dist`."""
    return min(v_top, math.sqrt(vg * vg + 2.0 * decel * max(0.0, dist - ARRIVE_SLACK)))


def in_frame(pose: Pose, px: float, py: float) -> tuple[float, float]:
    """(along, lateral) coordinates of the point (px, py) in the frame of `pose`."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    dx, dy = px - pose[0], py - pose[1]
    return dx * c + dy * s, -dx * s + dy * c
