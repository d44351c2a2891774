"""A lossy radio channel between teammates (Sec. 7.4.1): links drop out for random intervals.

Each pair of robots shares one link, down in both directions at once. A link alternates between up and
down intervals of exponentially distributed lengths (a two-state, Gilbert-like channel): outages last
`mean_outage` seconds on average, and the up intervals are as long as it takes for the link to be up a
share `quality` of the time, which is then the share of packets that arrive. quality 1 never drops a
packet, quality 0 never delivers one. Sampled at the teams' message period.
"""

from __future__ import annotations

import numpy as np


def link_intervals(quality: float, mean_outage: float) -> tuple[float, float]:
    """Mean lengths (s) of the up and the down intervals for a link up a share `quality` of the time."""
    if not 0.0 <= quality <= 1.0:
        raise ValueError(f"communication quality must lie in [0, 1], got {quality}")
    if not mean_outage > 0.0:
        raise ValueError(f"the mean outage must be positive, got {mean_outage}")
    if quality >= 1.0:
        return np.inf, 0.0
    if quality <= 0.0:
        return 0.0, np.inf
    return mean_outage * quality / (1.0 - quality), mean_outage


def link_states(ticks: int, robots: int, quality: float, mean_outage: float, period: float,
                rng: np.random.Generator) -> np.ndarray:
    """(ticks, robots, robots) bool: whether a packet sent at tick k between robots i and j arrives.

    Symmetric, False on the diagonal (a robot sends nothing to itself). Each link starts in its stationary
    state (up with probability `quality`) and then alternates up and down intervals."""
    up_mean, down_mean = link_intervals(quality, mean_outage)
    up = np.zeros((ticks, robots, robots), dtype=bool)
    times = np.arange(ticks) * period
    for i in range(robots):
        for j in range(i + 1, robots):
            state = bool(rng.random() < quality)
            column = np.empty(ticks, dtype=bool)
            start, k = 0.0, 0
            while k < ticks:
                mean = up_mean if state else down_mean
                length = np.inf if np.isinf(mean) else (rng.exponential(mean) if mean > 0 else 0.0)
                end = start + length
                stop = ticks if np.isinf(end) else int(np.searchsorted(times, end, side="left"))
                column[k:stop] = state
                k, start, state = max(k, stop), end, not state
            up[:, i, j] = up[:, j, i] = column
    return up
