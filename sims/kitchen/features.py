"""The kitchen's own feature spaces (Table 4.1 rows for its actions).

"route" (navigate): the shortest route from the start pose to the goal pose round the divider and the island
(navigation.nominal_map, world.nominal_obstacles: the furniture that can lengthen a route), described by its
length, the turn needed at the start to face the route's first leg, the turn at the goal from the last leg to
the goal heading, and the turning at the route's corners; and the speeds the base starts with and passes the goal
at (0: at rest), the time-optimal transfer over the route's length between them (kinematics.transfer_time at
V_MAX, A_MAX), and the start speed times the start turn (the overshoot of a base that must turn while it still
moves); and the goal's cruise speed c (at most V_MAX) with `slow`, the route's length times 1/c - 1/V_MAX (the
time the governor adds where the base would cruise at V_MAX), and the scales of the kinetic energy spent at that
speed: `drive`, the length times c^2, and `corners`, the turning at the corners times c^2. Invariant to the
frame a pose is written in (a spot with zero offsets is the pose itself).

"grasp" (grip, put): where the point to reach lies relative to the arm's shoulder: the pan angle |psi| and the
extension r beyond the tucked EXT_REST, and the longer of the two joints' time-optimal ramps (the arm moves
both at once, so the slower joint sets the time). Invariant to rigid motions of base and point together.

Both declare guaranteed enclosures over boxes of parameters (FeatureSpace.bounds, for the certified optimizer):
"grasp" by interval arithmetic through the geometry (the ramps are increasing in the distances they cover),
"route" by deciding the route's candidates box by box (sims.kitchen.route_bounds).
"""

from __future__ import annotations

import numpy as np
from tailor.sims import intervals as I
from tailor.sims.kitchen import world as W
from tailor.sims.kitchen.navigation import nominal_map
from tailor.sims.kitchen.route_bounds import route_bounds
from tailor.sims.kinematics import transfer_time
from tailor.sims.protocol import FeatureSpace

SPOT = ("ox", "oy", "ophi", "along", "dist", "heading")
PASSING = SPOT + ("v",)  # navigate's start and goal: a spot and the speed the base has there
GOAL = PASSING + ("cruise",)  # navigate's goal: and the cruise speed (world.CRUISE)


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2 * np.pi) - np.pi


def spot_poses(p: np.ndarray) -> np.ndarray:
    """(n, 6) spots -> (n, 3) poses x, y, phi (world.spot_pose, vectorized)."""
    ox, oy, ophi, along, dist, heading = p.T
    c, s = np.cos(ophi), np.sin(ophi)
    return np.column_stack([ox - dist * c - along * s, oy - dist * s + along * c, _wrap(ophi + heading)])


def _route(params: np.ndarray) -> np.ndarray:
    start, goal = spot_poses(params[:, :6]), spot_poses(params[:, 7:13])
    v_start, v_goal = params[:, 6], params[:, 13]
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
    transfer = transfer_time(length, v_start, v_goal, W.V_MAX, W.A_MAX)
    cruise = np.minimum(params[:, 14], W.V_MAX)
    slow = _slow(length, cruise)
    return np.column_stack([length, turn_start, turn_goal, turning, v_start, v_goal, transfer, v_start * turn_start,
                            cruise, slow, length * cruise * cruise, turning * cruise * cruise])


def _slow(length: np.ndarray, cruise: np.ndarray) -> np.ndarray:
    """The route's length times 1/cruise - 1/V_MAX: 0 at the top cruise speed (also with no route, length inf)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(cruise >= W.V_MAX, 0.0, length * (1.0 / cruise - 1.0 / W.V_MAX))


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


def _columns(low: np.ndarray, high: np.ndarray) -> list[I.Pair]:
    low, high = np.atleast_2d(np.asarray(low, dtype=float)), np.atleast_2d(np.asarray(high, dtype=float))
    return [(low[:, k], high[:, k]) for k in range(low.shape[1])]


def spot_pose_bounds(spot: list[I.Pair]) -> tuple[I.Pair, I.Pair, I.Pair]:
    """Enclosures of a spot's pose x, y over boxes of its six values (spot_poses, evaluated in its order:
    each operation rounds monotonically in each argument), and its heading ophi + heading unwrapped (the
    features only use it through a wrapped difference)."""
    ox, oy, ophi, along, dist, heading = spot
    s, c = I.sin_cos(*ophi)
    dc, ds, ac, as_ = I.product(dist, c), I.product(dist, s), I.product(along, c), I.product(along, s)
    x = I.widen(ox[0] - dc[1] - as_[1], ox[1] - dc[0] - as_[0])
    y = I.widen(oy[0] - ds[1] + ac[0], oy[1] - ds[0] + ac[1])
    return x, y, (ophi[0] + heading[0], ophi[1] + heading[1])


def _route_bounds(low: np.ndarray, high: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A guaranteed enclosure of `_route` over boxes of parameters (FeatureSpace.bounds): route_bounds over the
    boxes of both poses."""
    columns = _columns(low, high)
    (sx, sy, s_phi), (gx, gy, g_phi) = spot_pose_bounds(columns[:6]), spot_pose_bounds(columns[7:13])
    lo, hi = route_bounds(nominal_map(), (sx, sy), s_phi, (gx, gy), g_phi)
    v_start, v_goal = columns[6], columns[13]
    with np.errstate(invalid="ignore"):  # (a box with no route: length [inf, inf], its transfer time too)
        transfer = I.transfer_time_bounds((lo[:, 0], hi[:, 0]), v_start, v_goal, W.V_MAX, W.A_MAX)
    carry = I.product(v_start, (lo[:, 1], hi[:, 1]))
    cruise = (np.minimum(columns[14][0], W.V_MAX), np.minimum(columns[14][1], W.V_MAX))
    # 1/cruise - 1/V_MAX >= 0 falls with the cruise speed, and the length is >= 0: the product's bounds are the
    # corners', widened
    slow = I.widen(_slow(lo[:, 0], cruise[1]), _slow(hi[:, 0], cruise[0]))
    squared = I.square(*cruise)
    drive = I.widen(*I.product((lo[:, 0], hi[:, 0]), squared))
    corners = I.widen(*I.product((lo[:, 3], hi[:, 3]), squared))
    extra = (v_start, v_goal, transfer, carry, cruise, slow, drive, corners)
    return (np.column_stack([lo, *(e[0] for e in extra)]), np.column_stack([hi, *(e[1] for e in extra)]))


def _ramp_time_bounds(distance: I.Pair, v_max: float, a_max: float) -> I.Pair:
    """ramp_time over an interval of distances: increasing in |distance| (both pieces meet at the knee)."""
    lo, hi = I.absolute(*distance)
    return I.widen(ramp_time(lo, v_max, a_max), ramp_time(hi, v_max, a_max))


def _grasp_bounds(low: np.ndarray, high: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A guaranteed enclosure of `_grasp` over boxes of parameters (FeatureSpace.bounds): interval arithmetic
    through reach_geometry (the pan as the least turn between the direction to the point and the heading), the
    ramps increasing in the distances they cover. Exact at a point; over a box as wide as the heading's
    dependence through both the shoulder and the pan lets it be."""
    columns = _columns(low, high)
    x, y, phi = spot_pose_bounds(columns[:6])
    s, c = I.sin_cos(*phi)
    sx = I.widen(x[0] + W.SHOULDER_OFFSET * c[0], x[1] + W.SHOULDER_OFFSET * c[1])
    sy = I.widen(y[0] + W.SHOULDER_OFFSET * s[0], y[1] + W.SHOULDER_OFFSET * s[1])
    (px, py) = columns[6], columns[7]
    dx, dy = I.widen(px[0] - sx[1], px[1] - sx[0]), I.widen(py[0] - sy[1], py[1] - sy[0])
    bearing = I.direction(dx, dy)
    pan = I.abs_wrapped(bearing[0] - phi[1], bearing[1] - phi[0])
    reach = I.hypot(dx, dy)
    extension = I.widen(reach[0] - W.EXT_REST, reach[1] - W.EXT_REST)
    pan_ramp = _ramp_time_bounds(pan, W.PAN_SPEED, W.PAN_ACCELERATION)
    ext_ramp = _ramp_time_bounds(extension, W.EXT_SPEED, W.EXT_ACCELERATION)
    return (np.column_stack([pan[0], extension[0], np.maximum(pan_ramp[0], ext_ramp[0])]),
            np.column_stack([pan[1], extension[1], np.maximum(pan_ramp[1], ext_ramp[1])]))


def _reframe(spots: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The same poses as spots of random other frames (offsets solved so that spot_poses is unchanged)."""
    pose = spot_poses(spots)
    n = len(spots)
    ox, oy = pose[:, 0] + rng.uniform(-1.0, 1.0, n), pose[:, 1] + rng.uniform(-1.0, 1.0, n)
    ophi = rng.uniform(-np.pi, np.pi, n)
    return np.column_stack([ox, oy, ophi, *W.spot_offsets((ox, oy, ophi), pose.T)])


def _route_reframe(params: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    return np.column_stack([_reframe(params[:, :6], rng), params[:, 6], _reframe(params[:, 7:13], rng),
                            params[:, 13:15]])


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


ROUTE = FeatureSpace("route", PASSING + tuple(f"{q}g" for q in GOAL),
                     ("length", "turn_start", "turn_goal", "turning", "v_start", "v_goal", "transfer", "carry",
                      "cruise", "slow", "drive", "corners"),
                     _route, "the frame each pose is written in", _route_reframe, _route_bounds)
GRASP = FeatureSpace("grasp", SPOT + ("px", "py"), ("pan", "extension", "ramp"), _grasp,
                     "rigid motions of base and point together", _rigid_motion, _grasp_bounds)
