"""What the kitchen can change behind the plan's back (Ch. 8.1): a cup displaced while the base drives, and a
changed robot, a base slowed by a carpeted room.

Disturbance "cup": during the first navigate action a simulator runs while some cup stands free on a table
(not held), at a moment drawn uniformly from CUP_MOMENT times the straight-line distance of that navigate
divided by V_MAX (the base cannot arrive sooner than that distance at V_MAX, so the moment falls while it
drives; it strikes at the first control tick at or after it), one such cup, drawn uniformly, slides on its
table by a distance uniform in CUP_SHIFT in a uniform direction, redrawn (both) until the cup stands wholly on
the table top and at least CUP_SEPARATION from every other cup (at most SHIFT_TRIES draws; practically never
all rejected, then nothing moves). Once per simulator. Every draw comes from the generator
(seed, DISTURBANCE_STREAM), never from the motor and sensor noise, so a run with the disturbance is the run
without it up to the moment the cup moves.

Variant "slow_floor": room B (east of the divider, x > DIVIDER_X, where table2 stands) is carpeted: while the
base's centre is there, its speed, turn rate, acceleration and angular acceleration limits are SLOW_FACTOR of
the nominal ones. The drive enforces them and the navigation controller plans with them, as with a speed zone
of the map, so the base is slower there, not clumsier. Room A (the start, table1, the island) is unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from tailor.sims.kitchen import world as W

DISTURBANCE_STREAM = 2  # second seed word of the disturbances' generator (1 is the scenarios' sampling)
SENSING_STREAM = 3  # second seed word of the cup measurements of KitchenSim.scene()
CUP_SHIFT = (0.15, 0.35)  # m, how far the displaced cup slides on its table
CUP_MOMENT = (0.1, 0.9)  # share of distance / V_MAX into the navigate action at which the cup moves
SHIFT_TRIES = 1000
SLOW_FACTOR = 0.7  # the carpet's share of the base's speed and acceleration limits

DISTURBANCES = {
    "cup": (f"while the base drives (the first navigate with a cup standing free on a table), one such cup "
            f"slides {CUP_SHIFT[0]:.2f}-{CUP_SHIFT[1]:.2f} m in a random direction, staying on its table "
            "top"),
}
VARIANTS = {
    "slow_floor": (f"room B (x > {W.DIVIDER_X:g} m, table2's room) is carpeted: there the base's speed and "
                   f"acceleration limits are x{SLOW_FACTOR:g}"),
}

NOMINAL_LIMITS = (W.V_MAX, W.W_MAX, W.A_MAX, W.ALPHA_MAX)  # m/s, rad/s, m/s^2, rad/s^2
SLOW_LIMITS = tuple(SLOW_FACTOR * limit for limit in NOMINAL_LIMITS)


@dataclass(frozen=True)
class CupDisplacement:
    """What the "cup" disturbance did: which cup moved from where to where, when (the simulator's clock and
    the time into the navigate action) and the window the moment was drawn from (s into the action)."""

    cup: str
    before: tuple[float, float]
    after: tuple[float, float]
    time: float
    elapsed: float
    window: tuple[float, float]

    @property
    def distance(self) -> float:
        return math.hypot(self.after[0] - self.before[0], self.after[1] - self.before[1])


def on_slow_floor(x: float, y: float) -> bool:
    """Whether a base centred at (x, y) stands on the carpet of variant "slow_floor" (room B)."""
    return x > W.DIVIDER_X


def cup_moment(rng: np.random.Generator, distance: float) -> tuple[float, tuple[float, float]]:
    """The moment (s into a navigate of straight-line `distance` m) at which the cup moves, and its window."""
    least = distance / W.V_MAX
    window = (CUP_MOMENT[0] * least, CUP_MOMENT[1] * least)
    return float(rng.uniform(*window)), window


def standing_cups(cups: Mapping[str, Sequence[float]], tables: Mapping[str, W.Box],
                  held: str | None) -> list[str]:
    """The cups standing free on a table, in the order given."""
    return [name for name, (x, y) in cups.items()
            if name != held and any(box.contains(x, y) for box in tables.values())]


def displace(rng: np.random.Generator, cups: Mapping[str, Sequence[float]], tables: Mapping[str, W.Box],
             held: str | None) -> tuple[str, tuple[float, float]] | None:
    """A standing cup and its new position (see the module doc); None if no cup stands on a table, or no draw
    of SHIFT_TRIES keeps it on its table and clear of the others."""
    names = standing_cups(cups, tables, held)
    if not names:
        return None
    name = names[int(rng.integers(len(names)))]
    x, y = (float(v) for v in cups[name])
    box = next(b for b in tables.values() if b.contains(x, y))
    top = W.Box(box.cx, box.cy, box.hx - W.CUP_RADIUS, box.hy - W.CUP_RADIUS, box.angle)  # the cup all on it
    others = [(float(cx), float(cy)) for other, (cx, cy) in cups.items() if other not in (name, held)]
    for _ in range(SHIFT_TRIES):
        shift, direction = rng.uniform(*CUP_SHIFT), rng.uniform(-math.pi, math.pi)
        nx, ny = x + shift * math.cos(direction), y + shift * math.sin(direction)
        clear = all(math.hypot(nx - ox, ny - oy) >= W.CUP_SEPARATION for ox, oy in others)
        if clear and top.contains(nx, ny):
            return name, (float(nx), float(ny))
    return None
