"""Synchronized ramp (trapezoidal) joint velocity profiles of the reach action (App. A.4).

A joint goes from (x0, v0) to (xg, vg) in three phases: accelerate at +-a_max from v0 to a cruise speed vc,
cruise at vc, then accelerate at +-a_max from vc to vg; |vc| <= v_max. Start and goal speeds above v_max are
clamped to it. Every profile is of this family, so the time-optimal one is too: it is the fastest
of the *boundary* profiles (no cruise, cruise at +-v_max, a phase of length zero, or stop-and-wait), which
covers overshoot-and-return (vc of the other sign than the way to go, when the goal velocity points back or
the joint cannot brake in time). Rest to rest over d >= v^2/a this is T = d/v + v/a, else T = 2 sqrt(d/a).

Synchronization (both joints start and end together): the slower joint's optimal duration T is the target;
the other joint is stretched to take exactly T with a slower cruise speed, solved in closed form (duration
= T is a quadratic in vc for each sign pattern of the two ramps). Exact stretching is impossible when T
falls in a gap of the joint's feasible durations (a joint that must arrive moving and cannot slow down enough
without reversing, yet T is too short for a reversal); then T moves up to the smallest duration that joint
can take, and every joint is stretched to that, repeated until all agree (a few rounds at most).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

EPS = 1e-9  # s or rad: tolerance of the consistency checks (durations, distances)
MAX_SYNC_ROUNDS = 20  # rounds of raising the common duration before giving up synchronizing exactly


@dataclass(frozen=True)
class JointProfile:
    """One joint's ramp: phase 1 (t1 s at a1 rad/s^2), cruise (tc s at vc rad/s), phase 3 (t3 s at a3)."""

    x0: float
    v0: float
    vc: float
    a1: float
    t1: float
    tc: float
    a3: float
    t3: float
    xg: float
    vg: float

    @property
    def duration(self) -> float:
        return self.t1 + self.tc + self.t3

    def at(self, t: float) -> tuple[float, float]:
        """(position, velocity) at time t s after the start; after the end it moves on at vg."""
        if t <= self.t1:
            return self.x0 + (self.v0 + 0.5 * self.a1 * t) * t, self.v0 + self.a1 * t
        x1 = self.x0 + (self.v0 + self.vc) * 0.5 * self.t1
        t -= self.t1
        if t <= self.tc:
            return x1 + self.vc * t, self.vc
        t -= self.tc
        if t <= self.t3:
            return x1 + self.vc * self.tc + (self.vc + 0.5 * self.a3 * t) * t, self.vc + self.a3 * t
        return self.xg + self.vg * (t - self.t3), self.vg


def _clamp(v: float, v_max: float) -> float:
    return max(-v_max, min(v_max, v))


def _make(x0: float, v0: float, xg: float, vg: float, vc: float, a_max: float,
          tc: float | None = None) -> JointProfile | None:
    """The profile through cruise speed vc (its cruise time following from the distance), or None if it
    would need a negative cruise time; `tc` is given only for vc = 0 (stop, wait tc, start again)."""
    t1, t3 = abs(vc - v0) / a_max, abs(vg - vc) / a_max
    rest = (xg - x0) - 0.5 * (v0 + vc) * t1 - 0.5 * (vc + vg) * t3  # distance left for the cruise
    if tc is None:
        if vc == 0.0:
            return None
        tc = rest / vc
    elif abs(rest) > EPS:
        return None
    if tc < -EPS:
        return None
    return JointProfile(x0, v0, vc, math.copysign(a_max, vc - v0), t1, max(tc, 0.0),
                        math.copysign(a_max, vg - vc), t3, xg, vg)


def boundary_profiles(x0: float, v0: float, xg: float, vg: float, v_max: float,
                      a_max: float) -> list[JointProfile]:
    """The profiles at the ends of the joint's feasible durations: the fastest is time-optimal, and every
    gap in the feasible durations ends at one of them."""
    v0, vg = _clamp(v0, v_max), _clamp(vg, v_max)
    d = xg - x0
    speeds = {v_max, -v_max, v0, vg}
    for s1 in (1.0, -1.0):  # sign of phase 1's acceleration
        for s3 in (1.0, -1.0):  # sign of phase 3's acceleration
            if s1 != s3:  # no cruise: d = s1 (vc^2 - v0^2) / 2a + s3 (vg^2 - vc^2) / 2a
                sq = (2.0 * a_max * d + s1 * v0 * v0 - s3 * vg * vg) / (s1 - s3)
                if sq >= -EPS:
                    root = math.sqrt(max(sq, 0.0))
                    speeds.update((root, -root))
    out = [p for vc in speeds if abs(vc) <= v_max + EPS
           for p in [_make(x0, v0, xg, vg, _clamp(vc, v_max), a_max)] if p is not None]
    wait = _make(x0, v0, xg, vg, 0.0, a_max, tc=0.0)  # stop exactly at the goal, start again
    if wait is not None:
        out.append(wait)
    return out


def optimal(x0: float, v0: float, xg: float, vg: float, v_max: float, a_max: float) -> JointProfile:
    """The time-optimal ramp from (x0, v0) to (xg, vg) within |v| <= v_max, |a| <= a_max."""
    return min(boundary_profiles(x0, v0, xg, vg, v_max, a_max), key=lambda p: p.duration)


def stretched(x0: float, v0: float, xg: float, vg: float, duration: float, v_max: float,
              a_max: float) -> JointProfile | None:
    """A ramp taking exactly `duration` s (of several, the one accelerating least); None if there is none."""
    v0, vg = _clamp(v0, v_max), _clamp(vg, v_max)
    d, a = xg - x0, a_max
    found = [p for p in boundary_profiles(x0, v0, xg, vg, v_max, a_max) if abs(p.duration - duration) <= EPS]
    for s1 in (1.0, -1.0):
        for s3 in (1.0, -1.0):
            # T a vc = s1 (vc - v0) vc + s3 (vg - vc) vc + a d - s1 (vc^2 - v0^2)/2 - s3 (vg^2 - vc^2)/2
            qa = 0.5 * (s1 - s3)
            qb = s3 * vg - s1 * v0 - a * duration
            qc = a * d + 0.5 * (s1 * v0 * v0 - s3 * vg * vg)
            if qa == 0.0:
                roots = [-qc / qb] if qb != 0.0 else []
            else:
                disc = qb * qb - 4.0 * qa * qc
                if disc < 0.0:
                    continue
                sd = math.sqrt(disc)
                roots = [(-qb + sd) / (2.0 * qa), (-qb - sd) / (2.0 * qa)]
            for vc in roots:
                if abs(vc) > v_max + EPS or abs(vc) < EPS:
                    continue
                p = _make(x0, v0, xg, vg, _clamp(vc, v_max), a_max)
                if p is not None and abs(p.duration - duration) <= 1e3 * EPS:
                    found.append(p)
    wait = _make(x0, v0, xg, vg, 0.0, a_max, tc=0.0)
    if wait is not None and wait.duration <= duration:
        found.append(_make(x0, v0, xg, vg, 0.0, a_max, tc=duration - wait.duration))
    if not found:
        return None
    best = min(found, key=lambda p: (p.t1 + p.t3, abs(p.duration - duration)))
    if best.duration == duration:
        return best
    # absorb the round-off into the cruise (or, without one, the last ramp) so the joints end together
    if best.tc > 0.0 or best.t3 == 0.0:
        return JointProfile(best.x0, best.v0, best.vc, best.a1, best.t1,
                            max(duration - best.t1 - best.t3, 0.0), best.a3, best.t3, best.xg, best.vg)
    return JointProfile(best.x0, best.v0, best.vc, best.a1, best.t1, best.tc, best.a3,
                        max(duration - best.t1 - best.tc, 0.0), best.xg, best.vg)


def feasible_after(x0: float, v0: float, xg: float, vg: float, duration: float, v_max: float,
                   a_max: float) -> float:
    """The smallest duration >= `duration` the joint can take (inf if none)."""
    if stretched(x0, v0, xg, vg, duration, v_max, a_max) is not None:
        return duration
    later = [p.duration for p in boundary_profiles(x0, v0, xg, vg, v_max, a_max) if p.duration > duration]
    return min(later, default=math.inf)


def synchronize(starts: Sequence[tuple[float, float]], goals: Sequence[tuple[float, float]], v_max: float,
                a_max: float) -> tuple[JointProfile, ...]:
    """One ramp per joint, (x0, v0) -> (xg, vg), all taking the slowest joint's time (see the module doc).

    Without a common duration after MAX_SYNC_ROUNDS rounds (never seen) each joint keeps its optimal ramp."""
    joints = [(x0, v0, xg, vg) for (x0, v0), (xg, vg) in zip(starts, goals)]
    fastest = [optimal(*j, v_max, a_max) for j in joints]
    duration = max(p.duration for p in fastest)
    for _ in range(MAX_SYNC_ROUNDS):
        profiles = [stretched(*j, duration, v_max, a_max) for j in joints]
        if all(p is not None for p in profiles):
            return tuple(profiles)
        duration = max(feasible_after(*j, duration, v_max, a_max)
                       for j, p in zip(joints, profiles) if p is None)
        if not math.isfinite(duration):
            break
    return tuple(fastest)
