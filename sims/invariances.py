"""Random changes of action parameters that a feature space's features must not change under (the invariance
tests of Table 4.1's rows), shared by the generic feature spaces and those a robot brings. A change that
assumes a robot's parameter layout (a planar pose, say) lives in that robot's package."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def shift_mirror_axes(params: np.ndarray, rng: np.random.Generator, axes: Sequence[tuple[int, int]],
                      goal_offset: int, shift: float = 1.0) -> np.ndarray:
    """Each independent axis (a position and a velocity column; the goal's at + goal_offset) moved by one random
    offset in [-shift, shift] at start and goal, and mirrored half the time."""
    out = params.copy()
    for position, velocity in axes:
        offset, flip = rng.uniform(-shift, shift), -1.0 if rng.random() < 0.5 else 1.0
        for k in (position, position + goal_offset):
            out[:, k] = flip * (params[:, k] + offset)
        for k in (velocity, velocity + goal_offset):
            out[:, k] = flip * params[:, k]
    return out

