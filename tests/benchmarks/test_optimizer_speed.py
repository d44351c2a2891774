"""Median optimizer time on the two-action chain (issue floors: analytic <= 5 ms, GA <= 100 ms).

Synthetic approachBall -> dribbleBall problems (heading and speed at the subgoal free, trees of 50-150
rules); prints the medians and how often analytic and GA agree within 1% of the predicted cost.
Run: pytest -m benchmark tests/benchmarks/test_optimizer_speed.py -s
The floors are checked on CPU time (time.process_time), which a machine shared with other jobs does not
inflate; wall-clock medians are printed beside them.
"""

import time

import numpy as np
import pytest

from tailor.refinement.optimizers import optimize
from tailor.refinement.optimizers.synthetic import pose_chain

PROBLEMS = 40
REPEATS = 5
ANALYTIC_FLOOR_S = 0.005
GA_FLOOR_S = 0.100


def _median_seconds(objective, method, seed):
    cpu, wall = [], []
    for _ in range(REPEATS):
        start, start_wall = time.process_time(), time.perf_counter()
        result = optimize(objective, method, seed=seed)
        cpu.append(time.process_time() - start)
        wall.append(time.perf_counter() - start_wall)
    return float(np.median(cpu)), float(np.median(wall)), result


@pytest.mark.benchmark
def test_optimizer_speed():
    rng = np.random.default_rng(2024)
    analytic_times, ga_times, walls, agree, fallbacks = [], [], {"analytic": [], "ga": []}, 0, 0
    for k in range(PROBLEMS):
        objective = pose_chain(rng, n_leaves=int(rng.integers(50, 151)))
        optimize(objective, "analytic")  # warm the rule cache as a refinement of a chain would
        t_a, w_a, analytic = _median_seconds(objective, "analytic", k)
        t_g, w_g, ga = _median_seconds(objective, "ga", k)
        walls["analytic"].append(w_a)
        walls["ga"].append(w_g)
        analytic_times.append(t_a)
        ga_times.append(t_g)
        fallbacks += analytic.method != "analytic"
        agree += abs(ga.cost - analytic.cost) <= 0.01 * abs(analytic.cost)
    med_a, med_g = np.median(analytic_times), np.median(ga_times)
    print(f"\nCPU: analytic median {med_a * 1e3:.2f} ms, ga median {med_g * 1e3:.1f} ms over {PROBLEMS} problems; "
          f"wall: analytic {np.median(walls['analytic']) * 1e3:.2f} ms, ga {np.median(walls['ga']) * 1e3:.1f} ms; "
          f"agree within 1% on {agree}/{PROBLEMS}; analytic fell back {fallbacks} times")
    assert fallbacks == 0
    assert med_a <= ANALYTIC_FLOOR_S
    assert med_g <= GA_FLOOR_S
