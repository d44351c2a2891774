"""Which optimizer `auto` runs on the bundled domains' own problems, its certified gaps and its CPU time per
window, at the default horizon 2 and at 3 (the issue's floor: median <= 0.5 s per window at h = 3, whichever
optimizer auto chooses; every default refinement certifies at least one window within 1%).

Run: pytest -m benchmark tests/benchmarks/test_certified_domains_speed.py -s
Times are CPU seconds of each window (time.process_time around the optimizer), which a machine shared with
other jobs does not inflate; the windows' own wall-clock `seconds` are printed beside them.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
import tailor
from tailor.refinement import refine as refine_module

PROBLEMS = {
    "arm": ("letter-f", "letter-l", "letter-m", "letter-n", "letter-s", "letter-w", "letter-z", "stroke-4",
            "stroke-5", "stroke-6"),
    "kitchen": ("scenario1", "scenario2"),
    "soccer": ("score", "waypoints", "approach"),
}
FLOOR_S = 0.5  # median CPU time per window at h = 3
GAP_SHARE = 0.01  # a default refinement certifies at least one window this close


def _windows(domain: str, problem: str, horizon: int, monkeypatch) -> list[tuple[str, float, float | None, float]]:
    """(method, CPU seconds, gap share, wall seconds) of every window of the default refinement."""
    cpu: list[float] = []
    optimize = refine_module.optimize

    def timed(objective, method, seed):
        start = time.process_time()
        result = optimize(objective, method=method, seed=seed)
        cpu.append(time.process_time() - start)
        return result

    monkeypatch.setattr(refine_module, "optimize", timed)
    windows = tailor.refine(domain, problem, horizon=horizon).refined.windows
    monkeypatch.setattr(refine_module, "optimize", optimize)
    return [(w.method, t, w.gap_share, w.seconds) for w, t in zip(windows, cpu)]


@pytest.mark.benchmark
@pytest.mark.parametrize("domain", sorted(PROBLEMS))
def test_auto_on_the_bundled_problems(domain, monkeypatch):
    medians = {}
    for horizon in (2, 3):
        rows = [w for problem in PROBLEMS[domain] for w in _windows(domain, problem, horizon, monkeypatch)]
        methods = [m for m, *_ in rows]
        cpu = np.array([t for _, t, _, _ in rows])
        gaps = [g for m, _, g, _ in rows if m == "certified" and g is not None]
        medians[horizon] = float(np.median(cpu))
        print(f"\n{domain} h={horizon}: {len(rows)} windows, certified {methods.count('certified')}, ga "
              f"{methods.count('ga')}; CPU per window median {1e3 * medians[horizon]:.0f} ms, max "
              f"{1e3 * cpu.max():.0f} ms (wall median {1e3 * np.median([w for *_, w in rows]):.0f} ms); certified "
              f"gap median {100 * np.median(gaps) if gaps else float('nan'):.3f}%")
    for problem in PROBLEMS[domain][:1]:  # the domain's default problem (the first: letter-f, scenario1, score)
        rows = _windows(domain, problem, 2, monkeypatch)
        assert any(m == "certified" and g is not None and g <= GAP_SHARE for m, _, g, _ in rows)
    assert medians[3] <= FLOOR_S
