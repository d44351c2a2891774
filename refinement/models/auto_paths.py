"""Generated features of a path of bounded curvature (Sec. 4.1.1), for an action whose start and goal groups both
declare a pose in a plane (two lengths of one unit and a heading): the length of the shortest forward path with a
least turning radius (a Dubins path, sims.dubins) and the length of its arcs, as expressions (`dubins`,
`dubins_arcs`) that a model file stores and the certified optimizer bounds.

A vehicle that cannot turn on the spot drives such a path, but neither its turning radius nor the point it turns
about is declared: the point may lie behind the pose the action is given (a tool or a load carried ahead of the
axle), and the action may end with a straight run onto its goal (a path planned to a pre-pose behind it). All
three are constants discovered from the experience, as the transfer limits are: the radius r and the distances
behind the start and the goal pose under which the path's length and arcs fit the durations best by a line
(driving time is about straight / top speed + arcs / speed on an arc), on a coarse grid in proportion to the
typical distance and then refined (Nelder-Mead). A robot that turns on the spot drives the straight line and turns
at its ends instead: the path is offered only where it explains the durations clearly better (by MIN_GAIN) than the
same line on the distance and those two turns, candidates of their own (on a bundled base that turns on the spot,
the path offered anyway made forward selection start from it and end worse).

A vehicle in a walled workspace plans the shortest path that stays inside it (`dubins_inside`,
sims.dubins_inside): near a wall, a longer word than the free shortest one. Where the walls are is not declared
either; the region the positions of the experience occupy (the start's and the goal's), widened by a margin, stands
for them. The margin is discovered with the radius and the distances behind the poses refitted (fit_region): the
line there adds the square root of the path's straight part, the time of a run from rest to rest under bounded
acceleration (a vehicle that brakes on the way is not as fast over a short straight as over a long one), with
which the refitted constants came out nearer the true ones on a bundled robot whose controller plans inside its
walls (a radius of 0.39 to 0.40 m for its 0.4 m, its walls within 0.05 m). The region is offered only where it
explains the durations better (by REGION_GAIN) than the same path without it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize
from tailor.refinement.models.expressions import Expr, const, node
from tailor.sims import dubins, dubins_inside

RADII = (0.02, 0.05, 0.1, 0.2, 0.35)  # turning radii tried, times the typical distance between start and goal
BACKS = (0.0, 0.05, 0.15, 0.3)  # distances of the turning point behind a pose tried, likewise
FIT_ROWS = 1000  # examples the constants are fitted on (three constants need few)
MIN_GAIN = 0.1  # the path's line must err this much less than the line on the distance and the turns at its ends
MARGINS = (0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0)  # margins of the region tried, times the radius (none beyond 4: no
# path strays further from its ends, sims.dubins_inside.FAR)
REGION_GAIN = 0.05  # the path inside the region must err this much less than the same path without it


@dataclass(frozen=True)
class Curvature:
    """A discovered turning radius and the distances behind the start and the goal pose the path runs between,
    with the mean absolute error of the line that fits the durations on the path's length and arcs, and of the
    line on the straight distance and the turns at its ends (toward the goal, and onto its heading)."""

    radius: float
    start_back: float
    goal_back: float
    error: float
    straight_error: float

    @property
    def pays(self) -> bool:
        """Whether the path explains the durations clearly better than turning on the spot does."""
        return self.error < (1.0 - MIN_GAIN) * self.straight_error


def _ends(dx, dy, heading, goal_heading, start_back: float, goal_back: float) -> tuple[np.ndarray, np.ndarray]:
    """The start and goal poses (rows) of the path: each pose's point moved back along its heading."""
    start = np.column_stack([-start_back * np.cos(heading), -start_back * np.sin(heading), heading])
    goal = np.column_stack([dx - goal_back * np.cos(goal_heading), dy - goal_back * np.sin(goal_heading), goal_heading])
    return start, goal


def line_error(columns: list[np.ndarray], durations: np.ndarray) -> float:
    """Mean absolute error of the least-squares line of the durations on the columns (and a constant)."""
    A = np.column_stack([*columns, np.ones_like(durations)])
    coef = np.linalg.lstsq(A, durations, rcond=None)[0]
    return float(np.mean(np.abs(A @ coef - durations)))


def fit_curvature(dx: np.ndarray, dy: np.ndarray, heading: np.ndarray, goal_heading: np.ndarray,
                  durations: np.ndarray) -> Curvature:
    """The radius and the distances behind the poses (the goal at (dx, dy) from the start) under which the
    shortest path's length and arcs fit the durations best by a line (least absolute error of a least-squares
    fit), rounded to three significant digits (short constants in the model file)."""
    rows = slice(0, FIT_ROWS)
    dx, dy, heading, goal_heading, durations = (np.asarray(a, dtype=float)[rows]
                                                for a in (dx, dy, heading, goal_heading, durations))
    typical = float(np.median(np.hypot(dx, dy))) or 1.0

    def error(radius: float, start_back: float, goal_back: float) -> float:
        if not radius > 0.0 or start_back < 0.0 or goal_back < 0.0:
            return np.inf
        length, arcs = dubins.shortest(*_ends(dx, dy, heading, goal_heading, start_back, goal_back), radius)
        if not np.all(np.isfinite(length)):
            return np.inf
        return line_error([length, arcs], durations)

    grid = [(error(typical * r, typical * a, typical * b), typical * r, typical * a, typical * b)
            for r in RADII for a in BACKS for b in BACKS]
    best = min(grid)
    _, r, a, b = best

    def moved(z: np.ndarray) -> float:
        return error(r * np.exp(z[0]), a + typical * z[1], b + typical * z[2])

    found = minimize(moved, np.zeros(3), method="Nelder-Mead",
                     options={"xatol": 1e-3, "fatol": 1e-6, "maxfev": 90, "initial_simplex": np.array(
                         [[0.0, 0.0, 0.0], [0.3, 0.0, 0.0], [0.0, 0.05, 0.0], [0.0, 0.0, 0.05]])})
    if found.fun < best[0]:
        r, a, b = r * np.exp(found.x[0]), a + typical * found.x[1], b + typical * found.x[2]

    def short(value: float) -> float:  # (a distance below a thousandth of the typical one is none)
        return float(f"{value:.3g}") if value > 1e-3 * typical else 0.0

    r, a, b = float(f"{r:.3g}"), short(a), short(b)
    bearing = np.arctan2(dy, dx)
    turns = [np.abs(np.mod(angle + np.pi, 2.0 * np.pi) - np.pi) for angle in (bearing - heading, goal_heading - bearing)]
    return Curvature(r, a, b, error(r, a, b), line_error([np.hypot(dx, dy), *turns], durations))


def _back(offset: Expr, distance: float, heading: Expr, along) -> Expr:
    """`offset` less `distance` times cos (or sin) of `heading`; `offset` itself where the distance is 0."""
    return offset if distance == 0.0 else node("sub", offset, node("mul", const(distance), node(along, heading)))


def path_expressions(dx: Expr, dy: Expr, heading: Expr, goal_heading: Expr, fit: Curvature) -> tuple[Expr, Expr]:
    """The expressions of the path's length and of its arcs' length: `dubins` and `dubins_arcs` from the start
    pose moved back by fit.start_back to the goal pose moved back by fit.goal_back."""
    if fit.start_back:  # the goal relative to the start's turning point: dx + start_back cos(heading), ...
        dx = node("add", dx, node("mul", const(fit.start_back), node("cos", heading)))
        dy = node("add", dy, node("mul", const(fit.start_back), node("sin", heading)))
    dx, dy = _back(dx, fit.goal_back, goal_heading, "cos"), _back(dy, fit.goal_back, goal_heading, "sin")
    args = (dx, dy, heading, goal_heading, const(fit.radius))
    return node("dubins", *args), node("dubins_arcs", *args)


@dataclass(frozen=True)
class Region:
    """A path's constants refitted with the region it stays inside, (xmin, xmax, ymin, ymax): the positions' extent
    widened by `margin`; the error of the line on its length, arcs and the square root of its straight part, and of
    the same line on the path with the same constants and no region."""

    radius: float
    start_back: float
    goal_back: float
    margin: float
    region: tuple[float, float, float, float]
    error: float
    free_error: float

    @property
    def pays(self) -> bool:
        """Whether the region explains the durations clearly better than the free path does."""
        return self.error < (1.0 - REGION_GAIN) * self.free_error


def _braking_line_error(length: np.ndarray, arcs: np.ndarray, durations: np.ndarray) -> float:
    return line_error([length, arcs, np.sqrt(np.maximum(length - arcs, 0.0))], durations)


def fit_region(x: np.ndarray, y: np.ndarray, heading: np.ndarray, xg: np.ndarray, yg: np.ndarray,
               goal_heading: np.ndarray, durations: np.ndarray, fit: Curvature) -> Region:
    """The margin of the region the positions (x, y) and (xg, yg) occupy, and the path's radius and distances
    behind the poses (from `fit`'s), under which the path inside that region fits the durations best by a line
    (_braking_line_error): on the margins MARGINS, then refined together (Nelder-Mead) where the best margin
    already gains half REGION_GAIN; rounded to three significant digits. The extent is the positions' over every
    row, the fit on the first FIT_ROWS."""
    x, y, heading, xg, yg, goal_heading, durations = (np.asarray(a, dtype=float)
                                                      for a in (x, y, heading, xg, yg, goal_heading, durations))
    extent = (min(x.min(), xg.min()), max(x.max(), xg.max()), min(y.min(), yg.min()), max(y.max(), yg.max()))
    rows = slice(0, FIT_ROWS)
    x, y, heading, xg, yg, goal_heading, durations = (a[rows] for a in (x, y, heading, xg, yg, goal_heading,
                                                                         durations))

    def region_of(margin: float) -> tuple[float, float, float, float]:
        return tuple(float(f"{v:.3g}") for v in (extent[0] - margin, extent[1] + margin, extent[2] - margin,
                                                 extent[3] + margin))

    def ends(start_back: float, goal_back: float) -> tuple[np.ndarray, np.ndarray]:
        return (np.column_stack([x - start_back * np.cos(heading), y - start_back * np.sin(heading), heading]),
                np.column_stack([xg - goal_back * np.cos(goal_heading), yg - goal_back * np.sin(goal_heading),
                                 goal_heading]))

    def error(radius: float, start_back: float, goal_back: float, margin: float | None) -> float:
        if not radius > 0.0 or start_back < 0.0 or goal_back < 0.0 or (margin is not None and margin < 0.0):
            return np.inf
        start, goal = ends(start_back, goal_back)
        if margin is None:
            length, arcs = dubins.shortest(start, goal, radius)
        else:
            length, arcs = dubins_inside.shortest_inside(start, goal, radius, region_of(margin))
        return _braking_line_error(length, arcs, durations) if np.all(np.isfinite(length)) else np.inf

    r, a, b = fit.radius, fit.start_back, fit.goal_back
    grid, m = min((error(r, a, b, r * share), r * share) for share in MARGINS)
    free = error(r, a, b, None)
    if not grid < (1.0 - 0.5 * REGION_GAIN) * free:  # no sign of walls: not refined (it would not pay)
        return Region(r, a, b, float(f"{m:.3g}"), region_of(m), grid, free)
    scale = max(r, 1e-9)
    found = minimize(lambda z: error(r * np.exp(z[0]), a + scale * z[1], b + scale * z[2], m + scale * z[3]),
                     np.zeros(4), method="Nelder-Mead",
                     options={"xatol": 1e-3, "fatol": 1e-6, "maxfev": 120, "initial_simplex": np.array(
                         [[0.0, 0.0, 0.0, 0.0], [0.2, 0.0, 0.0, 0.0], [0.0, 0.3, 0.0, 0.0], [0.0, 0.0, 0.3, 0.0],
                          [0.0, 0.0, 0.0, 0.5]])})
    z = found.x if found.fun < error(r, a, b, m) else np.zeros(4)
    r, a, b, m = r * np.exp(z[0]), a + scale * z[1], b + scale * z[2], m + scale * z[3]
    r, a, b, m = (float(f"{v:.3g}") if v > 1e-3 * scale else 0.0 for v in (r, a, b, m))
    return Region(r, a, b, m, region_of(m), error(r, a, b, m), error(r, a, b, None))


def region_expressions(x: Expr, y: Expr, heading: Expr, xg: Expr, yg: Expr, goal_heading: Expr, fit: Region
                       ) -> tuple[Expr, Expr]:
    """The expressions of the path's length and of its arcs' length inside the region: `dubins_inside` and
    `dubins_inside_arcs` from the start pose moved back by fit.start_back to the goal pose moved back by
    fit.goal_back."""
    args = (_back(x, fit.start_back, heading, "cos"), _back(y, fit.start_back, heading, "sin"), heading,
            _back(xg, fit.goal_back, goal_heading, "cos"), _back(yg, fit.goal_back, goal_heading, "sin"),
            goal_heading, const(fit.radius), *(const(v) for v in fit.region))
    return node("dubins_inside", *args), node("dubins_inside_arcs", *args)
