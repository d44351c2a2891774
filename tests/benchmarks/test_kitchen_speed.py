"""Real-time factor of the kitchen simulator (simulated seconds per wall second, one core): each experience
scenario, and whole scenario-1 sequences (goToPose, grip, goToPose, put) as refinement dispatches them."""

import time

import numpy as np
import pytest

from tailor.sims.episode import ActionCall
from tailor.sims.experience import episode_seeds, run_episode
from tailor.sims.kitchen import world as W
from tailor.sims.kitchen.scenarios import random_layout
from tailor.sims.kitchen.simulator import simulate_sequence


@pytest.mark.benchmark
@pytest.mark.parametrize("scenario", ["goToPose", "grip", "put"])
def test_kitchen_real_time_factor(scenario):
    start, simulated = time.perf_counter(), 0.0
    for seed in episode_seeds(0, 300):
        simulated += run_episode("kitchen", scenario, seed).duration
    rtf = simulated / (time.perf_counter() - start)
    print(f"\n{scenario}: {simulated:.0f} simulated s, real-time factor {rtf:.0f}x")
    assert rtf >= 1000


@pytest.mark.benchmark
def test_kitchen_sequence_real_time_factor():
    rng = np.random.default_rng(0)
    start, simulated = time.perf_counter(), 0.0
    for seed in range(50):
        layout = random_layout(rng, 1)
        cup, put = layout["cups"][0], layout["puts"][0]
        calls = [ActionCall("goToPose", (*W.serving_frame(layout["table1"], *cup), 0.0, 0.5, 0.0)),
                 ActionCall("grip", cup),
                 ActionCall("goToPose", (*W.serving_frame(layout["table2"], *put), 0.0, 0.5, 0.0)),
                 ActionCall("put", put)]
        result = simulate_sequence(layout["start"], {"table1": layout["table1"], "table2": layout["table2"]},
                                   {"cup1": cup}, calls, seed)
        assert result.succeeded
        simulated += result.duration
    rtf = simulated / (time.perf_counter() - start)
    print(f"\nscenario 1 sequences: {simulated:.0f} simulated s, real-time factor {rtf:.0f}x")
    assert rtf >= 1000
