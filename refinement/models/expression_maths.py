"""What each expression operator computes (numpy, row-wise) and its interval extension (a guaranteed enclosure
of its values over a box of its arguments), in one place so that the two cannot drift apart.

Values (x, y arrays):
  add, sub, mul       x + y, x - y, x * y
  div                 x / y, 0 where y == 0 (protected division)
  min, max            elementwise
  hypot               sqrt(x^2 + y^2)
  atan2               atan2(y, x) in [-pi, pi] (args: y first, as numpy)
  neg, abs, square    -x, |x|, x^2
  sqrt                sqrt(max(x, 0))
  wrap                x + 2 pi k in [-pi, pi) (norm() of Table 4.1)
  sgn                 -1 where x < 0, else +1 (sgn(0) = +1, as Table 4.1's sgn)
  sin, cos
  transfer            the least time of a double integrator from speed v0 to vg over displacement d with
                      |speed| <= vmax and |acceleration| <= amax (v0, vg clipped to +-vmax): bang, coast, bang
  dubins, dubins_arcs the shortest path of bounded curvature from the origin heading h to (dx, dy) heading hg
                      (sims.dubins): its length, its arcs' length
  dubins_inside(_arcs) the same from the pose (x, y, h) to (xg, yg, hg), the shortest that stays inside a
                      region (xmin, xmax, ymin, ymax) (sims.dubins_inside)
Bounds are sound for every box, widened outward by a few units in the last place for rounding; where an
operator's range over a box cannot be told cheaply, the bound is its whole range (wrap: [-pi, pi]).
"""

from __future__ import annotations

import numpy as np

from tailor.sims import dubins, dubins_inside
from tailor.sims.intervals import transfer_time_bounds
from tailor.sims.kinematics import transfer_time

PI, TWO_PI = np.pi, 2.0 * np.pi
_EPS = np.finfo(float).eps
_ULPS = 8.0  # outward widening of every computed bound, in units of the bound's magnitude times eps
TRANSFER_TOL = 1e-12  # the transfer time's tolerance for a cruise phase of zero length
# operators whose numpy values may be off by an amount not relative to the value, and by how much (times the
# magnitude of the argument, plus pi): widening beyond _ULPS
ABSOLUTE_SLACK = {"wrap": 1e3 * _EPS, "atan2": 1e3 * _EPS, "sin": 1e3 * _EPS, "cos": 1e3 * _EPS, "transfer": 1e-9}


def _protected_div(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    out = np.zeros(np.broadcast(x, y).shape)
    np.divide(x, y, out=out, where=(y != 0))
    return out


def transfer(d: np.ndarray, v0: np.ndarray, vg: np.ndarray, vmax: float, amax: float) -> np.ndarray:
    """Least duration of a move by displacement d from speed v0 to vg under |v| <= vmax, |a| <= amax
    (sims.kinematics.transfer_time)."""
    return transfer_time(d, v0, vg, vmax, amax, TRANSFER_TOL)


def _poses(dx, dy, heading, goal_heading) -> tuple:
    """The start pose at the origin and the goal pose, as sims.dubins takes them (rows, or (low, high) pairs)."""
    if isinstance(dx, tuple):
        zero = (np.zeros_like(dx[0]), np.zeros_like(dx[0]))
        return (zero, zero, heading), (dx, dy, goal_heading)
    dx, dy, heading, goal_heading = np.broadcast_arrays(dx, dy, heading, goal_heading)
    zero = np.zeros_like(dx, dtype=float)
    return np.column_stack([zero, zero, heading]), np.column_stack([dx, dy, goal_heading])


def evaluate(op: str, args: list[np.ndarray], constants: tuple[float, ...] = ()) -> np.ndarray:
    """The values of operator `op` on argument columns (constants: its constant arguments, for transfer)."""
    x = args[0]
    y = args[1] if len(args) > 1 else None
    with np.errstate(over="ignore", invalid="ignore"):
        match op:
            case "add":
                return x + y
            case "sub":
                return x - y
            case "mul":
                return x * y
            case "div":
                return _protected_div(x, y)
            case "min":
                return np.minimum(x, y)
            case "max":
                return np.maximum(x, y)
            case "hypot":
                return np.hypot(x, y)
            case "atan2":
                return np.arctan2(x, y)
            case "neg":
                return -x
            case "abs":
                return np.abs(x)
            case "square":
                return x * x
            case "sqrt":
                return np.sqrt(np.maximum(x, 0.0))
            case "wrap":
                return np.mod(x + PI, TWO_PI) - PI
            case "sgn":
                return np.where(x < 0.0, -1.0, 1.0)
            case "sin":
                return np.sin(x)
            case "cos":
                return np.cos(x)
            case "transfer":
                return transfer(x, y, args[2], *constants)
            case "dubins" | "dubins_arcs":
                length, arcs = dubins.shortest(*_poses(*args), constants[0])
                return length if op == "dubins" else arcs
            case "dubins_inside" | "dubins_inside_arcs":
                columns = np.broadcast_arrays(*args)
                start, goal = np.column_stack(columns[:3]), np.column_stack(columns[3:])
                length, arcs = dubins_inside.shortest_inside(start, goal, constants[0], constants[1:])
                return length if op == "dubins_inside" else arcs
    raise ValueError(f"unknown operator {op!r}")


# --- interval extensions ------------------------------------------------------------------------------------
def _widen(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Outward by a few ulps (rounding of numpy's own evaluation); NaN (inf - inf) becomes unbounded."""
    lo = np.where(np.isnan(lo), -np.inf, lo)
    hi = np.where(np.isnan(hi), np.inf, hi)
    with np.errstate(over="ignore", invalid="ignore"):
        lo = lo - _ULPS * _EPS * np.abs(lo) - 1e-300
        hi = hi + _ULPS * _EPS * np.abs(hi) + 1e-300
    return np.where(np.isnan(lo), -np.inf, lo), np.where(np.isnan(hi), np.inf, hi)


def _products(a: tuple, b: tuple) -> tuple[np.ndarray, np.ndarray]:
    with np.errstate(invalid="ignore", over="ignore"):
        corners = np.stack([a[0] * b[0], a[0] * b[1], a[1] * b[0], a[1] * b[1]])
    corners = np.where(np.isnan(corners), 0.0, corners)  # 0 * inf: the box's values are finite products
    return corners.min(axis=0), corners.max(axis=0)


def _abs(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    low = np.where(lo >= 0.0, lo, np.where(hi <= 0.0, -hi, 0.0))
    return low, np.maximum(np.abs(lo), np.abs(hi))


def _atan2(y: tuple, x: tuple) -> tuple[np.ndarray, np.ndarray]:
    """Corners where the box neither holds the origin nor meets the branch cut (y = 0, x < 0): then the angles
    over the box form an arc whose ends are corners (the tangents from the origin touch a box at corners)."""
    corners = np.stack([np.arctan2(yy, xx) for yy in y for xx in x])
    full = ((y[0] <= 0.0) & (y[1] >= 0.0)) & (x[0] <= 0.0)  # holds the origin, or meets the cut
    lo = np.where(full, -PI, corners.min(axis=0))
    hi = np.where(full, PI, corners.max(axis=0))
    return lo, hi


def _wrap(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A shift by a multiple of 2 pi where the box stays within one turn clear of the seam, else [-pi, pi]."""
    with np.errstate(invalid="ignore", over="ignore"):
        k = np.floor((lo + PI) / TWO_PI)
        a, b = lo - TWO_PI * k, hi - TWO_PI * k
        slack = 1e3 * _EPS * (np.abs(lo) + np.abs(hi) + PI)  # rounding of (x + pi) mod 2 pi near the seam
        inside = np.isfinite(a) & np.isfinite(b) & (a - slack > -PI) & (b + slack < PI)
    return np.where(inside, a, -PI), np.where(inside, b, PI)


def _reaches(lo: np.ndarray, hi: np.ndarray, phase: float) -> np.ndarray:
    """Whether [lo, hi] holds a point phase + 2 pi k (with a little slack: then it is taken to)."""
    with np.errstate(invalid="ignore", over="ignore"):
        slack = 1e3 * _EPS * (np.abs(lo) + np.abs(hi) + 1.0)
        first = np.ceil((lo - slack - phase) / TWO_PI)
        reached = phase + TWO_PI * first <= hi + slack
    return ~np.isfinite(lo) | ~np.isfinite(hi) | reached


def _sin(lo: np.ndarray, hi: np.ndarray, shift: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """sin over [lo, hi], or cos (shift pi/2: its extremes are sin's shifted; its ends are numpy's cos)."""
    function = np.cos if shift else np.sin
    with np.errstate(invalid="ignore"):
        ends = np.stack([function(lo), function(hi)])
    ends = np.where(np.isnan(ends), 0.0, ends)
    low = np.where(_reaches(lo + shift, hi + shift, -0.5 * PI), -1.0, ends.min(axis=0))
    high = np.where(_reaches(lo + shift, hi + shift, 0.5 * PI), 1.0, ends.max(axis=0))
    wide = ~(hi - lo < TWO_PI)
    return np.where(wide, -1.0, low), np.where(wide, 1.0, high)


def interval(op: str, args: list[tuple[np.ndarray, np.ndarray]], constants: tuple[float, ...] = ()
             ) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) of operator `op` over the boxes of its arguments' intervals, widened for rounding."""
    x = args[0]
    y = args[1] if len(args) > 1 else None
    with np.errstate(over="ignore", invalid="ignore"):
        match op:
            case "add":
                out = (x[0] + y[0], x[1] + y[1])
            case "sub":
                out = (x[0] - y[1], x[1] - y[0])
            case "mul":
                out = _products(x, y)
            case "div":
                apart = (y[0] > 0.0) | (y[1] < 0.0)
                zero = (y[0] == 0.0) & (y[1] == 0.0)
                safe = (np.where(apart, y[0], 1.0), np.where(apart, y[1], 1.0))
                lo, hi = _products(x, (1.0 / safe[1], 1.0 / safe[0]))
                out = (np.where(apart, lo, np.where(zero, 0.0, -np.inf)),
                       np.where(apart, hi, np.where(zero, 0.0, np.inf)))
            case "min":
                out = (np.minimum(x[0], y[0]), np.minimum(x[1], y[1]))
            case "max":
                out = (np.maximum(x[0], y[0]), np.maximum(x[1], y[1]))
            case "hypot":
                ax, ay = _abs(*x), _abs(*y)
                out = (np.hypot(ax[0], ay[0]), np.hypot(ax[1], ay[1]))
            case "atan2":
                out = _atan2(x, y)
            case "neg":
                out = (-x[1], -x[0])
            case "abs":
                out = _abs(*x)
            case "square":
                lo, hi = _abs(*x)
                out = (lo * lo, hi * hi)
            case "sqrt":
                out = (np.sqrt(np.maximum(x[0], 0.0)), np.sqrt(np.maximum(x[1], 0.0)))
            case "wrap":
                out = _wrap(*x)
            case "sgn":
                out = (np.where(x[0] >= 0.0, 1.0, -1.0), np.where(x[1] < 0.0, -1.0, 1.0))
            case "sin":
                out = _sin(*x)
            case "cos":
                out = _sin(*x, shift=0.5 * PI)
            case "transfer":
                out = transfer_time_bounds(x, y, args[2], *constants, TRANSFER_TOL)
            case "dubins" | "dubins_arcs":
                length, arcs = dubins.shortest_bounds(*_poses(*args), constants[0])
                out = length if op == "dubins" else arcs
            case "dubins_inside" | "dubins_inside_arcs":
                length, arcs = dubins_inside.shortest_inside_bounds(tuple(args[:3]), tuple(args[3:]), constants[0],
                                                                    constants[1:])
                out = length if op == "dubins_inside" else arcs
            case _:
                raise ValueError(f"unknown operator {op!r}")
    lo, hi = _widen(np.asarray(out[0], dtype=float), np.asarray(out[1], dtype=float))
    if op in ABSOLUTE_SLACK:  # rounding that is absolute, not relative to the result (near a zero of sin, say)
        scale = sum(np.abs(np.where(np.isfinite(a), a, 0.0)) for a in args[0]) + PI
        if op == "transfer":
            scale = 1.0 + np.abs(np.where(np.isfinite(hi), hi, 0.0))
        slack = ABSOLUTE_SLACK[op] * scale
        lo, hi = lo - slack, hi + slack
    if op in ("wrap", "atan2"):
        lo, hi = np.maximum(lo, -PI - 1e-12), np.minimum(hi, PI + 1e-12)
    elif op in ("sin", "cos"):
        lo, hi = np.maximum(lo, -1.0), np.minimum(hi, 1.0)
    elif op == "sgn":
        lo, hi = np.maximum(lo, -1.0), np.minimum(hi, 1.0)
    elif op in ("dubins", "dubins_arcs", "dubins_inside", "dubins_inside_arcs"):
        lo = np.maximum(lo, 0.0)
    return lo, hi
