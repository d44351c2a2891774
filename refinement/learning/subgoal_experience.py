"""Experience where refinement acts (the outlook of Sec. 8.1): episodes of an action started from the subgoals
subgoal refinement chooses.

Refinement picks the subgoal where the summed prediction is lowest, which is also where a model's error
happens to be most optimistic (the optimizer's curse): the refined dribble was predicted 1 s too fast on average
while the greedy one was not, and so were refined way-point navigations. Episodes from those subgoals teach the
model exactly the region it is used in. The situations are random situations of a chain problem (a seed stream
of their own, so none is one of `tailor evaluate`'s), refined greedily and with horizon 2 in turn; each
occurrence of the learning action after the chain's first action yields one episode from its refined start to
its refined goal, the ball placed as in the action's experience scenario (in the guide for dribbleBall).
"""

from __future__ import annotations

import numpy as np
from joblib import Parallel, delayed
from tqdm import tqdm

from tailor.sims.episode import ActionCall, Episode
from tailor.sims.experience import SCENARIOS
from tailor.sims.soccer import SoccerSim

from tailor.refinement.evaluation.experiments import BELIEFS, Job, prepared_job, scenario_sequence
from tailor.refinement.pipeline import prepare, resolve_task
from tailor.refinement.refine import refine

SUBGOAL_STREAM = 2  # second seed word: apart from the evaluation's scenarios (SeedSequence([seed, index]))
CHUNK = 50  # situations a worker refines per task


def _seed(seed: int, index: int) -> int:
    return int(np.random.SeedSequence([seed, SUBGOAL_STREAM, index]).generate_state(1)[0])


def _episodes(job: Job, problem: str, models: dict, indices: list[int], action: str) -> tuple[int, list[Episode]]:
    """(situations, episodes) of the situations `indices`."""
    out = []
    for i in indices:
        seed = _seed(job.seed, i)
        sequence = scenario_sequence(job, BELIEFS[problem](np.random.default_rng(seed)))
        refined = refine(sequence, models, horizon=1 + i % 2, method="analytic", seed=seed)
        for k, follow in enumerate(refined.sequence.actions):
            if k == 0 or follow.action != action:  # the first action starts from the belief, not a subgoal
                continue
            p = follow.values()
            ball = SCENARIOS[action].ball_at((p[0], p[1]), (p[4], p[5]))
            sim = SoccerSim(seed + k - 1)
            sim.reset((p[0], p[1], p[2], p[3]), ball=ball)
            out.append(sim.run(ActionCall(action, tuple(float(v) for v in p[4:]))))
    return len(indices), out


def subgoal_job(domain: str, problem: str, seed: int) -> Job:
    """The planned and instantiated problem the subgoal situations are drawn for."""
    return prepared_job(prepare(resolve_task(domain, problem)), seed)


def gather_subgoal_experience(domain: str, problem: str, action: str, models: dict, situations: int, seed: int,
                              jobs: int = 1, progress: bool = True, first: int = 0, job: Job | None = None
                              ) -> list[Episode]:
    """Episodes of `action` from the subgoals refinement chooses with `models` (a dict action -> ActionModel) in
    `situations` random situations of `problem`: situations first, first + 1, ... of the seed's stream (so
    successive calls with consecutive ranges never repeat a situation). `job`, from `subgoal_job`, spares
    planning the problem again on each call."""
    job = subgoal_job(domain, problem, seed) if job is None else job
    last = first + situations
    chunks = [list(range(k, min(k + CHUNK, last))) for k in range(first, last, CHUNK)]
    out: list[Episode] = []
    with tqdm(total=situations, desc=f"{problem} subgoals ({action})", unit="situation", disable=not progress) as bar:
        calls = (delayed(_episodes)(job, problem, models, chunk, action) for chunk in chunks)
        for count, episodes in Parallel(n_jobs=jobs, return_as="generator")(calls):
            out.extend(episodes)
            bar.update(count)
    return out
