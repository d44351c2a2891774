"""Dubins paths: the shortest forward path of bounded curvature between two poses (Dubins 1957).

A path is one of six words of three segments, each a left arc (L), a right arc (R) or a straight line (S):
LSL, RSR, LSR, RSL, RLR, LRL. Arcs have the minimum turning radius `radius`; segment lengths are in metres
(arc length, not angle). The formulas follow Shkel & Lumelsky (2001) in the normalized frame where the start
lies at the origin heading `alpha`, the goal at (d, 0) heading `beta`, and lengths are in units of the radius.
Pure-Python floats: the soccer controllers compute a path every control tick.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from operator import itemgetter

from tailor.sims.dubins import WORDS  # noqa: F401  (the order every word table here follows)

TWO_PI = 2.0 * math.pi
_EPS = 1e-9
_HALF_PI, _THREE_HALF_PI = 0.5 * math.pi, 1.5 * math.pi
TANGENT_SLACK = 1.0  # (radius units)^2: a mixed word whose circles overlap this little is taken as tangent


@dataclass(frozen=True)
class DubinsPath:
    """A Dubins path: its word, its three segment lengths (m) and the turning radius (m) of its arcs."""

    word: str
    lengths: tuple[float, float, float]
    radius: float
    exact: bool = True  # False: a mixed word taken as tangent within TANGENT_SLACK; it ends near the goal only

    @property
    def length(self) -> float:
        return self.lengths[0] + self.lengths[1] + self.lengths[2]

    def curvature(self, segment: int) -> float:
        """Signed curvature (1/m) of a segment: +1/radius left, -1/radius right, 0 straight."""
        kind = self.word[segment]
        return 1.0 / self.radius if kind == "L" else -1.0 / self.radius if kind == "R" else 0.0


def _mod(angle: float) -> float:
    return angle % TWO_PI


def _words(alpha: float, beta: float, d: float) -> list[tuple[str, float, float, float, bool]]:
    """(word, t, p, q, exact): the normalized segment lengths of each existing word, in WORDS order."""
    sa, ca, sb, cb = math.sin(alpha), math.cos(alpha), math.sin(beta), math.cos(beta)
    cab = math.cos(alpha - beta)
    out: list[tuple[str, float, float, float, bool]] = []

    p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sa - sb)  # LSL
    if p2 >= 0.0:
        th = math.atan2(cb - ca, d + sa - sb)
        out.append(("LSL", _mod(th - alpha), math.sqrt(p2), _mod(beta - th), True))
    p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sb - sa)  # RSR
    if p2 >= 0.0:
        th = math.atan2(ca - cb, d - sa + sb)
        out.append(("RSR", _mod(alpha - th), math.sqrt(p2), _mod(th - beta), True))
    # LSR and RSL: where the two circles (nearly) touch, the straight shrinks to nothing; a robot following
    # such a path drifts across that boundary with any noise, so a slight overlap counts as touching
    # instead of making the word vanish (and the robot switch to a path a loop longer).
    p2 = -2.0 + d * d + 2.0 * cab + 2.0 * d * (sa + sb)  # LSR
    if p2 >= -TANGENT_SLACK:
        p = math.sqrt(max(p2, 0.0))
        th = math.atan2(-ca - cb, d + sa + sb) - math.atan2(-2.0, p)
        out.append(("LSR", _mod(th - alpha), p, _mod(th - beta), p2 >= 0.0))
    p2 = -2.0 + d * d + 2.0 * cab - 2.0 * d * (sa + sb)  # RSL
    if p2 >= -TANGENT_SLACK:
        p = math.sqrt(max(p2, 0.0))
        th = math.atan2(ca + cb, d - sa - sb) - math.atan2(2.0, p)
        out.append(("RSL", _mod(alpha - th), p, _mod(beta - th), p2 >= 0.0))
    c = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sa - sb)) / 8.0  # RLR
    if abs(c) <= 1.0:
        p = _mod(TWO_PI - math.acos(c))
        t = _mod(alpha - math.atan2(ca - cb, d - sa + sb) + p / 2.0)
        out.append(("RLR", t, p, _mod(alpha - beta - t + p), True))
    c = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sb - sa)) / 8.0  # LRL
    if abs(c) <= 1.0:
        p = _mod(TWO_PI - math.acos(c))
        t = _mod(-alpha + math.atan2(-ca + cb, d + sa - sb) + p / 2.0)
        out.append(("LRL", t, p, _mod(beta - alpha - t + p), True))
    return out


Candidate = tuple[float, str, tuple[float, float, float], bool]  # (length, word, lengths, exact)


def candidates(start: tuple[float, float, float], goal: tuple[float, float, float],
               radius: float) -> list[Candidate]:
    """Every existing Dubins path from start (x, y, heading) to goal as (length, word, lengths, exact),
    shortest first: all_paths without building the DubinsPaths (the controllers need one path of six)."""
    if radius <= 0.0:
        raise ValueError(f"Dubins radius must be positive, got {radius}")
    dx, dy = goal[0] - start[0], goal[1] - start[1]
    d = math.hypot(dx, dy) / radius
    th = math.atan2(dy, dx) if d > _EPS else 0.0
    alpha, beta = _mod(start[2] - th), _mod(goal[2] - th)
    out = []
    full = TWO_PI - _EPS  # an arc of (almost) a full turn is numerically zero: it is zero
    for word, t, p, q, exact in _words(alpha, beta, d):
        lengths = ((0.0 if t > full else t) * radius, (0.0 if p > full and word[1] != "S" else p) * radius,
                   (0.0 if q > full else q) * radius)
        out.append((lengths[0] + lengths[1] + lengths[2], word, lengths, exact))
    out.sort(key=itemgetter(0))  # stable: equally long words stay in WORDS order
    return out


def all_paths(start: tuple[float, float, float], goal: tuple[float, float, float],
              radius: float) -> list[DubinsPath]:
    """Every existing Dubins path from start (x, y, heading) to goal, shortest first."""
    return [DubinsPath(word, lengths, radius, exact)
            for _, word, lengths, exact in candidates(start, goal, radius)]


def shortest_path(start: tuple[float, float, float], goal: tuple[float, float, float],
                  radius: float) -> DubinsPath:
    """The shortest Dubins path from start (x, y, heading) to goal (x, y, heading) with turning radius."""
    return all_paths(start, goal, radius)[0]


def sample(start: tuple[float, float, float], path: DubinsPath,
           step: float) -> list[tuple[float, float, float]]:
    """Poses along the path from start, about `step` metres apart, including both ends."""
    x, y, h = start
    poses = [(x, y, h)]
    for seg in range(3):
        length, k = path.lengths[seg], path.curvature(seg)
        n = max(1, int(math.ceil(length / step))) if length > 0.0 else 0
        for _ in range(n):
            x, y, h = advance((x, y, h), k, length / n)
            poses.append((x, y, h))
    return poses


def advance(pose: tuple[float, float, float], curvature: float, length: float) -> tuple[float, float, float]:
    """The pose after driving `length` metres at constant curvature from `pose`."""
    x, y, h = pose
    if abs(curvature) < 1e-12:
        return x + length * math.cos(h), y + length * math.sin(h), h
    h1 = h + curvature * length
    return (x + (math.sin(h1) - math.sin(h)) / curvature, y - (math.cos(h1) - math.cos(h)) / curvature, h1)


def bounds(start: tuple[float, float, float], path: DubinsPath) -> tuple[float, float, float, float]:
    """The axis-aligned bounding box (xmin, xmax, ymin, ymax) of the path driven from `start`, exactly."""
    return word_bounds(start, path.word, path.lengths, path.radius)


def word_bounds(start: tuple[float, float, float], word: str, lengths: tuple[float, float, float],
                radius: float) -> tuple[float, float, float, float]:
    """`bounds` of the path (word, lengths, radius): the segment ends and the arcs' extreme points."""
    x, y, h = start
    xs, ys = [x], [y]
    for kind, length in zip(word, lengths):
        k = 1.0 / radius if kind == "L" else -1.0 / radius if kind == "R" else 0.0
        sin_h, cos_h = math.sin(h), math.cos(h)
        ex, ey, eh = advance((x, y, h), k, length)
        xs.append(ex)
        ys.append(ey)
        if k != 0.0 and length > 0.0:  # the arc's points furthest east, north, west, south it passes
            r = 1.0 / abs(k)
            cx, cy = x - sin_h / k, y + cos_h / k
            theta0 = math.atan2(y - cy, x - cx)
            sweep = abs(k) * length
            if k > 0.0:
                east, north = (0.0 - theta0) % TWO_PI, (_HALF_PI - theta0) % TWO_PI
                west, south = (math.pi - theta0) % TWO_PI, (_THREE_HALF_PI - theta0) % TWO_PI
            else:
                east, north = (theta0 - 0.0) % TWO_PI, (theta0 - _HALF_PI) % TWO_PI
                west, south = (theta0 - math.pi) % TWO_PI, (theta0 - _THREE_HALF_PI) % TWO_PI
            if east <= sweep:
                xs.append(cx + r)
                ys.append(cy)
            if north <= sweep:
                xs.append(cx)
                ys.append(cy + r)
            if west <= sweep:
                xs.append(cx - r)
                ys.append(cy)
            if south <= sweep:
                xs.append(cx)
                ys.append(cy - r)
        x, y, h = ex, ey, eh
    return min(xs), max(xs), min(ys), max(ys)


def surely_inside(start: tuple[float, float, float], goal: tuple[float, float, float], radius: float,
                  box: tuple[float, float, float, float]) -> bool:
    """Whether every Dubins path between start and goal stays in the box: no point of one is further than
    4 radii from both ends (a CCC path's middle circle lies within 3 radii of its first circle's centre)."""
    m = 4.0 * radius
    xmin, xmax, ymin, ymax = box[0] + m, box[1] - m, box[2] + m, box[3] - m
    return (xmin <= start[0] <= xmax and ymin <= start[1] <= ymax
            and xmin <= goal[0] <= xmax and ymin <= goal[1] <= ymax)


def shortest_path_inside(start: tuple[float, float, float], goal: tuple[float, float, float], radius: float,
                         box: tuple[float, float, float, float]) -> DubinsPath:
    """The shortest Dubins path that stays inside box = (xmin, xmax, ymin, ymax); if none does, the one that
    leaves it least (a robot already outside the box gets back in as directly as it can)."""
    paths = candidates(start, goal, radius)
    if surely_inside(start, goal, radius, box):
        best = paths[0]
    else:
        best, best_excess = None, math.inf
        for path in paths:
            x0, x1, y0, y1 = word_bounds(start, path[1], path[2], radius)
            excess = max(box[0] - x0, x1 - box[1], box[2] - y0, y1 - box[3])
            if excess <= 0.0:
                best = path
                break
            if excess < best_excess - 1e-9:
                best, best_excess = path, excess
        if best is None:
            return None
    return DubinsPath(best[1], best[2], radius, best[3])


def distance_to(start: tuple[float, float, float], path: DubinsPath, point: tuple[float, float]) -> float:
    """The least distance from `point` to the path driven from `start` (exact: segments and arcs)."""
    return word_distance(start, path.word, path.lengths, path.radius, point)


def word_distance(start: tuple[float, float, float], word: str, lengths: tuple[float, float, float],
                  radius: float, point: tuple[float, float]) -> float:
    """`distance_to` the path (word, lengths, radius)."""
    px, py = point
    x, y, h = start
    best = math.hypot(px - x, py - y)
    for kind, length in zip(word, lengths):
        if length <= 0.0:
            continue
        k = 1.0 / radius if kind == "L" else -1.0 / radius if kind == "R" else 0.0
        sin_h, cos_h = math.sin(h), math.cos(h)
        ex, ey, eh = advance((x, y, h), k, length)
        best = min(best, math.hypot(px - ex, py - ey))
        if k == 0.0:
            t = (px - x) * cos_h + (py - y) * sin_h
            if 0.0 < t < length:
                best = min(best, abs(-(px - x) * sin_h + (py - y) * cos_h))
        else:
            cx, cy = x - sin_h / k, y + cos_h / k
            theta0 = math.atan2(y - cy, x - cx)
            offset = (math.atan2(py - cy, px - cx) - theta0) % TWO_PI
            if (offset if k > 0.0 else (TWO_PI - offset) % TWO_PI) <= abs(k) * length:
                best = min(best, abs(math.hypot(px - cx, py - cy) - 1.0 / abs(k)))
        x, y, h = ex, ey, eh
    return best
