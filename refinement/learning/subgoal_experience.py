"""Experience where refinement acts (the outlook of Sec. 8.1): episodes of an action started from the subgoals
subgoal refinement chooses.

Refinement picks the subgoal where the summed prediction is lowest, which is also where a model's error
happens to be most optimistic (the optimizer's curse). Episodes from those subgoals teach the model exactly
the region it is used in. The situations are random situations of a chain problem (drawn by the simulator's
situation generator of the same name, on a seed stream of their own, so none is one of `tailor evaluate`'s),
refined greedily and with horizon 2 in turn; each occurrence of the learning action after the chain's first
action yields one episode from its refined start to its refined goal (the simulator's `subgoal_episode`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from joblib import Parallel, delayed
from tqdm import tqdm

from tailor.refinement.errors import TailorError
from tailor.refinement.pipeline import prepare, resolve_task
from tailor.refinement.refine import refine
from tailor.refinement.situations import Job, draw_situation, job_binding, prepared_job, situation_sequence, stream_seed
from tailor.sims.episode import Episode

SUBGOAL_STREAM = 2  # second seed word: apart from the evaluation's situations (SeedSequence([seed, index]))
CHUNK = 50  # situations a worker refines per task


def _episodes(job: Job, problem: str, models: dict, indices: list[int], action: str) -> tuple[int, list[Episode]]:
    """(situations, episodes) of the situations `indices`."""
    entry = job_binding(job).entry
    out = []
    for i in indices:
        seed = stream_seed(job.seed, SUBGOAL_STREAM, i)
        drawn, objects = draw_situation(job, problem, np.random.default_rng(seed))
        if drawn != problem:
            raise TailorError(f"situation generator {problem!r} drew a situation of problem {drawn!r}")
        refined = refine(situation_sequence(job, objects), models, horizon=1 + i % 2, method="analytic", seed=seed)
        for k, follow in enumerate(refined.sequence.actions):
            if k == 0 or follow.action != action:  # the first action starts from the belief, not a subgoal
                continue
            out.append(entry.subgoal_episode(action, follow.values(), seed + k - 1))
    return len(indices), out


def subgoal_job(domain_dir: Path, problem: str, seed: int) -> Job:
    """The planned and instantiated problem the subgoal situations are drawn for."""
    return prepared_job(prepare(resolve_task(str(Path(domain_dir) / "domain.pddl"), problem)), seed)


def gather_subgoal_experience(domain_dir: Path, problem: str, action: str, models: dict, situations: int, seed: int,
                              jobs: int = 1, progress: bool = True, first: int = 0, job: Job | None = None
                              ) -> list[Episode]:
    """Episodes of `action` from the subgoals refinement chooses with `models` (a dict action -> ActionModel) in
    `situations` random situations of `problem`: situations first, first + 1, ... of the seed's stream (so
    successive calls with consecutive ranges never repeat a situation). `job`, from `subgoal_job`, spares
    planning the problem again on each call."""
    job = subgoal_job(domain_dir, problem, seed) if job is None else job
    last = first + situations
    chunks = [list(range(k, min(k + CHUNK, last))) for k in range(first, last, CHUNK)]
    out: list[Episode] = []
    with tqdm(total=situations, desc=f"{problem} subgoals ({action})", unit="situation", disable=not progress) as bar:
        calls = (delayed(_episodes)(job, problem, models, chunk, action) for chunk in chunks)
        for count, episodes in Parallel(n_jobs=jobs, return_as="generator")(calls):
            out.extend(episodes)
            bar.update(count)
    return out
