"""Scaling of experience gathering: episodes per second with 1 and 2 loky workers and a local Dask cluster
(and more workers where the machine has them), for the soccer robot and the arm. Prints a Markdown table
(README "Scaling"). Each setting is warmed up first (worker processes started, simulators imported), so the
rate is that of the gathering, not of starting the pool; the episodes are checked to be the serial ones.

    pytest -m benchmark -s tests/benchmarks/test_scaling.py
"""

from __future__ import annotations

import importlib.util
import os
import time

import pytest

from tailor.sims.experience import gather
from tailor.sims.parallel import backend_session

CASES = {"soccer": ("approachBall", 800), "arm": ("reach", 800)}  # simulator: (scenario, episodes timed)
WARM_UP = 40  # episodes gathered before timing, in the same session


def settings() -> list[tuple[str, int]]:
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    workers = sorted({1, 2, *(w for w in (4, 8) if w <= cpus)})
    out = [("loky", w) for w in workers]
    if importlib.util.find_spec("distributed") is not None:
        out += [("dask", w) for w in workers if w > 1]
    return out


def rate(simulator: str, scenario: str, episodes: int, backend: str, jobs: int) -> tuple[float, list]:
    with backend_session(backend, jobs):
        gather(simulator, scenario, WARM_UP, seed=99, jobs=jobs, progress=False)
        start = time.perf_counter()
        gathered = gather(simulator, scenario, episodes, seed=0, jobs=jobs, progress=False)
        return episodes / (time.perf_counter() - start), gathered


@pytest.mark.benchmark
def test_episodes_per_second():
    rows = [f"{os.cpu_count()} CPUs; load average {os.getloadavg()[0]:.1f} at the start",
            "| simulator (scenario) | episodes | " + " | ".join(f"{b} x{j}" for b, j in settings()) + " |",
            "|---|---|" + "---|" * len(settings())]
    for simulator, (scenario, episodes) in CASES.items():
        rates, reference = [], None
        for backend, jobs in settings():
            per_second, gathered = rate(simulator, scenario, episodes, backend, jobs)
            if reference is None:
                reference = gathered
            assert [e.state.tobytes() for e in gathered] == [e.state.tobytes() for e in reference]
            rates.append(per_second)
        rows.append(f"| {simulator} ({scenario}) | {episodes} | " + " | ".join(f"{r:.0f}" for r in rates) + " |")
    print("\nepisodes per second\n" + "\n".join(rows))
