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

TWO_PI = 2.0 * math.pi
WORDS = ("LSL", "RSR", "LSR", "RSL", "RLR", "LRL")
_EPS = 1e-9
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


def _words(alpha: float, beta: float, d: float) -> dict[str, tuple | None]:
    """Normalized segment lengths (t, p, q) of each word, None where the word does not exist."""
    sa, ca, sb, cb = math.sin(alpha), math.cos(alpha), math.sin(beta), math.cos(beta)
    cab = math.cos(alpha - beta)
    out: dict[str, tuple[float, float, float] | None] = {}

    p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sa - sb)  # LSL
    if p2 >= 0.0:
        th = math.atan2(cb - ca, d + sa - sb)
        out["LSL"] = (_mod(th - alpha), math.sqrt(p2), _mod(beta - th))
    else:
        out["LSL"] = None
    p2 = 2.0 + d * d - 2.0 * cab + 2.0 * d * (sb - sa)  # RSR
    if p2 >= 0.0:
        th = math.atan2(ca - cb, d - sa + sb)
        out["RSR"] = (_mod(alpha - th), math.sqrt(p2), _mod(th - beta))
    else:
        out["RSR"] = None
    # LSR and RSL: where the two circles (nearly) touch, the straight shrinks to nothing; a robot following
    # such a path drifts across that boundary with any noise, so a slight overlap counts as touching
    # instead of making the word vanish (and the robot switch to a path a loop longer).
    p2 = -2.0 + d * d + 2.0 * cab + 2.0 * d * (sa + sb)  # LSR
    if p2 >= -TANGENT_SLACK:
        p = math.sqrt(max(p2, 0.0))
        th = math.atan2(-ca - cb, d + sa + sb) - math.atan2(-2.0, p)
        out["LSR"] = (_mod(th - alpha), p, _mod(th - beta), p2 >= 0.0)
    else:
        out["LSR"] = None
    p2 = -2.0 + d * d + 2.0 * cab - 2.0 * d * (sa + sb)  # RSL
    if p2 >= -TANGENT_SLACK:
        p = math.sqrt(max(p2, 0.0))
        th = math.atan2(ca + cb, d - sa - sb) - math.atan2(2.0, p)
        out["RSL"] = (_mod(alpha - th), p, _mod(beta - th), p2 >= 0.0)
    else:
        out["RSL"] = None
    c = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sa - sb)) / 8.0  # RLR
    if abs(c) <= 1.0:
        p = _mod(TWO_PI - math.acos(c))
        t = _mod(alpha - math.atan2(ca - cb, d - sa + sb) + p / 2.0)
        out["RLR"] = (t, p, _mod(alpha - beta - t + p))
    else:
        out["RLR"] = None
    c = (6.0 - d * d + 2.0 * cab + 2.0 * d * (sb - sa)) / 8.0  # LRL
    if abs(c) <= 1.0:
        p = _mod(TWO_PI - math.acos(c))
        t = _mod(-alpha + math.atan2(-ca + cb, d + sa - sb) + p / 2.0)
        out["LRL"] = (t, p, _mod(beta - alpha - t + p))
    else:
        out["LRL"] = None
    return out


def _clean(t: float) -> float:
    """An arc of (almost) a full turn that is numerically zero is zero."""
    return 0.0 if t > TWO_PI - _EPS else t


def all_paths(start: tuple[float, float, float], goal: tuple[float, float, float],
              radius: float) -> list[DubinsPath]:
    """Every existing Dubins path from start (x, y, heading) to goal, shortest first."""
    if radius <= 0.0:
        raise ValueError(f"Dubins radius must be positive, got {radius}")
    dx, dy = goal[0] - start[0], goal[1] - start[1]
    d = math.hypot(dx, dy) / radius
    th = math.atan2(dy, dx) if d > _EPS else 0.0
    alpha, beta = _mod(start[2] - th), _mod(goal[2] - th)
    paths = []
    for word, seg in _words(alpha, beta, d).items():
        if seg is not None:
            t, p, q = seg[:3]
            arc_p = p if word[1] == "S" else _clean(p)
            exact = seg[3] if len(seg) > 3 else True
            paths.append(DubinsPath(word, (_clean(t) * radius, arc_p * radius, _clean(q) * radius), radius, exact))
    paths.sort(key=lambda path: path.length)
    return paths


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
    pose = start
    xs, ys = [start[0]], [start[1]]
    for seg in range(3):
        length, k = path.lengths[seg], path.curvature(seg)
        end = advance(pose, k, length)
        xs.append(end[0])
        ys.append(end[1])
        if k != 0.0 and length > 0.0:
            x, y, h = pose
            r = 1.0 / abs(k)
            cx, cy = x - math.sin(h) / k, y + math.cos(h) / k
            theta0 = math.atan2(y - cy, x - cx)
            sweep = abs(k) * length
            for target, px, py in ((0.0, cx + r, cy), (0.5 * math.pi, cx, cy + r),
                                   (math.pi, cx - r, cy), (1.5 * math.pi, cx, cy - r)):
                offset = (target - theta0) % TWO_PI if k > 0.0 else (theta0 - target) % TWO_PI
                if offset <= sweep:
                    xs.append(px)
                    ys.append(py)
        pose = end
    return min(xs), max(xs), min(ys), max(ys)


def surely_inside(start: tuple[float, float, float], goal: tuple[float, float, float], radius: float,
                  box: tuple[float, float, float, float]) -> bool:
    """Whether every Dubins path between start and goal stays in the box: no point of one is further than
    4 radii from both ends (a CCC path's middle circle lies within 3 radii of its first circle's centre)."""
    m = 4.0 * radius
    return all(box[0] + m <= p[0] <= box[1] - m and box[2] + m <= p[1] <= box[3] - m for p in (start, goal))


def shortest_path_inside(start: tuple[float, float, float], goal: tuple[float, float, float], radius: float,
                         box: tuple[float, float, float, float]) -> DubinsPath:
    """The shortest Dubins path that stays inside box = (xmin, xmax, ymin, ymax); if none does, the one that
    leaves it least (a robot already outside the box gets back in as directly as it can)."""
    paths = all_paths(start, goal, radius)
    if surely_inside(start, goal, radius, box):
        return paths[0]
    best, best_excess = None, math.inf
    for path in paths:
        x0, x1, y0, y1 = bounds(start, path)
        excess = max(box[0] - x0, x1 - box[1], box[2] - y0, y1 - box[3])
        if excess <= 0.0:
            return path
        if excess < best_excess - 1e-9:
            best, best_excess = path, excess
    return best


def distance_to(start: tuple[float, float, float], path: DubinsPath, point: tuple[float, float]) -> float:
    """The least distance from `point` to the path driven from `start` (exact: segments and arcs)."""
    px, py = point
    pose = start
    best = math.hypot(px - start[0], py - start[1])
    for seg in range(3):
        length, k = path.lengths[seg], path.curvature(seg)
        if length <= 0.0:
            continue
        end = advance(pose, k, length)
        best = min(best, math.hypot(px - end[0], py - end[1]))
        x, y, h = pose
        if k == 0.0:
            t = (px - x) * math.cos(h) + (py - y) * math.sin(h)
            if 0.0 < t < length:
                best = min(best, abs(-(px - x) * math.sin(h) + (py - y) * math.cos(h)))
        else:
            cx, cy = x - math.sin(h) / k, y + math.cos(h) / k
            theta0 = math.atan2(y - cy, x - cx)
            offset = (math.atan2(py - cy, px - cx) - theta0) % TWO_PI
            if (offset if k > 0.0 else (TWO_PI - offset) % TWO_PI) <= abs(k) * length:
                best = min(best, abs(math.hypot(px - cx, py - cy) - 1.0 / abs(k)))
        pose = end
    return best
