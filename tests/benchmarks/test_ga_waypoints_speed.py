"""Optimizer speed per window on the soccer way-point chain at horizons 2 and 3 (issue floors: with the deployed
robust objective, the genetic algorithm's median <= 0.25 s CPU a window at h=2 and <= 0.5 s at h=3, and `auto`,
the default, <= 0.5 s at h=3 whichever optimizer it chooses; checked here at h=2 against the same 0.5 s: the
dissertation's worst case took < 0.5 s). At h >= 2
the chain has up to six free parameters per window (two way-points' heading and speed, and more); the
analytic minimization does not apply (goToPose's `goto` features are curved in a heading); the certified
optimizer bounds them (sims/soccer/feature_bounds.py) but closes the gap only on windows of two free
parameters; where it cannot, auto gives up once the gap's fall shows it cannot close within the budget
(judged from certified.CHECKPOINT boxes on, at most WIDE) and runs the GA, keeping the better choice.

Run: pytest -m benchmark -n 0 tests/benchmarks/test_ga_waypoints_speed.py -s
The floors are checked on CPU time per window (time.process_time over the refinement divided by its windows),
which other jobs on a shared machine do not inflate; the wall-clock median of the windows is printed beside.
With the binding's neighbourhood refinement minimizes the worst case over 1 + 4 k points around each candidate
(k: the free parameters an action reads), the deployed objective (`[refinement] neighbourhood`); without it,
one point per candidate, as the dissertation times its GA.
"""

import time
from pathlib import Path

import numpy as np
import pytest

from tailor.planner_bridge import resolve_domain_dir
from tailor.refinement.binding import load_domain_binding
from tailor.refinement.refine import refine
from tailor.refinement.situations import draw_situations, job_models, situation_sequence, stream_seed

SITUATIONS = 20
HORIZONS = (2, 3)
FLOOR_S = {2: 0.25, 3: 0.5}  # the GA with the neighbourhood; without it the floor of both is 0.5 s
AUTO_FLOOR_S = 0.5  # auto, at either horizon (the certified search it tries first costs more than the GA alone on
# some windows: its choice is certified where it closes)


@pytest.mark.benchmark
def test_optimizer_speed_on_the_waypoint_chain():
    domain_dir = resolve_domain_dir("soccer")
    binding = load_domain_binding(domain_dir)
    items = draw_situations(Path(domain_dir), binding, "waypoints",
                            [(i, stream_seed(7, i)) for i in range(SITUATIONS)], 7, {})
    deployed = binding.refinement.neighbourhood
    keys = [(h, 0.0, "ga") for h in HORIZONS] + [(h, deployed, m) for h in HORIZONS for m in ("ga", "auto")]
    cpu, wall, totals, free, methods = {k: [] for k in keys}, {k: [] for k in keys}, {k: [] for k in keys}, set(), set()
    for job, index, objects in items:
        sequence = situation_sequence(job, objects)
        models = job_models(job, sequence)
        for h, share, method in keys:
            start = time.process_time()
            refined = refine(sequence, models, horizon=h, method=method, seed=index, neighbourhood=share)
            cpu[h, share, method].append((time.process_time() - start) / len(refined.windows))
            wall[h, share, method] += [w.seconds for w in refined.windows]
            totals[h, share, method].append(refined.predicted_total)
            free.add(max(len(w.values) for w in refined.windows))
            if method == "auto":
                methods.update(w.method for w in refined.windows)
    for h, share, method in keys:
        k = (h, share, method)
        print(f"\nh={h}, neighbourhood {share:g}, {method}: per window median CPU {np.median(cpu[k]):.3f} s (max "
              f"{np.max(cpu[k]):.3f} s), median wall {np.median(wall[k]):.3f} s over {len(wall[k])} windows of "
              f"{SITUATIONS} situations; mean predicted total {np.mean(totals[k]):.4f} s")
    print(f"free parameters per window: up to {max(free)}; auto chose {sorted(methods)}")
    for h in HORIZONS:
        # auto keeps the better of the certified optimizer's and the GA's choice in each window it cannot certify
        assert np.mean(totals[h, deployed, "auto"]) <= 1.001 * np.mean(totals[h, deployed, "ga"])
        assert np.median(cpu[h, 0.0, "ga"]) <= 0.5
        assert np.median(cpu[h, deployed, "ga"]) <= FLOOR_S[h]
        assert np.median(cpu[h, deployed, "auto"]) <= AUTO_FLOOR_S
