"""Learning a domain's action models end to end (Chapter 4): gather experience, train, write models and report.

The recipe of a domain says which actions get a duration model and which scenario feeds the collision
classifier. Everything is computed first and written only at the end, each file to a temporary name that is
renamed over the target once all are complete: an interrupted run leaves the old files untouched.
"""

from __future__ import annotations

import json
import os
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from tqdm import tqdm

from tailor.planner_bridge.bundled import DOMAINS_DIR
from tailor.refinement.models.action_models import COLLISION_SUFFIX
from tailor.refinement.learning.classifiers import train_collision_model
from tailor.refinement.errors import DataError, TailorError
from tailor.refinement.learning.protocol import EPISODE_FRACTIONS, MIN_SAMPLES_LEAF, N_I_CANDIDATES, train_duration_model
from tailor.refinement.learning.report import format_report
from tailor.sims.episode import Episode

FILE_MODE = 0o644  # permissions of the written files
FRESH_SEED_OFFSET = 7_919_000  # the fresh test episodes of the classifier use seed + this: no shared episode


@dataclass(frozen=True)
class SubgoalExperience:
    """Experience at refined subgoals (Sec. 8.1, refinement.subgoal_experience): `action` also learns from
    episodes that start at the subgoals refinement chooses in random situations of the chain `problem`."""

    problem: str  # a problem beside the domain whose plan is the chain
    action: str  # the action that learns; one episode per occurrence of it after the chain's first action
    share: float  # situations per episode of a scenario
    rounds: int  # gathered in this many rounds, each with the model the previous one retrained


@dataclass(frozen=True)
class TrainingRecipe:
    """What `tailor train DOMAIN` learns."""

    domain: str
    duration_actions: tuple[str, ...]  # each also the name of its experience scenario
    collision_scenario: str  # experience for the collision classifier (Sec. 4.2.2)
    collision_action: str  # the action the classifier guards
    default_episodes: int  # per scenario; chosen so the floors hold and a run takes < 15 min on 2 cores
    fresh_episodes: int = 1000  # fresh episodes the classifier is evaluated on (Table 4.4)
    subgoal_experience: tuple[SubgoalExperience, ...] = ()


TRAINING_DOMAINS: dict[str, TrainingRecipe] = {
    "soccer": TrainingRecipe(
        domain="soccer",
        duration_actions=("goToPose", "approachBall", "dribbleBall"),
        collision_scenario="goToPoseAtBall",
        collision_action="goToPose",
        default_episodes=6000,
        subgoal_experience=(
            SubgoalExperience("score", "dribbleBall", share=0.5, rounds=3),  # approachBall -> dribbleBall
            SubgoalExperience("waypoints", "goToPose", share=1 / 6, rounds=3),  # three goToPose per situation
        ),
    ),
}


def recipe_for(domain: str) -> TrainingRecipe:
    try:
        return TRAINING_DOMAINS[domain]
    except KeyError:
        raise TailorError(f"no training recipe for domain {domain!r} (known: {', '.join(TRAINING_DOMAINS)})") from None


def default_out(domain: str) -> Path:
    return DOMAINS_DIR / domain


Gather = Callable[..., list[Episode]]


def train_domain(
    recipe: TrainingRecipe,
    episodes: int,
    seed: int,
    out: Path,
    jobs: int = 1,
    fresh_episodes: int | None = None,
    progress: bool = True,
    gather: Gather | None = None,
    n_i_candidates: tuple[int, ...] = N_I_CANDIDATES,
    episode_fractions: tuple[float, ...] = EPISODE_FRACTIONS,
) -> dict:
    """Gather, train and write `out/models/*.json` and `out/training/` (report and plots); return the report."""
    if gather is None:
        from tailor.sims.experience import gather
    if episodes < 1:
        raise DataError(f"--episodes must be positive, got {episodes}")
    fresh_episodes = recipe.fresh_episodes if fresh_episodes is None else fresh_episodes
    started = time.perf_counter()

    experience = {}
    for scenario in (*recipe.duration_actions, recipe.collision_scenario):
        experience[scenario] = gather(scenario, episodes, seed=seed, jobs=jobs, progress=progress)
    fresh = gather(recipe.collision_scenario, fresh_episodes, seed=seed + FRESH_SEED_OFFSET, jobs=jobs,
                   progress=progress)
    shared = {e.seed for e in experience[recipe.collision_scenario]} & {e.seed for e in fresh}
    if shared:
        raise DataError(f"fresh and training episodes share seeds {sorted(shared)[:3]}: choose another seed")
    gathered = time.perf_counter()

    fits = len(recipe.duration_actions) * _fits_per_model(n_i_candidates, episode_fractions) + 2
    with tqdm(total=fits, desc="training", unit="fit", disable=not progress) as bar:
        def step(label: str) -> None:
            bar.set_postfix_str(label, refresh=False)
            bar.update(1)

        models = {}
        for action in recipe.duration_actions:
            models[action] = train_duration_model(action, experience[action], seed, step=step,
                                                  n_i_candidates=n_i_candidates,
                                                  episode_fractions=episode_fractions).model
        collision = train_collision_model(recipe.collision_action, experience[recipe.collision_scenario], fresh,
                                          seed, step=step).model
        bar.n = bar.total
        bar.refresh()
    subgoal = [_learn_at_subgoals(recipe.domain, chain, models, experience, round(chain.share * episodes), seed,
                                  jobs, progress, n_i_candidates, episode_fractions)
               for chain in recipe.subgoal_experience]

    report = {
        "schema": "tailor.training_report/2",  # 2: subgoal_experience is a list of chains
        "domain": recipe.domain,
        "seed": seed,
        "episodes_per_scenario": episodes,
        "models": {action: model.report for action, model in models.items()},
        "collision": collision.report,
        "subgoal_experience": [row for row in subgoal if row is not None],
        "gather_seconds": gathered - started,
        "train_seconds": time.perf_counter() - gathered,
    }
    write_outputs(out, models, collision, report)
    return report


def _learn_at_subgoals(domain: str, chain: SubgoalExperience, models: dict, experience: dict, situations: int,
                       seed: int, jobs: int, progress: bool, n_i_candidates, episode_fractions) -> dict | None:
    """Gather episodes of `chain.action` from the subgoals refinement chooses in `situations` situations of the
    chain, and retrain the action's model on its experience plus them (its report then covers both). In rounds:
    each round's subgoals are chosen with the models the previous round retrained, so the optimistic spots a
    retrained model has in turn are visited too (the optimizer's curse moves with the model)."""
    if situations < 1:
        return None
    from tailor.refinement.learning.subgoal_experience import gather_subgoal_experience, subgoal_job

    job = subgoal_job(domain, chain.problem, seed)  # planned once for all rounds
    rounds = max(1, min(chain.rounds, situations))
    bounds = [round(situations * k / rounds) for k in range(rounds + 1)]
    extra: list[Episode] = []
    fits = _fits_per_model(n_i_candidates, episode_fractions)
    for k in range(rounds):
        extra += gather_subgoal_experience(domain, chain.problem, chain.action, models, bounds[k + 1] - bounds[k],
                                           seed, jobs=jobs, progress=progress, first=bounds[k], job=job)
        label = f"retraining {chain.action} ({k + 1}/{rounds})"
        with tqdm(total=fits, desc=label, unit="fit", disable=not progress) as bar:
            models[chain.action] = train_duration_model(chain.action, experience[chain.action] + extra, seed,
                                                        step=lambda _: bar.update(1), n_i_candidates=n_i_candidates,
                                                        episode_fractions=episode_fractions).model
            bar.n = bar.total
            bar.refresh()
    return {"problem": chain.problem, "action": chain.action, "situations": situations, "episodes": len(extra),
            "rounds": rounds, "succeeded": sum(e.succeeded for e in extra)}


def _fits_per_model(n_i_candidates: tuple[int, ...], episode_fractions: tuple[float, ...]) -> int:
    """At most this many fits train one duration model (the bar may finish early: fits are shared)."""
    return 2 * len(n_i_candidates) + len(MIN_SAMPLES_LEAF) + 2 * len(episode_fractions) + 2


def write_outputs(out: Path, models: dict, collision, report: dict) -> None:
    """Stage every file beside its target, then rename them all into place."""
    from tailor.refinement.learning import plots as learning_plots

    models_dir, training_dir = Path(out) / "models", Path(out) / "training"
    files: dict[Path, Callable[[Path], None]] = {}
    for action, model in models.items():
        files[models_dir / f"{action}.json"] = _json_writer(model.to_json())
    files[models_dir / f"{collision.action}{COLLISION_SUFFIX}"] = _json_writer(collision.to_json())
    files[training_dir / "report.json"] = _json_writer(report)
    files[training_dir / "report.txt"] = lambda p: p.write_text(format_report(report, models, collision), "utf-8")
    reports = {action: model.report for action, model in models.items()}
    files[training_dir / "mae_vs_n_i.png"] = lambda p: learning_plots.plot_mae_vs_n_i(reports, p)
    files[training_dir / "mae_vs_episodes.png"] = lambda p: learning_plots.plot_mae_vs_episodes(reports, p)
    files[training_dir / "angle_at_polar.png"] = lambda p: learning_plots.plot_angle_at(models, p)
    files[training_dir / "collision_region.png"] = lambda p: learning_plots.plot_collision_region(collision, p)

    staged: list[tuple[Path, Path]] = []
    try:
        for target, write in files.items():
            target.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(prefix=f".{target.stem}.", suffix=target.suffix, dir=target.parent)
            os.close(fd)
            staged.append((Path(tmp), target))
            write(Path(tmp))
            os.chmod(tmp, FILE_MODE)  # mkstemp makes files private; models and reports are for everyone
        for tmp, target in staged:
            os.replace(tmp, target)
    finally:
        for tmp, _ in staged:
            tmp.unlink(missing_ok=True)


def _json_writer(data: dict) -> Callable[[Path], None]:
    return lambda path: path.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
