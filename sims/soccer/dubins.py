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


@dataclass(frozen=True)
class DubinsPath:
    """A Dubins path: its word, its three segment lengths (m) and the turning radius (m) of its arcs."""

    word: str
    lengths: tuple[float, float, float]
    radius: float

    @property
    def length(self) -> float:
        return self.lengths[0] + self.lengths[1] + self.lengths[2]

    def curvature(self, segment: int) -> float:
        """Signed curvature (1/m) of a segment: +1/radius left, -1/radius right, 0 straight."""
        kind = self.word[segment]
        return 1.0 / self.radius if kind == "L" else -1.0 / self.radius if kind == "R" else 0.0


def _mod(angle: float) -> float:
    return angle % TWO_PI


def _words(alpha: float, beta: float, d: float) -> dict[str, tuple[float, float, float] | None]:
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
    p2 = -2.0 + d * d + 2.0 * cab + 2.0 * d * (sa + sb)  # LSR
    if p2 >= 0.0:
        p = math.sqrt(p2)
        th = math.atan2(-ca - cb, d + sa + sb) - math.atan2(-2.0, p)
        out["LSR"] = (_mod(th - alpha), p, _mod(th - beta))
    else:
        out["LSR"] = None
    p2 = -2.0 + d * d + 2.0 * cab - 2.0 * d * (sa + sb)  # RSL
    if p2 >= 0.0:
        p = math.sqrt(p2)
        th = math.atan2(ca + cb, d - sa - sb) - math.atan2(2.0, p)
        out["RSL"] = (_mod(alpha - th), p, _mod(beta - th))
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
            t, p, q = seg
            arc_p = p if word[1] == "S" else _clean(p)
            paths.append(DubinsPath(word, (_clean(t) * radius, arc_p * radius, _clean(q) * radius), radius))
    paths.sort(key=lambda path: path.length)
    return paths


def shortest_path(start: tuple[float, float, float], goal: tuple[float, float, float],
                  radius: float) -> DubinsPath:
    """The shortest Dubins path from start (x, y, heading) to goal (x, y, heading) with turning radius."""
    return all_paths(start, goal, radius)[0]


def sample(start: tuple[float, float, float], path: DubinsPath, step: float) -> list[tuple[float, float, float]]:
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
