"""Real-time factor of the arm simulator (simulated seconds per wall second, one core, random reaches)."""

import time

import pytest

from tailor.sims import registry
from tailor.sims.arm import SIMULATOR
from tailor.sims.experience import episode_seeds, run_episode


@pytest.mark.benchmark
def test_arm_real_time_factor():
    registry.register(SIMULATOR, replace=True)  # until the entry point is installed
    start, simulated = time.perf_counter(), 0.0
    for seed in episode_seeds(0, 500):
        simulated += run_episode("arm", "reach", seed).duration
    rtf = simulated / (time.perf_counter() - start)
    print(f"\nreach: {simulated:.0f} simulated s, real-time factor {rtf:.0f}x")
    assert rtf >= 1000
