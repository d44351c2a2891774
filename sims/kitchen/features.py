"""The kitchen's own feature spaces (Table 4.1 rows for its actions).

"route" (navigate): the shortest route from the start pose to the goal pose round the divider and the island
(navigation.nominal_map, world.nominal_obstacles: the furniture that can lengthen a route), described by its length, the turn needed at the start to face the route's first leg, the turn
at the goal from the last leg to the goal heading, and the turning at the route's corners. Invariant to
the frame a pose is written in (a spot with zero offsets is the pose itself).

"grasp" (grip, put): where the point to reach lies relative to the arm's shoulder: the pan angle |psi| and the
extension r beyond the tucked EXT_REST, and the longer of the two joints' time-optimal ramps (the arm moves
both at once, so the slower joint sets the time). Invariant to rigid motions of base and point together.
"""

from __future__ import annotations

import numpy as np

from tailor.sims.kitchen import world as W
from tailor.sims.kitchen.navigation import nominal_map
from tailor.sims.protocol import FeatureSpace

SPOT = ("ox", "oy", "ophi", "along", "dist", "heading")


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2 * np.pi) - np.pi


def spot_poses(p: np.ndarray) -> np.ndarray:
    """(n, 6) spots -> (n, 3) poses x, y, phi (world.spot_pose, vectorized)."""
    ox, oy, ophi, along, dist, heading = p.T
    c, s = np.cos(ophi), np.sin(ophi)
    return np.column_stack([ox - dist * c - along * s, oy - dist * s + along * c, _wrap(ophi + heading)])


def _route(params: np.ndarray) -> np.ndarray:
    start, goal = spot_poses(params[:, :6]), spot_poses(params[:, 6:12])
    routes = nominal_map()
    length, first, last, turning = routes.routes(start[:, :2], goal[:, :2])
    nodes = routes.nodes
    to = np.where(first[:, None] >= 0, nodes[np.maximum(first, 0)], goal[:, :2])
    frm = np.where(last[:, None] >= 0, nodes[np.maximum(last, 0)], start[:, :2])
    first_dir = np.arctan2(to[:, 1] - start[:, 1], to[:, 0] - start[:, 0])
    last_dir = np.arctan2(goal[:, 1] - frm[:, 1], goal[:, 0] - frm[:, 0])
    short = length < 1e-3  # no leg to face: only the heading changes
    turn_start = np.where(short, 0.0, np.abs(_wrap(first_dir - start[:, 2])))
    turn_goal = np.where(short, np.abs(_wrap(goal[:, 2] - start[:, 2])), np.abs(_wrap(goal[:, 2] - last_dir)))
    return np.column_stack([length, turn_start, turn_goal, turning])


def ramp_time(distance: np.ndarray, v_max: float, a_max: float) -> np.ndarray:
    """Duration of the time-optimal rest-to-rest ramp over `distance` (trapezoid, or triangle if short)."""
    d = np.abs(distance)
    return np.where(d >= v_max * v_max / a_max, d / v_max + v_max / a_max, 2.0 * np.sqrt(d / a_max))


def reach_geometry(params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(pan angle psi, extension r) from the shoulder of the base at the spot to the point (px, py)."""
    pose = spot_poses(params[:, :6])
    sx = pose[:, 0] + W.SHOULDER_OFFSET * np.cos(pose[:, 2])
    sy = pose[:, 1] + W.SHOULDER_OFFSET * np.sin(pose[:, 2])
    dx, dy = params[:, 6] - sx, params[:, 7] - sy
    return _wrap(np.arctan2(dy, dx) - pose[:, 2]), np.hypot(dx, dy)


def _grasp(params: np.ndarray) -> np.ndarray:
    pan, ext = reach_geometry(params)
    pan = np.abs(pan)
    extension = ext - W.EXT_REST
    ramp = np.maximum(ramp_time(pan, W.PAN_SPEED, W.PAN_ACCELERATION),
                      ramp_time(extension, W.EXT_SPEED, W.EXT_ACCELERATION))
    return np.column_stack([pan, extension, ramp])


def _reframe(spots: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The same poses as spots of random other frames (offsets solved so that spot_poses is unchanged)."""
    pose = spot_poses(spots)
    n = len(spots)
    ox, oy = pose[:, 0] + rng.uniform(-1.0, 1.0, n), pose[:, 1] + rng.uniform(-1.0, 1.0, n)
    ophi = rng.uniform(-np.pi, np.pi, n)
    c, s = np.cos(ophi), np.sin(ophi)
    dx, dy = pose[:, 0] - ox, pose[:, 1] - oy
    return np.column_stack([ox, oy, ophi, -s * dx + c * dy, -(c * dx + s * dy), _wrap(pose[:, 2] - ophi)])


def _route_reframe(params: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    return np.column_stack([_reframe(params[:, :6], rng), _reframe(params[:, 6:12], rng)])


def _rigid_motion(params: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Base frame and point rotated by one random angle and shifted by one random offset."""
    a = rng.uniform(-np.pi, np.pi)
    t = rng.uniform(-2.0, 2.0, 2)
    c, s = np.cos(a), np.sin(a)
    out = params.copy()
    for x, y in ((0, 1), (6, 7)):
        out[:, x] = c * params[:, x] - s * params[:, y] + t[0]
        out[:, y] = s * params[:, x] + c * params[:, y] + t[1]
    out[:, 2] = _wrap(params[:, 2] + a)
    return out


ROUTE = FeatureSpace("route", SPOT + tuple(f"{q}g" for q in SPOT), ("length", "turn_start", "turn_goal", "turning"),
                     _route, "the frame each pose is written in", _route_reframe)
GRASP = FeatureSpace("grasp", SPOT + ("px", "py"), ("pan", "extension", "ramp"), _grasp,
                     "rigid motions of base and point together", _rigid_motion)
