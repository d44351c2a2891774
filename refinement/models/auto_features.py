"""Candidate features of an action generated from its declared quantities (Sec. 4.1.1), for any robot.

An action declares its parameters in two groups, observed (the start) and internal (the goal), each with a
quantity that the simulator declares as a unit and whether it is an angle. From that alone, with operators of
the kind the dissertation names, we build candidates that exploit the invariances the quantities imply:

- axes: a quantity both groups have (x and xg): the difference of like quantities (wrapped for angles), its
  absolute value and square root (translation and mirror invariance); where the goal group's quantities are
  not the start's, each goal quantity is paired with the start's of the same unit in declaration order;
- planes: two adjacent length axes of one unit (x, y): Euclidean distance and bearing; with a start angle
  (heading) the angle to the goal, the goal in the start's frame (along, |across|), and with the goal's angle
  of the same quantity the angle at the goal (normalised, signed as Table 4.1's), |its value|, their sum (the
  turning) and the relative heading (rotation and mirror invariance);
- speeds: a quantity in unit/s beside an axis of that unit (v beside x, or beside a plane's distance): the
  speeds signed toward the goal, their squares and product, and the transfer time of a double integrator
  (expression_maths.transfer) whose limits are constants discovered from the data; the largest transfer time
  of several axes (a move is as slow as its slowest part); maxima of like differences;
- paths: where the start and the goal are both poses in a plane (a heading each), the shortest path of bounded
  curvature between them (a Dubins path), its arcs and the transfer time along it, its radius and the points it
  turns about discovered from the data (auto_paths); where the durations show walls, the shortest such path that
  stays inside the region the positions occupy, its margin discovered likewise.
- via points: where the durations depend on where in the plane a move goes (a fixed scene), the points its
  paths pass through (a door, a corner to go round), discovered from the data: the length through each and
  the turns toward it and from it.
Which of them a model uses is chosen by cross-validated model-tree error (learning.feature_selection). The
rows of Table 4.1 that such a structure matches (the pose row, the reach row in a space of angles, a move along
one axis) are built the same way: `generic_row`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction

import numpy as np
from scipy.optimize import minimize

from tailor.refinement.models.auto_paths import (fit_curvature, fit_region, line_error, path_expressions,
                                                 region_expressions)
from tailor.refinement.models.expression_maths import evaluate, transfer
from tailor.refinement.models.model_tree import ModelTree
from tailor.refinement.models.expressions import (CONSTANT_ARGUMENTS, MAX_DEPTH, MAX_NODES, Expr, const, node, param,
                                                  parse_unit)
from tailor.sims.parallel import ordered_results
from tailor.sims.protocol import ActionSpec, Quantity

MAX_CANDIDATES = 160
DISCOVERY_ROWS = 1500  # examples the transfer limits are fitted on
SECOND = (("s", Fraction(1)),)


@dataclass(frozen=True)
class Parameter:
    name: str
    group: str  # "observed" or "internal"
    quantity: str
    unit: tuple
    angle: bool

    @property
    def speed_of(self) -> tuple | None:
        """The unit this is a speed of (m for m/s), or None."""
        exponents = dict(self.unit)
        if exponents.get("s", 0) != -1:
            return None
        return tuple((s, e) for s, e in self.unit if s != "s")


@dataclass(frozen=True)
class Candidate:
    name: str
    expression: Expr
    family: str  # what kind of operator built it (for the report)


@dataclass(frozen=True)
class Axis:
    """A like pair: the goal's value minus the start's (wrapped where the quantity is an angle)."""

    start: Parameter
    goal: Parameter
    difference: Expr
    label: str


def parameters_of(spec: ActionSpec, quantity: Callable[[str], Quantity]) -> list[Parameter]:
    out = []
    for group in ("observed", "internal"):
        names, quantities = spec.group(group)
        for name, q in zip(names, quantities):
            declared = quantity(q)
            out.append(Parameter(name, group, q, parse_unit(declared.unit), declared.angle))
    return out


FULL_TURN_SHARE = 0.9  # an angle whose values cover less of the circle is a bounded coordinate: not wrapped


def axes_of(params: list[Parameter], values: dict[str, np.ndarray] | None = None) -> list[Axis]:
    """Like pairs of start and goal parameters (not speeds): by quantity, else by unit in declaration order.
    The difference of two angles is wrapped, unless `values` (parameter columns of the experience) show the
    angle covering less than FULL_TURN_SHARE of the circle (a joint within its limits never goes round)."""
    start = [p for p in params if p.group == "observed" and p.speed_of is None]
    goal = [p for p in params if p.group == "internal" and p.speed_of is None]
    pairs, used = [], set()
    for g in goal:
        match = next((s for s in start if s.quantity == g.quantity and s.name not in used), None)
        if match is None:
            match = next((s for s in start if s.unit == g.unit and s.angle == g.angle and s.name not in used), None)
        if match is not None:
            used.add(match.name)
            pairs.append((match, g))
    axes = []
    for s, g in pairs:
        diff = node("sub", param(g.name), param(s.name))
        round_ = s.angle and (values is None or _span(values, s.name, g.name) >= FULL_TURN_SHARE * 2.0 * np.pi)
        axes.append(Axis(s, g, node("wrap", diff) if round_ else diff, s.name))
    return axes


def _span(values: dict[str, np.ndarray], *names: str) -> float:
    both = np.concatenate([values[n] for n in names])
    return float(np.ptp(both)) if both.size else 0.0


def speed_pairs(params: list[Parameter]) -> list[tuple[Parameter, Parameter | None]]:
    """(start speed, goal speed or None) per speed quantity of the start group."""
    start = [p for p in params if p.group == "observed" and p.speed_of is not None]
    goal = [p for p in params if p.group == "internal" and p.speed_of is not None]
    pairs, used = [], set()
    for s in start:
        g = next((g for g in goal if g.quantity == s.quantity and g.name not in used), None)
        used.add(g.name if g is not None else None)
        pairs.append((s, g))
    return pairs


def planes_of(axes: list[Axis]) -> list[tuple[Axis, Axis]]:
    """Adjacent (in declaration order) length axes of one unit: the coordinates of a point in a plane."""
    lengths = [a for a in axes if not a.start.angle and a.start.unit]
    return [(a, b) for a, b in zip(lengths, lengths[1:]) if a.start.unit == b.start.unit]


def _in_frame(dx: Expr, dy: Expr, heading: Expr) -> tuple[Expr, Expr]:
    """The move (dx, dy) in the frame of `heading`: along it, and |across| it (mirror invariance)."""
    along = node("add", node("mul", dx, node("cos", heading)), node("mul", dy, node("sin", heading)))
    across = node("abs", node("sub", node("mul", dy, node("cos", heading)), node("mul", dx, node("sin", heading))))
    return along, across


def _toward(speed: Expr, direction: Expr) -> Expr:
    """A speed signed toward the goal along `direction` (mirror invariance)."""
    return node("mul", speed, node("sgn", direction))


def generate(spec: ActionSpec, quantity: Callable[[str], Quantity], params: np.ndarray | None = None,
             durations: np.ndarray | None = None, jobs: int = 1) -> list[Candidate]:
    """Every candidate feature of `spec`'s action (deduplicated where `params`, rows of the action's parameters,
    are given; transfer limits, approach lengths, paths and via points discovered from them and their `durations`,
    those four families in `jobs` workers)."""
    ps = parameters_of(spec, quantity)
    values = None if params is None else {name: params[:, k] for k, name in enumerate(spec.parameters)}
    axes = axes_of(ps, values)
    speeds = speed_pairs(ps)
    out: list[Candidate] = []

    def add(name: str, e: Expr, family: str) -> None:
        out.append(Candidate(name, e, family))

    for p in ps:  # the raw parameters, as the black box knows them
        add(p.name, param(p.name), "parameter")
    for a in axes:
        add(f"d_{a.label}", a.difference, "difference")
        add(f"abs_d_{a.label}", node("abs", a.difference), "absolute difference")
        add(f"sqrt_d_{a.label}", node("sqrt", node("abs", a.difference)), "square root")
    for a, b in zip(axes, axes[1:]):
        if a.start.unit == b.start.unit and a.start.angle == b.start.angle:
            add(f"max_d_{a.label}_{b.label}", node("max", node("abs", a.difference), node("abs", b.difference)),
                "maximum")
    for s, g in speeds:
        add(f"abs_{s.name}", node("abs", param(s.name)), "absolute value")
        add(f"sq_{s.name}", node("square", param(s.name)), "product")
        if g is not None:
            add(f"abs_{g.name}", node("abs", param(g.name)), "absolute value")
            add(f"sq_{g.name}", node("square", param(g.name)), "product")
            add(f"{s.name}_{g.name}", node("mul", param(s.name), param(g.name)), "product")
    planes = planes_of(axes)
    headings = [p for p in ps if p.group == "observed" and p.angle]
    for a, b in planes:
        dx, dy = a.difference, b.difference
        tag = f"{a.label}_{b.label}"
        dist = node("hypot", dx, dy)
        bearing = node("atan2", dy, dx)
        add(f"dist_{tag}", dist, "Euclidean distance")
        add(f"bearing_{tag}", bearing, "angle")
        for h in headings:
            hx = param(h.name)
            signed = node("wrap", node("sub", bearing, hx))
            add(f"to_{tag}_{h.name}", node("abs", signed), "angle to the goal")
            add(f"signed_to_{tag}_{h.name}", signed, "angle to the goal")
            along, across = _in_frame(dx, dy, hx)
            add(f"along_{tag}_{h.name}", along, "goal in the start's frame")
            add(f"across_{tag}_{h.name}", across, "goal in the start's frame")
            for g in (p for p in ps if p.group == "internal" and p.angle and p.quantity == h.quantity):
                at = node("wrap", node("sub", param(g.name), bearing))
                add(f"at_{tag}_{g.name}", node("mul", node("sgn", signed), at), "angle at the goal")
                add(f"abs_at_{tag}_{g.name}", node("abs", at), "angle at the goal")
                add(f"turn_{tag}_{g.name}", node("add", node("abs", signed), node("abs", at)), "turning")
                add(f"rel_{h.name}_{g.name}", node("abs", node("wrap", node("sub", param(g.name), hx))),
                    "relative heading")
    # moves: a plane's distance (with the speed of its unit where there is one), the turn toward the goal, each
    # axis outside a plane (with its own speed where each has one): signed speeds, and the transfer time
    moves: list[tuple[str, Expr, Parameter | None, Parameter | None, tuple]] = []
    in_plane = {a.label for plane in planes for a in plane}
    for a, b in planes:
        fast = [(s, g) for s, g in speeds if s.speed_of == a.start.unit]
        s, g = fast[0] if len(fast) == 1 else (None, None)
        moves.append((f"{a.label}_{b.label}", node("hypot", a.difference, b.difference), s, g, a.start.unit))
        for h in headings[:1]:
            turn = node("wrap", node("sub", node("atan2", b.difference, a.difference), param(h.name)))
            moves.append((f"turn_{a.label}_{b.label}_{h.name}", turn, None, None, h.unit))
    for unit in dict.fromkeys(a.start.unit for a in axes if a.label not in in_plane):
        mine = [a for a in axes if a.start.unit == unit and a.label not in in_plane]
        fast = [(s, g) for s, g in speeds if s.speed_of == unit]
        if len(fast) == len(mine):
            moves += [(a.label, a.difference, s, g, unit) for a, (s, g) in zip(mine, fast)]
        else:
            moves += [(a.label, a.difference, None, None, unit) for a in mine]
    for label, d, s, g, unit in moves:
        if s is not None:
            add(f"{s.name}_toward_{label}", _toward(param(s.name), d), "speed toward the goal")
            if g is not None:
                add(f"{g.name}_toward_{label}", _toward(param(g.name), d), "speed toward the goal")
    if params is not None and durations is not None and len(params) >= 8:
        composed = _composed(ps, spec, params, durations)  # (the offset points _via_points starts from)
        calls = [(_transfers, moves, spec, params, durations), (_approaches, planes, ps, spec, params, durations),
                 (_paths, planes, ps, speeds, spec, params, durations),
                 (_via_points, planes, ps, spec, params, durations, out + composed)]
        transfers, approaches, paths, via = ordered_results(_discovered, calls, jobs)
        out += transfers + composed + approaches + paths + via
    return _distinct(out, spec, params)


def _discovered(family: Callable[..., list[Candidate]], *args) -> list[Candidate]:
    """The candidates of one family whose constants are discovered from the data (a call for the workers)."""
    return family(*args)


def _paths(planes, ps: list[Parameter], speeds, spec: ActionSpec, params: np.ndarray, durations: np.ndarray
           ) -> list[Candidate]:
    """Where the start and the goal each have a pose in the first plane (with each group's first angle of one
    quantity as its heading): the shortest path of bounded curvature between them, its radius and the points it
    turns about discovered (auto_paths), the length of its arcs, and the transfer time along it (with the plane's
    speeds where it has them, its limits discovered as _transfers' are); none where the durations show a robot
    that turns on the spot (Curvature.pays). Where keeping the path inside the region the positions occupy
    explains the durations better (auto_paths.Region.pays), that path and its arcs too."""
    start = next((p for p in ps if p.group == "observed" and p.angle), None)
    goal = next((p for p in ps if p.group == "internal" and p.angle and start is not None
                 and p.quantity == start.quantity), None)
    if not planes or goal is None:
        return []
    (a, b), rows = planes[0], slice(0, DISCOVERY_ROWS)
    columns = {name: values[rows] for name, values in zip(spec.parameters, params.T)}
    fit = fit_curvature(_evaluate(a.difference, columns), _evaluate(b.difference, columns), columns[start.name],
                        columns[goal.name], durations[rows])
    if not fit.pays:  # it turns on the spot: the distance and the turns at its ends are candidates already
        return []
    length, arcs = path_expressions(a.difference, b.difference, param(start.name), param(goal.name), fit)
    fast = [(s, g) for s, g in speeds if s.speed_of == a.start.unit]
    s, g = fast[0] if len(fast) == 1 else (None, None)
    v0, vg = _speed_or_zero(s), _speed_or_zero(g)
    vmax, amax = _discover([_evaluate(length, columns)], [_evaluate(v0, columns)], [_evaluate(vg, columns)],
                           durations[rows])
    tag = f"{a.label}_{b.label}_{start.name}_{goal.name}"
    out = [Candidate(f"dubins_{tag}", length, "path of bounded curvature"),
           Candidate(f"dubins_arcs_{tag}", arcs, "path of bounded curvature"),
           Candidate(f"dubins_transfer_{tag}", node("transfer", length, v0, vg, const(vmax), const(amax)),
                     "transfer time")]
    # the same path kept inside the region the positions occupy, where that explains the durations better
    everywhere = {name: params[:, k] for k, name in enumerate(spec.parameters)}
    positions = [everywhere[p.name] for p in (a.start, b.start, start, a.goal, b.goal, goal)]
    region = fit_region(*positions, durations, fit)
    if region.pays:
        inside, inside_arcs = region_expressions(*(param(p.name) for p in (a.start, b.start, start, a.goal, b.goal,
                                                                          goal)), region)
        out += [Candidate(f"dubins_inside_{tag}", inside, "path of bounded curvature in a region"),
                Candidate(f"dubins_inside_arcs_{tag}", inside_arcs, "path of bounded curvature in a region")]
    return out


def _approaches(planes, ps: list[Parameter], spec: ActionSpec, params: np.ndarray, durations: np.ndarray
                ) -> list[Candidate]:
    """Where the goal has a heading in a plane: the point a length r behind the goal along its heading (where a
    robot that cannot turn on the spot lines up), the distance, angles and turning toward it; r is discovered:
    of a few lengths in proportion to the typical distance, the one with which a small model tree on distance,
    turning and angle at it predicts the durations best (2-fold, absolute error)."""
    out: list[Candidate] = []
    columns = {name: values[:DISCOVERY_ROWS] for name, values in zip(spec.parameters, params.T)}
    target = durations[:DISCOVERY_ROWS]
    headings = [p for p in ps if p.group == "observed" and p.angle]
    for a, b in planes:
        for h in headings[:1]:
            for g in [p for p in ps if p.group == "internal" and p.angle and p.quantity == h.quantity][:1]:
                typical = float(np.median(_evaluate(node("hypot", a.difference, b.difference), columns))) or 1.0
                tried = []
                for share in (0.05, 0.1, 0.2, 0.3, 0.5):
                    r = float(f"{share * typical:.3g}")
                    features = _approach(a, b, h, g, r)
                    X = np.column_stack([_evaluate(features[k].expression, columns) for k in (0, 2, 3)])
                    tried.append((_two_fold_error(X, target), share, features))
                for _, _, features in sorted(tried, key=lambda t: t[:2])[:APPROACH_LENGTHS]:
                    out += features
    return out


def _two_fold_error(X: np.ndarray, y: np.ndarray) -> float:
    """Mean absolute error of a small model tree, each half predicted by one fitted on the other."""
    half = len(y) // 2
    error = 0.0
    for fit, test in ((slice(0, half), slice(half, None)), (slice(half, None), slice(0, half))):
        tree = ModelTree(min_samples_leaf=max(20, len(y) // 40)).fit(X[fit], y[fit])
        error += float(np.sum(np.abs(tree.predict(X[test]) - y[test])))
    return error / len(y)


APPROACH_LENGTHS = 1  # the best lengths r kept (two: measured worse on the bundled robots, selection drifts)


def _approach(a: Axis, b: Axis, h: Parameter, g: Parameter, r: float) -> list[Candidate]:
    goal_heading = param(g.name)
    dx = node("sub", a.difference, node("mul", const(r), node("cos", goal_heading)))
    dy = node("sub", b.difference, node("mul", const(r), node("sin", goal_heading)))
    bearing = node("atan2", dy, dx)
    signed = node("wrap", node("sub", bearing, param(h.name)))
    at = node("wrap", node("sub", goal_heading, bearing))
    tag = f"{a.label}_{b.label}_{g.name}_{r:g}".replace(".", "_")
    return [Candidate(f"behind_dist_{tag}", node("hypot", dx, dy), "point behind the goal"),
            Candidate(f"behind_to_{tag}", node("abs", signed), "point behind the goal"),
            Candidate(f"behind_at_{tag}", node("mul", node("sgn", signed), at), "point behind the goal"),
            Candidate(f"behind_turn_{tag}", node("add", node("abs", signed), node("abs", at)),
                      "point behind the goal")]


def _frame_point(group: list[Parameter], u: Expr, w: Expr) -> tuple[Expr, Expr]:
    """The point (u, w) of a group's frame (its first two lengths, turned by its first angle) in the world."""
    x, y, a = param(group[0].name), param(group[1].name), param(next(p for p in group if p.angle).name)
    c, s = node("cos", a), node("sin", a)
    return (node("add", x, node("sub", node("mul", u, c), node("mul", w, s))),
            node("add", y, node("add", node("mul", u, s), node("mul", w, c))))


def _composed(ps: list[Parameter], spec: ActionSpec, params: np.ndarray, durations: np.ndarray) -> list[Candidate]:
    """Where a group declares a pose (two lengths of one unit and an angle) and two more lengths of that unit
    (offsets in the pose's frame) and perhaps another angle (a heading offset), and the other group likewise or
    a point (two lengths of that unit, perhaps an angle: a pose without offsets): the offset point in the world,
    its distance and bearing from start to goal, the angle to it and at it; where only one group has offsets,
    also the goal in the start's frame (along, |across|). How the offsets sit in the frame (which is ahead, which
    to the side, their signs) is not declared: of the eight ways, the one whose distance fits the durations best
    by a line is taken."""
    groups = [_pose_group([p for p in ps if p.group == group and p.speed_of is None])
              for group in ("observed", "internal")]
    if None in groups or not any(g[0] for g in groups) or groups[0][1][0].unit != groups[1][1][0].unit:
        return []
    columns = {name: params[:, k] for k, name in enumerate(spec.parameters)}
    best = None
    for first, second in ((2, 3), (3, 2)):
        for su in (1.0, -1.0):
            for sw in (1.0, -1.0):
                points = []
                for offsets, lengths, angles in groups:
                    if not offsets:  # a point: where it is
                        points.append((param(lengths[0].name), param(lengths[1].name)))
                        continue
                    u, w = param(lengths[first].name), param(lengths[second].name)
                    u, w = (u if su > 0 else node("neg", u)), (w if sw > 0 else node("neg", w))
                    points.append(_frame_point(lengths + angles, u, w))
                dist = node("hypot", node("sub", points[1][0], points[0][0]), node("sub", points[1][1], points[0][1]))
                d = _evaluate(dist, columns)
                error = line_error([d], durations)
                if best is None or error < best[0]:
                    best = (error, points)
    (start, goal) = best[1]
    dx, dy = node("sub", goal[0], start[0]), node("sub", goal[1], start[1])
    headings = [_group_heading(angles) for _, _, angles in groups]
    bearing = node("atan2", dy, dx)
    out = [Candidate("offset_dist", node("hypot", dx, dy), "offset point")]
    one_sided = not all(offsets for offsets, _, _ in groups)
    if one_sided:
        out.append(Candidate("offset_bearing", bearing, "offset point"))
    if headings[0] is not None:
        signed = node("wrap", node("sub", bearing, headings[0]))
        out.append(Candidate("offset_to", node("abs", signed), "offset point"))
        if one_sided:
            along, across = _in_frame(dx, dy, headings[0])
            out += [Candidate("offset_signed_to", signed, "offset point"),
                    Candidate("offset_along", along, "offset point"),
                    Candidate("offset_across", across, "offset point")]
    if headings[1] is not None:
        at = node("wrap", node("sub", headings[1], bearing))
        if headings[0] is not None:
            out.append(Candidate("offset_at", node("mul", node("sgn", signed), at), "offset point"))
        out.append(Candidate("offset_abs_at", node("abs", at), "offset point"))
        if headings[0] is not None:
            out.append(Candidate("offset_turn", node("abs", node("wrap", node("sub", headings[1], headings[0]))),
                                 "offset point"))
    return out + [Candidate("offset_start_x", start[0], "offset point"),
                  Candidate("offset_start_y", start[1], "offset point"),
                  Candidate("offset_goal_x", goal[0], "offset point"),
                  Candidate("offset_goal_y", goal[1], "offset point")]


def _pose_group(mine: list[Parameter]) -> tuple[bool, list[Parameter], list[Parameter]] | None:
    """(has offsets, lengths, angles) of a group that is a pose with offsets (four lengths of one unit, an angle)
    or a point (two lengths of one unit, perhaps angles); None for any other group."""
    lengths = [p for p in mine if not p.angle]
    angles = [p for p in mine if p.angle]
    if len({p.unit for p in lengths}) != 1 or len(lengths) not in (2, 4) or (len(lengths) == 4 and not angles):
        return None
    return len(lengths) == 4, lengths, angles


def _group_heading(angles: list[Parameter]) -> Expr | None:
    """A group's heading in the world: its first angle plus its second (a heading offset) where it has one."""
    if not angles:
        return None
    return node("add", *(param(p.name) for p in angles[:2])) if len(angles) > 1 else param(angles[0].name)


def _speed_or_zero(p: Parameter | None) -> Expr:
    return param(p.name) if p is not None else const(0.0)


def _transfers(moves, spec: ActionSpec, params: np.ndarray, durations: np.ndarray) -> list[Candidate]:
    """Transfer times over each move (one axis, or a plane's distance, with its speeds if it has them), their
    limits discovered per unit by least squares against the durations; and the largest of them."""
    columns = {name: params[:, k] for k, name in enumerate(spec.parameters)}

    def values(e: Expr) -> np.ndarray:
        return _evaluate(e, columns)

    rows = slice(0, DISCOVERY_ROWS)  # the limits are fitted on the first rows: a few constants need few
    columns = {name: values_[rows] for name, values_ in columns.items()}
    durations = durations[rows]
    limits: dict = {}
    by_unit: dict = {}
    for label, d, s, g, unit in moves:
        by_unit.setdefault(unit, []).append((label, d, s, g))
    for unit, group in by_unit.items():
        ds = [values(d) for _, d, _, _ in group]
        v0s = [values(_speed_or_zero(s)) for _, _, s, _ in group]
        vgs = [values(_speed_or_zero(g)) for _, _, _, g in group]
        limits[unit] = _discover(ds, v0s, vgs, durations)
    out, times = [], []
    for unit, group in by_unit.items():
        vmax, amax = limits[unit]
        for label, d, s, g in group:
            e = node("transfer", d, _speed_or_zero(s), _speed_or_zero(g), const(vmax), const(amax))
            out.append(Candidate(f"transfer_{label}", e, "transfer time"))
            times.append(e)
    if len(times) >= 2:
        largest = times[0]
        for e in times[1:]:
            largest = node("max", largest, e)
        out.append(Candidate("transfer_max", largest, "maximum"))
    return out


def _discover(ds, v0s, vgs, durations) -> tuple[float, float]:
    """Speed and acceleration limits (shared by the axes of one unit) under which the largest transfer time
    fits the durations best by a line (least absolute error), on a coarse grid and then a fine one."""
    speeds = np.abs(np.concatenate([*v0s, *vgs]))
    distance = float(np.median(np.abs(np.concatenate(ds)))) or 1.0
    if speeds.size and speeds.max() > 0:
        scale_v = float(speeds.max())
    else:  # no speed declared: the distance covered per second of a typical execution
        scale_v = distance / max(float(np.median(durations)), 1e-9)
    scale_a = scale_v * scale_v / distance

    def error(vmax: float, amax: float) -> float:
        t = np.max([transfer(d, a, b, vmax, amax) for d, a, b in zip(ds, v0s, vgs)], axis=0)
        if not np.all(np.isfinite(t)):
            return np.inf
        return line_error([t], durations)

    best = min(((error(scale_v * fv, scale_a * fa), scale_v * fv, scale_a * fa)
                for fv in (0.5, 0.7, 0.85, 1.0, 1.15, 1.3, 1.6) for fa in (0.25, 0.5, 0.7, 1.0, 1.4, 2.0, 2.8, 4.0)))
    _, v, a = best
    found = minimize(lambda z: error(v * np.exp(z[0]), a * np.exp(z[1])), np.zeros(2), method="Nelder-Mead",
                     options={"xatol": 1e-3, "fatol": 1e-6, "maxfev": 80})
    v, a = (v, a) if not found.fun < best[0] else (v * np.exp(found.x[0]), a * np.exp(found.x[1]))
    return float(f"{v:.4g}"), float(f"{a:.4g}")  # short constants in the model file


VIA_POINTS = 3  # at most this many points the paths pass through
VIA_GAIN = 0.05  # a point is kept where its length and turns lower a small model tree's error by 5%
VIA_GRID = 1000  # points of the plane tried: a grid over the box of the start and goal points
VIA_LEAF_SHARE = 100  # the small model tree's leaves hold at least 1/VIA_LEAF_SHARE of the rows (10 at least)
VIA = "point the paths pass through"


def _via_points(planes, ps: list[Parameter], spec: ActionSpec, params: np.ndarray, durations: np.ndarray,
                found: list[Candidate]) -> list[Candidate]:
    """Where the durations depend on where in the plane a move goes (a fixed scene: a wall with a door, furniture
    to go round), the points its paths pass through, discovered from the data, and per point the length of the
    path through it, the turn toward it at the start and from it at the goal. Points are tried on a grid over the
    start and goal points; greedily, the one whose detour (beyond the straight move, in seconds by the line of
    least absolute error on the straight move's length and turns) best explains, row by row, what that line
    leaves of the durations, kept only where a small model tree on the straight move and the places predicts
    them better by VIA_GAIN (2-fold) with its length and turns besides; none where the durations do not depend on
    the place (a robot in an open field). The start and the goal are the offset points where _composed found them
    in `found`, else the first plane's."""
    if not planes:
        return []
    start, goal, start_heading, goal_heading = _world_poses(planes, ps, found)
    columns = {name: values[:DISCOVERY_ROWS] for name, values in zip(spec.parameters, params.T)}
    y = durations[:DISCOVERY_ROWS]
    s, g = [_evaluate(e, columns) for e in start], [_evaluate(e, columns) for e in goal]
    hs, hg = (None if h is None else _evaluate(h, columns) for h in (start_heading, goal_heading))
    straight = _path_columns(None, s, g, hs, hg)
    line = np.column_stack([np.ones(len(y)), straight])
    coefficients = _least_absolute(line, y)  # detours only lengthen a move: the line follows the straight ones
    residual = y - line @ coefficients
    xs, ys = np.concatenate([s[0], g[0]]), np.concatenate([s[1], g[1]])
    if not (np.ptp(xs) > 0 and np.ptp(ys) > 0):
        return []
    nx = max(2, round(float(np.sqrt(VIA_GRID * np.ptp(xs) / np.ptp(ys)))))
    grid = [(float(px), float(py)) for px in np.linspace(xs.min(), xs.max(), nx)
            for py in np.linspace(ys.min(), ys.max(), max(2, VIA_GRID // nx))]
    detours = np.array([(_path_columns(q, s, g, hs, hg) - straight) @ coefficients[1:] for q in grid])
    left = np.abs(residual)  # per row, what the points kept so far leave unexplained
    leaf = max(10, len(y) // VIA_LEAF_SHARE)
    X = np.column_stack([straight, *s, *g])  # the places too: a tree tells from them which moves pass a point
    error, kept = _split_error(X, y, leaf), []
    for _ in range(VIA_POINTS):
        j = int(np.argmax(np.maximum(0.0, left - np.abs(residual - detours)).mean(axis=1)))
        point = tuple(float(f"{v:.3g}") for v in grid[j])  # short constants in the model file
        trial = np.column_stack([X, _path_columns(point, s, g, hs, hg)])
        trial_error = _split_error(trial, y, leaf)
        if not trial_error < (1.0 - VIA_GAIN) * error:
            break
        X, error = trial, trial_error
        kept.append(point)
        left = np.minimum(left, np.abs(residual - detours[j]))
    out = []
    for k, (px, py) in enumerate(kept):
        cx, cy = const(px), const(py)
        out.append(Candidate(f"via{k}_length", node("add", node("hypot", node("sub", cx, start[0]),
                                                                  node("sub", cy, start[1])),
                                                     node("hypot", node("sub", goal[0], cx), node("sub", goal[1], cy))),
                             VIA))
        if start_heading is not None:
            toward = node("atan2", node("sub", cy, start[1]), node("sub", cx, start[0]))
            out.append(Candidate(f"via{k}_to", node("abs", node("wrap", node("sub", toward, start_heading))), VIA))
        if goal_heading is not None:
            onward = node("atan2", node("sub", goal[1], cy), node("sub", goal[0], cx))
            out.append(Candidate(f"via{k}_at", node("abs", node("wrap", node("sub", goal_heading, onward))), VIA))
    return out


def _world_poses(planes, ps: list[Parameter], found: list[Candidate]) -> tuple:
    """(start point, goal point, start heading, goal heading) as expressions, a heading None where its group has
    no angle: the offset points and headings of _composed where it found them, else the first plane's points and
    the first angle of each group (the goal's of the start's quantity)."""
    named = {c.name: c.expression for c in found}
    if "offset_goal_x" in named:
        headings = [_group_heading([p for p in ps if p.group == group and p.angle and p.speed_of is None])
                    for group in ("observed", "internal")]
        return ((named["offset_start_x"], named["offset_start_y"]),
                (named["offset_goal_x"], named["offset_goal_y"]), *headings)
    a, b = planes[0]
    h = next((p for p in ps if p.group == "observed" and p.angle), None)
    g = next((p for p in ps if p.group == "internal" and p.angle and h is not None and p.quantity == h.quantity),
             None)
    return ((param(a.start.name), param(b.start.name)), (param(a.goal.name), param(b.goal.name)),
            None if h is None else param(h.name), None if g is None else param(g.name))


def _path_columns(point, s, g, hs, hg) -> np.ndarray:
    """The path from s through `point` (None: straight) to g, as numbers: its length, the turn toward its first leg
    at the start (where hs, the start heading, is given) and from its last leg to the goal heading hg (where given)."""
    if point is None:
        length, toward = np.hypot(g[0] - s[0], g[1] - s[1]), np.arctan2(g[1] - s[1], g[0] - s[0])
        onward = toward
    else:
        px, py = point
        length = np.hypot(px - s[0], py - s[1]) + np.hypot(g[0] - px, g[1] - py)
        toward, onward = np.arctan2(py - s[1], px - s[0]), np.arctan2(g[1] - py, g[0] - px)
    turns = [toward - hs] if hs is not None else []
    turns += [hg - onward] if hg is not None else []
    return np.column_stack([length, *(np.abs((t + np.pi) % (2.0 * np.pi) - np.pi) for t in turns)])


def _least_absolute(A: np.ndarray, y: np.ndarray, rounds: int = 30) -> np.ndarray:
    """Coefficients of the line A @ c of least absolute error to y (iteratively reweighted least squares)."""
    weights = np.ones(len(y))
    for _ in range(rounds):
        c = np.linalg.lstsq(A * weights[:, None], y * weights, rcond=None)[0]
        weights = 1.0 / np.sqrt(np.maximum(np.abs(y - A @ c), 1e-3))
    return c


def _split_error(X: np.ndarray, y: np.ndarray, leaf: int) -> float:
    """Mean absolute error of a model tree with leaves of `leaf` rows, each half predicted by one fitted on the
    other; every column in each leaf's plane (a noise column's splits cannot drop the ones that matter)."""
    half = len(y) // 2
    error = 0.0
    for fit, test in ((slice(0, half), slice(half, None)), (slice(half, None), slice(0, half))):
        tree = ModelTree(min_samples_leaf=leaf, node_features="all").fit(X[fit], y[fit])
        error += float(np.sum(np.abs(tree.predict(X[test]) - y[test])))
    return error / len(y)


def candidate_columns(candidates: list[Candidate], parameters: tuple[str, ...], params: np.ndarray) -> np.ndarray:
    """(n, len(candidates)) the candidates' values on rows of the action's parameters."""
    columns = {name: params[:, k] for k, name in enumerate(parameters)}
    return np.column_stack([_evaluate(c.expression, columns) for c in candidates]) if candidates else \
        np.empty((len(params), 0))


def _evaluate(e: Expr, columns: dict[str, np.ndarray]) -> np.ndarray:
    if e.op == "param":
        return columns[e.name]
    if e.op == "const":
        return np.full(len(next(iter(columns.values()))), e.value)
    fixed = CONSTANT_ARGUMENTS.get(e.op, ())
    args = [_evaluate(a, columns) for k, a in enumerate(e.args) if k not in fixed]
    return evaluate(e.op, args, tuple(e.args[k].value for k in fixed))


def _distinct(candidates: list[Candidate], spec: ActionSpec, params: np.ndarray | None) -> list[Candidate]:
    """Unique names; where data is given, no constant, non-finite or duplicate column (the simpler one kept)."""
    seen_names, out = set(), []
    for c in candidates:  # (a model file must read back: within the limits of a stored expression)
        if c.expression.depth > MAX_DEPTH or c.expression.size > MAX_NODES:
            continue
        if c.name not in seen_names:
            seen_names.add(c.name)
            out.append(c)
    if params is None:
        return out[:MAX_CANDIDATES]
    columns = {name: params[:, k] for k, name in enumerate(spec.parameters)}
    kept, keys = [], {}
    for c in sorted(out, key=lambda c: c.expression.size):
        v = _evaluate(c.expression, columns)
        if not np.all(np.isfinite(v)) or np.ptp(v) <= 1e-12 * (1.0 + np.abs(v).max()):
            continue
        key = (np.round(v, 9) + 0.0).tobytes()  # (+ 0.0: -0.0 and 0.0 are one value)
        if key in keys:
            continue
        keys[key] = c.name
        kept.append(c)
    order = {c.name: k for k, c in enumerate(out)}
    return sorted(kept, key=lambda c: order[c.name])[:MAX_CANDIDATES]


def generic_row(spec: ActionSpec, quantity: Callable[[str], Quantity]) -> list[Candidate] | None:
    """Table 4.1's generic row that the action's structure matches, or None: the pose row (v, vg, dist,
    angle_to, angle_at) for a plane with start and goal headings; the reach row (dist, angle1, angle2, v, vg) for
    two angle axes with their speeds; a move along one axis (|d|, v and vg signed toward the goal)."""
    ps = parameters_of(spec, quantity)
    axes, speeds = axes_of(ps), speed_pairs(ps)
    planes = planes_of(axes)
    headings = [a for a in axes if a.start.angle]
    if planes and headings:
        (a, b), h = planes[0], headings[0]
        dx, dy = a.difference, b.difference
        bearing = node("atan2", dy, dx)
        signed = node("wrap", node("sub", bearing, param(h.start.name)))
        row = [Candidate("dist", node("hypot", dx, dy), "row"),
               Candidate("angle_to", node("abs", signed), "row"),
               Candidate("angle_at", node("mul", node("sgn", signed),
                                          node("wrap", node("sub", param(h.goal.name), bearing))), "row")]
        for s, g in speeds[:1]:
            row = [Candidate("v", param(s.name), "row")] + ([Candidate("vg", param(g.name), "row")] if g else []) + row
        return row
    angular = [a for a in axes if a.start.angle]
    fast = [(s, g) for s, g in speeds if g is not None]
    if len(angular) == 2 and len(fast) == 2 and len(axes) == 2:
        (a, b), ((sa, ga), (sb, gb)) = angular, fast
        direction = node("atan2", b.difference, a.difference)
        return [Candidate("dist", node("hypot", a.difference, b.difference), "row"),
                Candidate("angle1", node("wrap", node("sub", direction, node("atan2", param(sb.name), param(sa.name)))),
                          "row"),
                Candidate("angle2", node("wrap", node("sub", node("atan2", param(gb.name), param(ga.name)), direction)),
                          "row"),
                Candidate("v", node("hypot", param(sa.name), param(sb.name)), "row"),
                Candidate("vg", node("hypot", param(ga.name), param(gb.name)), "row")]
    if len(axes) == 1 and len(fast) == 1:
        a, (s, g) = axes[0], fast[0]
        return [Candidate("dist", node("abs", a.difference), "row"),
                Candidate("v", _toward(param(s.name), a.difference), "row"),
                Candidate("vg", _toward(param(g.name), a.difference), "row")]
    return None
