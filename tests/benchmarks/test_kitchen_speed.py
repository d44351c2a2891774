"""Real-time factor of the kitchen simulator (simulated seconds per second of this process's CPU time, one core,
so that a machine shared with other work does not distort it; the wall-clock factor is printed beside it):
each experience scenario, and whole scenario-1 sequences (navigate, grip, navigate through the door at
0.5 m/s, navigate, put) as dispatched."""

import time

import numpy as np
import pytest

from tailor.sims.episode import ActionCall
from tailor.sims.experience import episode_seeds, run_episode
from tailor.sims.kitchen import world as W
from tailor.sims.kitchen.scenarios import random_layout
from tailor.sims.kitchen.simulator import simulate_sequence


class _Clock:
    def __init__(self):
        self.cpu, self.wall = time.process_time(), time.perf_counter()

    def report(self, what: str, simulated: float) -> float:
        cpu, wall = time.process_time() - self.cpu, time.perf_counter() - self.wall
        print(f"\n{what}: {simulated:.0f} simulated s, real-time factor {simulated / cpu:.0f}x per CPU second "
              f"({simulated / wall:.0f}x per wall second)")
        return simulated / cpu


@pytest.mark.benchmark
@pytest.mark.parametrize("scenario", ["navigate", "grip", "put"])
def test_kitchen_real_time_factor(scenario):
    clock = _Clock()
    simulated = 0.0
    for seed in episode_seeds(0, 300):
        simulated += run_episode("kitchen", scenario, seed).duration
    rtf = clock.report(scenario, simulated)
    assert rtf >= 1000


@pytest.mark.benchmark
def test_kitchen_sequence_real_time_factor():
    rng = np.random.default_rng(0)
    clock, simulated = _Clock(), 0.0
    for seed in range(50):
        layout = random_layout(rng, 1)
        cup, put = layout["cups"][0], layout["puts"][0]
        calls = [ActionCall("navigate", (*W.serving_frame(layout["table1"], *cup), 0.0, 0.5, 0.0, 0.0)),
                 ActionCall("grip", cup),
                 ActionCall("navigate", (*W.door_frame(True), 0.0, 0.0, 0.0, 0.5)),
                 ActionCall("navigate", (*W.serving_frame(layout["table2"], *put), 0.0, 0.5, 0.0, 0.0)),
                 ActionCall("put", put)]
        result = simulate_sequence(layout["start"], {"table1": layout["table1"], "table2": layout["table2"]},
                                   {"cup1": cup}, calls, seed)
        assert result.succeeded
        simulated += result.duration
    rtf = clock.report("scenario 1 sequences", simulated)
    assert rtf >= 1000


@pytest.mark.benchmark
def test_kitchen_optimizer_time_per_window():
    """Refinement (h=2, the genetic algorithm) of random scenario-2 situations: CPU time per window and the
    share of the sequence's (predicted) execution time all windows take; wall-clock times printed beside."""
    import statistics
    from types import MappingProxyType

    from tailor.planner_bridge import plan_files, resolve_problem
    from tailor.refinement.binding import load_domain_binding
    from tailor.refinement.instantiate import instantiate
    from tailor.refinement.models.action_models import load_action_models
    from tailor.refinement.refine import refine
    from tailor.refinement.belief import BeliefState
    from tailor.sims.kitchen.scenarios import scenario2

    domain, path = resolve_problem("kitchen", "scenario2")
    plan, binding = plan_files(domain, path), load_domain_binding(domain.parent)
    models = load_action_models(domain.parent / "models")
    wall, cpu, shares = [], [], []
    for i in range(10):
        _, objects = scenario2(np.random.default_rng(100 + i))
        belief = BeliefState(MappingProxyType({k: MappingProxyType(v) for k, v in objects.items()}))
        sequence = instantiate(plan, binding, belief)
        start = time.process_time()
        refined = refine(sequence, models, horizon=2, method="ga", seed=i)
        used = time.process_time() - start
        wall += [w.seconds for w in refined.windows]
        cpu.append(used / len(refined.windows))
        shares.append(used / refined.predicted_total)
    print(f"\nscenario 2, h=2: {len(wall)} windows, CPU per window median {1000 * statistics.median(cpu):.0f} ms "
          f"(wall median {1000 * statistics.median(wall):.0f} ms); all windows {100 * statistics.mean(shares):.2f}% "
          "of the execution time (CPU)")
    assert statistics.median(cpu) <= 0.5
    assert statistics.mean(shares) <= 0.01
