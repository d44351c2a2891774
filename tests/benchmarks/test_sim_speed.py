"""Real-time factor of the soccer simulator (simulated seconds per wall second, one core, one robot)."""

import time

import pytest

from tailor.sims.experience import episode_seeds, run_episode


@pytest.mark.benchmark
@pytest.mark.parametrize("scenario", ["goToPose", "approachBall", "dribbleBall"])
def test_real_time_factor(scenario):
    start, simulated = time.perf_counter(), 0.0
    for seed in episode_seeds(0, 40):
        simulated += run_episode("soccer", scenario, seed).duration
    rtf = simulated / (time.perf_counter() - start)
    print(f"\n{scenario}: {simulated:.0f} simulated s, real-time factor {rtf:.0f}x")
    assert rtf >= 1000
