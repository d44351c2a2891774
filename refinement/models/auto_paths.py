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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize
from tailor.refinement.models.expressions import Expr, const, node
from tailor.sims import dubins

RADII = (0.02, 0.05, 0.1, 0.2, 0.35)  # turning radii tried, times the typical distance between start and goal
BACKS = (0.0, 0.05, 0.15, 0.3)  # distances of the turning point behind a pose tried, likewise
FIT_ROWS = 1000  # examples the constants are fitted on (three constants need few)
MIN_GAIN = 0.1  # the path's line must err this much less than the line on the distance and the turns at its ends


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
