"""The kitchen world (Sec. 5.5, Fig. 5.11): two rooms, their furniture, a B21-like base with an arm, cups.

Coordinates: metres, radians, seconds; top view, phi counter-clockwise from +x.

Rooms: ROOM_LENGTH x ROOM_WIDTH, split at x = DIVIDER_X by a wall with a door (DOOR_Y, DOOR_WIDTH wide).
Room A (x < DIVIDER_X) holds table1 against its north wall and the fixed kitchen island; room B holds
table2 against its east wall. Tables are static boxes TABLE_LENGTH x TABLE_DEPTH served from one long edge
(the *serving edge*, facing the room); the layout's random displacements (Fig. 5.11(a)) move each table
along its wall, its cups along and into the table, and the robot's start within START_REGION.

Robot (B21, synchro drive, modelled as a unicycle about the centre of its round base of BASE_RADIUS):
motor commands [v, phidot] with |v| <= V_MAX, |phidot| <= W_MAX, changed no faster than A_MAX, ALPHA_MAX.
Its arm stands at the front (shoulder SHOULDER_OFFSET ahead of the centre) and has two joints: a pan joint
(bearing psi from the base heading, |psi| <= PAN_LIMIT, PAN_SPEED, PAN_ACCELERATION) and a horizontal
extension (gripper distance r from the shoulder, EXT_REST <= r <= EXT_MAX, EXT_SPEED, EXT_ACCELERATION);
the gripper closes or opens in GRIPPER_TIME (constant, whatever the pose).

A *spot* is where the robot may stand at a table to grip or put a cup (the free parameters of Fig. 5.12): a
frame (ox, oy, ophi) whose origin is the point of the serving edge nearest the cup (or the put location) and
whose ophi faces the table, and the offsets `along` (to the left of ophi, SPOT_ALONG), `dist` (from the edge,
SPOT_DIST: the grip precondition of Sec. 5.5, 40-80 cm) and `heading` (base heading minus ophi,
SPOT_HEADING). Any pose is a spot with zero offsets in its own frame: the robot's start is one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

# --- rooms (m) -------------------------------------------------------------------------------------------
ROOM_LENGTH = 10.0  # m, x in [0, 10]
ROOM_WIDTH = 6.0  # m, y in [0, 6]
DIVIDER_X = 5.0  # m, the wall between room A (west) and room B (east)
DOOR_Y = 3.0  # m, centre of the door in the divider
DOOR_WIDTH = 1.3  # m
WALL_THICKNESS = 0.1  # m

# --- furniture -------------------------------------------------------------------------------------------
TABLE_LENGTH = 1.4  # m, along the serving edge
TABLE_DEPTH = 0.7  # m
TABLE_HEIGHT = 0.75  # m (the arm works at this height; not simulated in the top view)
ISLAND = (2.5, 3.3, 1.2, 0.8)  # m, fixed kitchen island in room A: centre x, y, size x, y
# nominal table poses (centre x, y, phi: the direction the robot faces when facing the serving edge)
TABLE1 = (2.5, ROOM_WIDTH - TABLE_DEPTH / 2, math.pi / 2)  # against room A's north wall
TABLE2 = (ROOM_LENGTH - TABLE_DEPTH / 2, 3.0, 0.0)  # against room B's east wall
TABLE1_SHIFT = 1.0  # m, table1's random displacement along its wall (uniform +-)
TABLE2_SHIFT = 1.2  # m, table2's random displacement along its wall (uniform +-)
CUP_RADIUS = 0.04  # m
CUP_MASS = 0.25  # kg
CUP_ALONG = 0.55  # m, a cup's random position along its table (uniform +- from the table centre)
CUP_INSET = (0.1, 0.3)  # m, a cup's random distance from the serving edge
CUP_SEPARATION = 0.25  # m, two cups on one table lie at least this far apart along it
START_REGION = ((0.8, 4.2), (0.8, 1.8))  # m, the robot's random start (x range, y range), any heading

# --- base (B21-like) -------------------------------------------------------------------------------------
BASE_RADIUS = 0.26  # m
V_MAX = 0.6  # m/s
W_MAX = 1.0  # rad/s
A_MAX = 0.5  # m/s^2
ALPHA_MAX = 1.5  # rad/s^2
CLEARANCE = 0.12  # m, the route planner keeps the base this far from furniture and walls
# The cruise speed of a navigate (Ch. 8.1: a free parameter that trades time for energy): the drive's governor
# holds the base at most at it, below the command's noise, while pure pursuit commands its usual speeds (up to
# V_MAX). Governed below what pursuit asks for, the base runs smooth; at V_MAX it follows the noisy command.
CRUISE = (0.3, V_MAX)  # m/s

# --- arm ---------------------------------------------------------------------------------------------------
SHOULDER_OFFSET = 0.15  # m, shoulder ahead of the base centre
PAN_LIMIT = 2.0  # rad
PAN_SPEED = 0.6  # rad/s
PAN_ACCELERATION = 1.2  # rad/s^2
EXT_REST = 0.3  # m, the tucked (carrying) extension
EXT_MAX = 1.3  # m
EXT_SPEED = 0.15  # m/s
EXT_ACCELERATION = 0.3  # m/s^2
GRIPPER_TIME = 1.5  # s, closing or opening the gripper

# --- spots (Fig. 5.12's ranges) ----------------------------------------------------------------------------
SPOT_ALONG = (-0.5, 0.5)  # m
SPOT_DIST = (0.4, 0.8)  # m, base centre to the serving edge (the grip precondition)
SPOT_HEADING = (-1.0, 1.0)  # rad

# --- the door as a way-point (Sec. 5.5: "the velocity and orientation at way-points are also not fixed") -----
# A door spot is a frame at the door's centre facing through it (east from room A, west from room B) with the
# offsets along (across the door), dist = 0 (on the divider's line) and heading, and the speed v at which the
# base passes it: free in these ranges, so that refinement decides where, in which direction and how fast the
# base crosses. A spot at a table has v = 0 (the base stops to grip or put).
DOOR_ALONG = (-0.2, 0.2)  # m, the door's half width less the base's radius and a margin
DOOR_HEADING = (-0.6, 0.6)  # rad, with DOOR_ALONG: the straight line through the door clears its posts
PASS_SPEED = (0.0, V_MAX)  # m/s


def door_frame(eastward: bool) -> tuple[float, float, float]:
    """The frame (ox, oy, ophi) of a door spot: the door's centre, facing east (from room A) or west."""
    return DIVIDER_X, DOOR_Y, 0.0 if eastward else math.pi


def wrap(angle: float) -> float:
    """The angle normalized to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def spot_pose(ox: float, oy: float, ophi: float, along: float, dist: float, heading: float
              ) -> tuple[float, float, float]:
    """The base pose (x, y, phi) of a spot: `dist` back from the frame's origin against ophi, `along` to the
    left of ophi, heading ophi + heading."""
    c, s = math.cos(ophi), math.sin(ophi)
    return ox - dist * c - along * s, oy - dist * s + along * c, wrap(ophi + heading)


def spot_offsets(frame: tuple, pose: tuple) -> tuple:
    """The offsets (along, dist, heading) of base pose (x, y, phi) in spot frame (ox, oy, ophi): spot_pose's
    inverse, so that spot_pose(*frame, *spot_offsets(frame, pose)) == pose. Numbers or arrays (numpy)."""
    ox, oy, ophi = frame
    c, s = np.cos(ophi), np.sin(ophi)
    dx, dy = pose[0] - ox, pose[1] - oy
    return -s * dx + c * dy, -(c * dx + s * dy), wrap(pose[2] - ophi)


@dataclass(frozen=True)
class Box:
    """A static rectangle: centre, half sizes along its own axes, rotation (rad)."""

    cx: float
    cy: float
    hx: float
    hy: float
    angle: float = 0.0

    def corners(self, grow: float = 0.0) -> list[tuple[float, float]]:
        c, s = math.cos(self.angle), math.sin(self.angle)
        hx, hy = self.hx + grow, self.hy + grow
        return [(self.cx + c * dx - s * dy, self.cy + s * dx + c * dy)
                for dx, dy in ((hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy))]

    def distance(self, x: float, y: float) -> float:
        """Distance from (x, y) to the box (0 inside)."""
        c, s = math.cos(self.angle), math.sin(self.angle)
        dx, dy = x - self.cx, y - self.cy
        u, w = abs(c * dx + s * dy) - self.hx, abs(-s * dx + c * dy) - self.hy
        return math.hypot(max(u, 0.0), max(w, 0.0))

    def contains(self, x: float, y: float) -> bool:
        return self.distance(x, y) == 0.0


def table_box(x: float, y: float, phi: float) -> Box:
    """The box of a table whose centre is (x, y) and whose serving edge faces -phi (the robot faces phi)."""
    return Box(x, y, TABLE_DEPTH / 2, TABLE_LENGTH / 2, phi)


def serving_frame(table: tuple[float, float, float], px: float, py: float) -> tuple[float, float, float]:
    """The spot frame (ox, oy, ophi) of point (px, py) on a table (x, y, phi): its foot on the serving edge."""
    x, y, phi = table
    c, s = math.cos(phi), math.sin(phi)
    ex, ey = x - c * TABLE_DEPTH / 2, y - s * TABLE_DEPTH / 2  # middle of the serving edge
    along = -s * (px - ex) + c * (py - ey)
    return ex - s * along, ey + c * along, phi


def table_point(table: tuple[float, float, float], along: float, inset: float) -> tuple[float, float]:
    """The point `along` from the table's centre line and `inset` in from its serving edge."""
    x, y, phi = table
    c, s = math.cos(phi), math.sin(phi)
    depth = -TABLE_DEPTH / 2 + inset
    return x + c * depth - s * along, y + s * depth + c * along


def outer_walls() -> list[Box]:
    t, L, Wd = WALL_THICKNESS / 2, ROOM_LENGTH, ROOM_WIDTH
    return [Box(L / 2, -t, L / 2 + 2 * t, t), Box(L / 2, Wd + t, L / 2 + 2 * t, t),
            Box(-t, Wd / 2, t, Wd / 2), Box(L + t, Wd / 2, t, Wd / 2)]


def divider() -> list[Box]:
    """The wall between the rooms, as the two boxes beside its door."""
    t, Wd = WALL_THICKNESS / 2, ROOM_WIDTH
    lower = DOOR_Y - DOOR_WIDTH / 2
    upper = DOOR_Y + DOOR_WIDTH / 2
    return [Box(DIVIDER_X, lower / 2, t, lower / 2), Box(DIVIDER_X, (upper + Wd) / 2, t, (Wd - upper) / 2)]


def walls() -> list[Box]:
    """The outer walls and the divider with its door, as boxes."""
    return [*outer_walls(), *divider()]


def island() -> Box:
    x, y, sx, sy = ISLAND
    return Box(x, y, sx / 2, sy / 2)


def nominal_obstacles() -> list[Box]:
    """The map the route features are computed on: the divider and the island. The tables stand against the
    walls, where no route between spots passes, and a straight line between two points of the (convex) room
    never crosses its outer walls, so neither can lengthen a route."""
    return [*divider(), island()]
