"""Random situations of a planned problem: a belief state drawn by the simulator's situation generator,
instantiated with the plan already made (the experiments and the subgoal experience refine many of them).

A `Job` holds plain, picklable values, so worker processes can instantiate situations without planning again.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

import numpy as np

from tailor.planner_bridge import AbstractPlan
from tailor.refinement.action_sequence import ActionSequence
from tailor.refinement.belief import BeliefState
from tailor.errors import TailorError
from tailor.refinement.instantiate import instantiate
from tailor.refinement.binding import Binding
from tailor.refinement.models.meta_model import load_meta_model
from tailor.planner_bridge import plan_pddl, read_pddl
from tailor.refinement.pipeline import (Task, assert_task, load_binding, load_models, resolve_task,
                                        success_models_in)


@dataclass(frozen=True)
class Job:
    """A planned problem whose random situations workers instantiate, and the seed of their stream."""

    task: Task
    plan: AbstractPlan
    seed: int


def planned_job(task: Task, seed: int) -> Job:
    """A job for `task` without its learned models (training plans before any exist): the PDDL pair read, the
    binding checked against it (a bad binding fails before the planner runs), then the plan."""
    pddl = read_pddl(task.domain, task.problem)
    load_binding(task, pddl.signature)
    return Job(task=task, plan=plan_pddl(pddl), seed=seed)


_CACHE: dict = {}  # per worker process: bindings and models, loaded once


def job_binding(job: Job):
    key = ("binding", str(job.task.domain))
    if key not in _CACHE:
        _CACHE[key] = load_binding(job.task)
    return _CACHE[key]


def job_models(job: Job, sequence: ActionSequence):
    key = ("models", str(job.task.models_dir), tuple(sorted({a.action for a in sequence.actions})))
    if key not in _CACHE:
        _CACHE[key] = load_models(job.task.models_dir, sequence)
    return _CACHE[key]


def job_meta_model(job: Job):
    """The meta action model beside the job's action models (models/meta.json), loaded once per process."""
    key = ("meta", str(job.task.models_dir))
    if key not in _CACHE:
        _CACHE[key] = load_meta_model(job.task.models_dir)
    return _CACHE[key]


def job_success_models(job: Job, sequence: ActionSequence) -> dict:
    """The success classifiers the binding names for the sequence's actions, loaded once per process."""
    key = ("success", str(job.task.models_dir), tuple(sorted({a.pddl.split()[0] for a in sequence.actions})))
    if key not in _CACHE:
        _CACHE[key] = success_models_in(job.task.models_dir, job_binding(job), sequence)
    return _CACHE[key]


def asserted_situation(job: Job, objects: dict) -> tuple[ActionSequence, dict]:
    """One situation through Algorithm 4 up to refinement: instantiated, subgoals asserted where the binding's
    success classifiers predict failure; with the classifiers the refinement must respect (Alg. 6)."""
    sequence = situation_sequence(job, objects)
    success = job_success_models(job, sequence)
    if not success:
        return sequence, success
    return assert_task(sequence, job_binding(job), success, job.plan).sequence, success


def situation_sequence(job: Job, objects: dict) -> ActionSequence:
    """The instantiated plan of `job` for one random situation (belief values per object)."""
    belief = BeliefState(MappingProxyType({k.lower(): MappingProxyType(v) for k, v in objects.items()}))
    return instantiate(job.plan, job_binding(job), belief)


def draw_situations(domain_dir: Path, binding: Binding, generator: str, seeds: Iterable[tuple[int, int]],
                    seed: int, planned: dict[str, Job], models: Path | None = None) -> list[tuple[Job, int, dict]]:
    """(job, index, belief values) of each (index, its seed) drawn by the simulator's situation generator
    `generator`, in this process (drawing is cheap); each problem the situations need is planned once, into
    `planned` (problem -> Job), which callers keep across calls; `models` is the model folder (None: the
    domain's own)."""
    entry = binding.entry
    if generator not in entry.situations:
        raise TailorError(f"simulator {entry.name!r} has no situation generator {generator!r} "
                          f"(known: {', '.join(entry.situations) or 'none'})")
    draw = entry.situations[generator]
    out = []
    for index, situation_seed in seeds:
        problem, objects = draw(np.random.default_rng(situation_seed))
        if problem not in planned:
            planned[problem] = planned_job(resolve_task(str(Path(domain_dir) / "domain.pddl"), problem, models=models), seed)
        out.append((planned[problem], index, objects))
    return out


def stream_seed(*words: int) -> int:
    """One seed from a tuple of seed words (SeedSequence): the streams of different uses never overlap."""
    return int(np.random.SeedSequence(list(words)).generate_state(1)[0])
