"""Seeded noise for the simulators' control ticks: rows of standard normal numbers drawn in blocks."""

from __future__ import annotations

import numpy as np

BLOCK = 512  # control ticks of noise drawn at once: one numpy call instead of one per tick


class NormalRows:
    """Rows of `width` standard normal numbers from `rng`, one per control tick, drawn BLOCK rows at a time
    (the first block on the first row asked for)."""

    def __init__(self, rng: np.random.Generator, width: int):
        self.rng = rng
        self.width = width
        self._rows: list[list[float]] = []

    def next(self) -> list[float]:
        self.peek()
        return self._rows.pop()

    def peek(self) -> list[float]:
        """The row `next` returns next, without taking it (what a closed loop's observe() measures with, so that
        observing consumes nothing)."""
        if not self._rows:
            self._rows = self.rng.standard_normal((BLOCK, self.width)).tolist()
            self._rows.reverse()
        return self._rows[-1]
