"""Experience where refinement acts (the outlook of Sec. 8.1): episodes of an action started from the subgoals
subgoal refinement chooses.

Refinement picks the subgoal where the summed prediction is lowest, which is also where a model's error
happens to be most optimistic (the optimizer's curse). Episodes from those subgoals teach the model exactly
the region it is used in. The situations are drawn by one of the simulator's situation generators (on a seed stream
of their own, so none is one of `tailor evaluate`'s; each problem they need is planned once),
refined greedily and with horizon 2 in turn; each occurrence of the learning action after the chain's first
action yields one episode from its refined start to its refined goal (the simulator's `subgoal_episode`).
"""

from __future__ import annotations

from pathlib import Path

from tailor.errors import DataError, ModelFileError
from tailor.progress import stage_bar
from tailor.refinement.binding import load_domain_binding
from tailor.refinement.refine import refine
from tailor.refinement.situations import Job, draw_situations, job_binding, situation_sequence, stream_seed
from tailor.sims.episode import Episode
from tailor.sims.parallel import ordered_results

SUBGOAL_STREAM = 2  # second seed word: apart from the evaluation's situations (SeedSequence([seed, index]))
CHUNK = 50  # situations a worker refines per task


def _episodes(situations: list[tuple[Job, int, dict]], models: dict, action: str) -> tuple[int, list[Episode]]:
    """(situations, episodes) of the drawn `situations` (job, index, belief values)."""
    out = []
    for job, i, objects in situations:
        entry = job_binding(job).entry
        seed = stream_seed(job.seed, SUBGOAL_STREAM, i)
        try:
            refined = refine(situation_sequence(job, objects), models, horizon=1 + i % 2, method="analytic", seed=seed)
        except ModelFileError as exc:
            if exc.file is not None:  # a model read from a file: it is the file that is wrong
                raise
            # a model just trained, not a file: at the minimum of episodes it may extrapolate absurdly
            raise DataError(f"the models just trained predict a duration outside the durations seen in training "
                            f"when refining situation {i} of '{job.plan.problem}' to choose subgoals: too few "
                            "episodes to learn from (train with more --episodes)") from None
        for k, follow in enumerate(refined.sequence.actions):
            if k == 0 or follow.action != action:  # the first action starts from the belief, not a subgoal
                continue
            out.append(entry.subgoal_episode(action, follow.values(), seed + k - 1))
    return len(situations), out


def gather_subgoal_experience(domain_dir: Path, generator: str, action: str, models: dict, situations: int,
                              seed: int, jobs: int = 1, progress: bool = True, first: int = 0,
                              planned: dict[str, Job] | None = None) -> list[Episode]:
    """Episodes of `action` from the subgoals refinement chooses with `models` (a dict action -> ActionModel) in
    `situations` random situations drawn by the simulator's situation generator `generator`: situations first,
    first + 1, ... of the seed's stream (so successive calls with consecutive ranges never repeat a situation).
    `planned` (problem -> Job) caches the problems planned so far across calls."""
    planned = {} if planned is None else planned
    seeds = [(i, stream_seed(seed, SUBGOAL_STREAM, i)) for i in range(first, first + situations)]
    drawn = draw_situations(domain_dir, load_domain_binding(domain_dir), generator, seeds, seed, planned)
    chunks = [drawn[k:k + CHUNK] for k in range(0, len(drawn), CHUNK)]
    out: list[Episode] = []
    with stage_bar(situations, f"{generator} subgoals ({action})", "situation", progress) as bar:
        results = ordered_results(_episodes, [(chunk, models, action) for chunk in chunks], jobs)
        try:
            for count, episodes in results:
                out.extend(episodes)
                bar.update(count)
        finally:
            results.close()
    return out
