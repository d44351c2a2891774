"""Learning a domain's action models end to end (Chapter 4): gather experience, train, write models and report.

The domain's recipe (its binding's [training] table, tailor.refinement.learning.recipe) says which actions get
a duration model, which get a success classifier, from which experience scenario of its simulator, in which
feature space, and which further measures (energy, end error: Ch. 8.1) each duration model's action learns: a
model tree per measure by the same protocol, in the duration model's features, stored in the same file
(measure_models). Everything is computed first and written only at the end, each file to a temporary name that
is renamed over the target once all are complete: an interrupted run leaves the old files untouched.
"""

from __future__ import annotations

import errno
import html
import logging
import os
import signal
import threading
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Self

import numpy as np

from tailor.errors import DataError
from tailor.refinement.learning.classifiers import train_collision_model
from tailor.refinement.learning.duration_protocol import (
    EPISODE_FRACTIONS,
    MIN_SAMPLES_LEAF,
    N_I_CANDIDATES,
    train_duration_model,
)
from tailor.refinement.learning.feature_selection import brought_spaces, generic_space, select_features
from tailor.refinement.learning.recipe import SubgoalExperience, TrainingRecipe
from tailor.refinement.learning.space_comparison import compare_spaces, learning_episodes
from tailor.refinement.learning.html_report import html_report
from tailor.refinement.learning.report import format_report, rules_sections
from tailor.refinement.learning.trust import trust_warnings
from tailor.refinement.models.action_models import COLLISION_SUFFIX, MeasureModel
from tailor.refinement.models.expression_space import AUTO
from tailor.refinement.models.features import resolve
from tailor.sims import registry
from tailor.refinement.models.uncertainty import FOLDS
from tailor import __version__
from tailor.outputs import Provenance, check_output_dir, json_text, provenance_lines, staged_file, write_error
from tailor.progress import finish, stage_bar
from tailor.sims.episode import Episode

FRESH_SEED_OFFSET = 7_919_000  # the fresh test episodes of a classifier use seed + this: no shared episode
# 3: classifiers by action, the simulator named (+ warnings, files); 4: `measures`, the further measures' models
REPORT_SCHEMA = "tailor.training_report/4"

HELD_SIGNALS = (signal.SIGINT, signal.SIGTERM)  # held back once the finished files are renamed (RenameHold)
Gather = Callable[..., list[Episode]]
log = logging.getLogger(__name__)


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
    own_episodes: bool = False,
    companions: dict | None = None,
    compare: bool = False,
    recorded: dict[str, list[Episode]] | None = None,
    provenance: Provenance | None = None,
    hold: RenameHold | None = None,
) -> dict:
    """Gather, train and write `out/models/*.json` and `out/training/` (report and plots); return the report.

    `episodes` per scenario; with `own_episodes` a duration model whose recipe names its own count learns from
    that many of each of its scenarios instead (the first ones of the seed stream: a scenario is gathered once,
    as many as the most any model needs). `gather(simulator, scenario, episodes, seed, jobs, progress)` defaults
    to tailor.sims.experience.gather. `companions` (action -> ActionModel) are models this run does not learn
    that its subgoal experience refines with (`--only`: the domain's others); they are not written. With
    `compare`, each duration model's report holds Fig. 4.3's comparison of feature spaces (space_comparison).
    `recorded` (action -> episodes, e.g. read from logs, learning.logs) replaces gathering: the duration models
    learn from those executions only; success classifiers and subgoal experience, which need the simulator, are
    not learned then. `provenance` (the command's: its line, seeds and the model files it read) leads the report;
    by default it names this call's seed and no command line. `hold`: Ctrl-C and SIGTERM are held back from the
    first rename of the files written until the caller ends it (RenameHold), else until the last rename."""
    if gather is None:
        from tailor.sims.experience import gather
    if episodes < 1:
        raise DataError(f"--episodes must be positive, got {episodes}")
    check_output_dir(out)  # before gathering: a folder we cannot write in must not cost the whole run
    fresh_episodes = recipe.fresh_episodes if fresh_episodes is None else fresh_episodes
    started = time.perf_counter()

    def count(m) -> int:
        return m.episodes if own_episodes and m.episodes is not None else episodes

    if recorded is not None:
        skipped = [c.action for c in recipe.classifiers] + [c.action for c in recipe.subgoal_experience]
        if skipped:
            log.info("learning from recorded executions: no success classifier or subgoal experience (%s), "
                     "they need the simulator", ", ".join(dict.fromkeys(skipped)))
        recipe = replace(recipe, classifiers=(), subgoal_experience=())
    else:
        for m in recipe.models:
            if not m.scenarios:
                raise DataError(f"{m.action}: its [training.models.{m.action}] names no experience scenario and "
                                f"simulator {recipe.simulator!r} has none of that name: learn it from recorded "
                                "executions (`tailor train --log FILE`)")
    needed: dict[str, int] = {}
    for m in (*recipe.models, *recipe.classifiers):
        for scenario in m.scenarios if recorded is None else ():
            needed[scenario] = max(needed.get(scenario, 0), count(m))
    gathered_by_scenario: dict[str, list[Episode]] = {}
    for scenario, n in needed.items():
        gathered_by_scenario[scenario] = gather(recipe.simulator, scenario, n, seed=seed, jobs=jobs,
                                                progress=progress)

    def experience_of(m) -> list[Episode]:
        if recorded is not None:
            return list(recorded.get(m.action, ()))
        return [e for scenario in m.scenarios for e in gathered_by_scenario[scenario][:count(m)]]

    fresh = {}
    for c in recipe.classifiers:
        fresh[c.action] = [e for scenario in c.scenarios
                           for e in gather(recipe.simulator, scenario, fresh_episodes, seed=seed + FRESH_SEED_OFFSET,
                                           jobs=jobs, progress=progress)]
        shared = {e.seed for e in experience_of(c)} & {e.seed for e in fresh[c.action]}
        if shared:
            raise DataError(f"fresh and training episodes share seeds {sorted(shared)[:3]}: choose another seed")
    gathered = time.perf_counter()
    log.debug("gathered the experience of %s in %.1f s", ", ".join(gathered_by_scenario), gathered - started)

    timings: dict[str, dict] = {}
    fits = (len(recipe.models) * _fits_per_model(n_i_candidates, episode_fractions) + 2 * len(recipe.classifiers)
            + sum(len(m.further_measures) for m in recipe.models) * _fits_per_model(MEASURE_N_I, episode_fractions))
    with stage_bar(fits, "training", "fit", progress) as bar:
        def step(label: str) -> None:
            bar.set_postfix_str(label, refresh=False)
            bar.update(1)

        models = {}
        for m in recipe.models:
            models[m.action] = train_action(recipe, m.action, m.feature_space, experience_of(m), seed, step=step,
                                            n_i_candidates=n_i_candidates, episode_fractions=episode_fractions,
                                            jobs=jobs, compare=compare, timings=timings)
        classifiers = {c.action: train_collision_model(c.action, experience_of(c), fresh[c.action], seed,
                                                       c.feature_space, step=step).model
                       for c in recipe.classifiers}
        finish(bar)  # (fits are shared: fewer than the most there may be)
    experience = {m.action: experience_of(m) for m in recipe.models}
    subgoal = []
    for chain in recipe.subgoal_experience:
        refining = {**(companions or {}), **models}  # the chain's situations may need actions not learned here
        subgoal.append(_learn_at_subgoals(recipe, chain, refining, experience, round(chain.share * episodes), seed,
                                          jobs, progress, n_i_candidates, episode_fractions))
        models[chain.action] = refining[chain.action]

    if provenance is None:  # a library call: no command line
        provenance = Provenance(__version__, (), (("seed", seed),))
    report = {
        "schema": REPORT_SCHEMA,
        "provenance": provenance.to_json(),
        "domain": recipe.domain,
        "simulator": recipe.simulator,
        "seed": seed,
        "episodes_per_scenario": episodes,
        "experience": "simulator" if recorded is None else "recorded executions",
        "models": {action: model.report for action, model in models.items()},
        # per action, its further measures' reports (the same rows as a duration model's, `mean` and `range` in
        # the measure's unit)
        "measures": {action: {name: m.report for name, m in getattr(model, "measures", {}).items()}
                     for action, model in models.items() if getattr(model, "measures", None)},
        "classifiers": {action: model.report for action, model in classifiers.items()},
        "subgoal_experience": [row for row in subgoal if row is not None],
        "gather_seconds": gathered - started,
        "train_seconds": time.perf_counter() - gathered,
        "model_seconds": timings,  # per duration model: feature selection, the protocol, measures, Fig. 4.3
    }
    log.debug("trained %s in %.1f s", ", ".join([*models, *(f"{a} classifier" for a in classifiers)]),
              report["train_seconds"])
    report["warnings"] = trust_warnings(report)
    write_outputs(out, recipe, models, classifiers, report, hold)
    return report


def train_action(recipe: TrainingRecipe, action: str, feature_space: str, episodes: list[Episode], seed: int,
                 compare: bool = True, jobs: int = 1, timings: dict | None = None, **protocol):
    """One duration model: its features chosen automatically where the recipe says "auto" (on the learning
    episodes only), the protocol of Fig. 4.9, and, with `compare`, Fig. 4.3's comparison of feature spaces;
    the report records the chosen features (formulas and units) and the selection; `timings[action]` the seconds
    the selection, the protocol and the comparison took."""
    entry = registry.get(recipe.simulator)
    spec = recipe.specs[action]
    selection = None
    if feature_space == AUTO or compare:
        others = None if recipe.own_spaces else {}  # None: the simulator's own spaces compete
        selection = select_features(spec, entry, learning_episodes(episodes, seed), seed, others=others, jobs=jobs)
    space = feature_space
    if feature_space == AUTO:
        space = selection.space if selection.space is not None else selection.named
    selected = time.perf_counter()  # the selection's own time is its report's "seconds"
    model = train_duration_model(action, episodes, seed, space, spec.observed, jobs=jobs, **protocol).model
    duration_trained = time.perf_counter()
    further = next((m.further_measures for m in recipe.models if m.action == action), ())
    if further:
        model = replace(model, measures=measure_models(action, further, space, episodes, seed, spec.observed, entry,
                                                       jobs=jobs, **protocol))
    trained = time.perf_counter()
    report = getattr(model, "report", {})  # (a stand-in model without a report records nothing)
    if selection is not None:
        report["feature_selection"] = {k: v for k, v in selection.report.items() if k != "seconds"}
    if getattr(model, "expressions", None) is not None:
        report["features"] = model.expressions.describe()
    if timings is not None:  # beside the models, not in them: a model file is the same for the same seed
        timings[action] = {"selection": selection.report["seconds"] if selection is not None else 0.0,
                           "selection_for": feature_space if feature_space == AUTO else "comparison",
                           "protocol": duration_trained - selected,  # the duration model's
                           "measures": trained - duration_trained if further else 0.0}  # the further measures' models
    if compare:
        spaces = {}
        generic = generic_space(spec, entry)
        if generic is not None:
            spaces["generic"] = generic.feature_space("generic row")
        expert = None if feature_space == AUTO else resolve(feature_space)
        if expert is None:
            brought = brought_spaces(entry, spec)
            sets = selection.report["candidate_sets"]
            best = min((name for name in sets if name in brought), key=sets.get, default=None)
            expert = brought[best] if best is not None else None
        if expert is not None:
            spaces["expert"] = expert
        spaces["auto"] = selection.generated.feature_space()  # the generated set, whichever set the model uses
        comparison = compare_spaces(episodes, seed, spec.observed, model.n_i, spaces, tuple(spec.parameters), jobs)
        if timings is not None:
            timings[action]["comparison"] = comparison["seconds"]
        report["space_comparison"] = {k: v for k, v in comparison.items() if k != "seconds"}
    return model


MEASURE_N_I = (1,)  # a measure model learns from the first example of each episode (measure_episodes)


def measure_episodes(action: str, episodes: list[Episode], measure: str) -> list[Episode]:
    """The episodes as the duration protocol sees them for `measure`: each successful one with the measure in
    place of its duration and only its first logged row (an episode's log does not say how much of a measure a
    later row had still to spend, as it says how much time: only the whole episode's is known); failed ones as
    they are (counted, not learned from). A DataError where a successful episode reports no such measure
    (experience gathered, or a log written, before measures were recorded)."""
    out, missing, used = [], 0, 0
    for e in episodes:
        if not e.succeeded:
            out.append(e)
            continue
        if measure not in e.measures:
            missing += 1
            continue
        used += 1
        out.append(replace(e, duration=float(e.measures[measure]), t=np.zeros(1), state=e.state[:1]))
    if missing:
        raise DataError(f"{action}: {missing} of its {missing + used} successful episodes report no measure "
                        f"{measure!r} (experience gathered, or a log written, before measures were recorded: gather "
                        "it again, e.g. into a new --experience folder)")
    values = [e.duration for e in out if e.succeeded]
    if values and max(values) <= 0:
        raise DataError(f"{action}: its measure {measure!r} is 0 in every successful episode: nothing to learn")
    return out


def measure_models(action: str, measures: tuple[str, ...], space, episodes: list[Episode], seed: int,
                   observed: tuple[str, ...], entry, jobs: int = 1, n_i_candidates=None, **protocol) -> dict:
    """A MeasureModel per measure: the duration protocol (Fig. 4.9: split, leaf size on validation, held-out MAE
    beside gradient boosting, the final tree on all episodes, its leaves' held-out spread) run on
    `measure_episodes`, in the duration model's feature space `space` (so one file holds one set of features);
    n_i is 1 (MEASURE_N_I). Each report names its measure and unit and gives `mean` and `range` of the measure
    where a duration model's report gives them of the duration."""
    del n_i_candidates  # one example per episode: see measure_episodes
    out = {}
    for measure in measures:
        trained = train_duration_model(f"{action} {measure}", measure_episodes(action, episodes, measure), seed,
                                       space, observed, n_i_candidates=MEASURE_N_I, jobs=jobs, **protocol).model
        report = dict(trained.report)
        mean, seen = report.pop("mean_duration"), report.pop("duration_range")
        report.pop("simulated_hours", None)  # (the sum of the measure, not time)
        unit = entry.quantity(measure).unit
        report = {"action": action, "measure": measure, "unit": unit, "mean": mean, "range": seen,
                  **{k: v for k, v in report.items() if k != "action"}}
        out[measure] = MeasureModel(measure, unit, trained.duration, trained.n_i, report, trained.uncertainty)
    return out


def _learn_at_subgoals(recipe: TrainingRecipe, chain: SubgoalExperience, models: dict, experience: dict,
                       situations: int, seed: int, jobs: int, progress: bool, n_i_candidates,
                       episode_fractions) -> dict | None:
    """Gather episodes of `chain.action` from the subgoals refinement chooses in `situations` situations of the
    chain, and retrain the action's model on its experience plus them (its report then covers both). In rounds:
    each round's subgoals are chosen with the models the previous round retrained, so the optimistic spots a
    retrained model has in turn are visited too (the optimizer's curse moves with the model)."""
    if situations < 1:
        return None
    from tailor.refinement.learning.subgoal_experience import gather_subgoal_experience

    model_recipe = next(m for m in recipe.models if m.action == chain.action)
    planned: dict = {}  # each problem planned once for all rounds
    rounds = max(1, min(chain.rounds, situations))
    bounds = [round(situations * k / rounds) for k in range(rounds + 1)]
    extra: list[Episode] = []
    fits = (_fits_per_model(n_i_candidates, episode_fractions)
            + len(model_recipe.further_measures) * _fits_per_model(MEASURE_N_I, episode_fractions))
    for k in range(rounds):
        extra += gather_subgoal_experience(recipe.domain_dir, chain.situations, chain.action, models,
                                           bounds[k + 1] - bounds[k], seed, jobs=jobs, progress=progress,
                                           first=bounds[k], planned=planned)
        label = f"retraining {chain.action} ({k + 1}/{rounds})"
        with stage_bar(fits, label, "fit", progress) as bar:
            before = getattr(models[chain.action], "report", None) or {}
            models[chain.action] = train_action(
                recipe, chain.action, model_recipe.feature_space, experience[chain.action] + extra, seed,
                compare=False, step=lambda _: bar.update(1), n_i_candidates=n_i_candidates,
                episode_fractions=episode_fractions, jobs=jobs)
            after = getattr(models[chain.action], "report", None)
            if after is not None and "space_comparison" in before:  # Fig. 4.3 of the scenarios' experience, as first trained
                after["space_comparison"] = {**before["space_comparison"], "experience": "scenarios"}
            if "feature_selection" in before and "feature_selection" not in after:
                after["feature_selection"] = before["feature_selection"]
            finish(bar)
    return {"generator": chain.situations, "action": chain.action, "situations": situations, "episodes": len(extra),
            "rounds": rounds, "succeeded": sum(e.succeeded for e in extra)}


def _fits_per_model(n_i_candidates: tuple[int, ...], episode_fractions: tuple[float, ...]) -> int:
    """At most this many fits train one duration model (the bar may finish early: fits are shared)."""
    return 2 * len(n_i_candidates) + len(MIN_SAMPLES_LEAF) + 2 * len(episode_fractions) + 2 + FOLDS


REPORT_FILES = {  # the report files beside report.json, and what each holds (named by `tailor train`)
    "report.html": "tables, learning curves, pictures and rules in one page",
    "report.txt": "tables and the full rules as text",
}


def training_files(out: Path, recipe: TrainingRecipe, models: dict, classifiers: dict,
                   report: dict) -> dict[Path, Callable[[Path], None]]:
    """Every file a training run writes, with the function that writes it. The figures are drawn here, once:
    the same PNG bytes are written as files and embedded in the HTML report."""
    from tailor.refinement.learning import plots

    models_dir, training_dir = Path(out) / "models", Path(out) / "training"
    files: dict[Path, Callable[[Path], None]] = {}
    for action, model in models.items():
        files[models_dir / f"{action}.json"] = _json_writer(model.to_json())
    for action, classifier in classifiers.items():
        files[models_dir / f"{action}{COLLISION_SUFFIX}"] = _json_writer(classifier.to_json())
    figures = {name: (plots.png_bytes(draw), plots.caption(name, recipe.simulator))
               for name, draw in plots.training_plots(recipe.simulator, models, classifiers).items()}
    warnings = report.get("warnings", [])
    files[training_dir / "report.json"] = _json_writer(report)
    origin = provenance_lines(report.get("provenance", {}))
    files[training_dir / "report.html"] = lambda p: p.write_text(
        html_report(report, rules_sections(models, classifiers), figures, warnings).replace(
            "\n</body>", "\n<footer><p class=\"note\">" + "<br>".join(html.escape(line) for line in origin)
            + "</p></footer>\n</body>", 1), "utf-8")
    files[training_dir / "report.txt"] = lambda p: p.write_text(
        format_report(report, models, classifiers, warnings) + "\n".join(["Provenance:", *origin, ""]), "utf-8")
    for name, (png, _) in figures.items():
        files[training_dir / name] = lambda p, png=png: p.write_bytes(png)
    return files


def write_outputs(out: Path, recipe: TrainingRecipe, models: dict, classifiers: dict, report: dict,
                  hold: RenameHold | None = None) -> list[Path]:
    """Stage every file beside its target, then rename them all into place (signals held: _rename_all);
    `report["files"]` lists them (relative to `out`). Returns the files written."""
    files = training_files(out, recipe, models, classifiers, report)
    report["files"] = [target.relative_to(Path(out)).as_posix() for target in files]
    staged: list[tuple[Path, Path]] = []
    for target in files:  # a folder where a file goes would fail the renames: name it before writing anything
        if target.is_dir():
            raise write_error(target, IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR)))
    target = Path(out)
    try:
        for target, write in files.items():
            target.parent.mkdir(parents=True, exist_ok=True)
            tmp = staged_file(target)  # the permissions of a new file (0666 less the umask), not mkstemp's 0600
            staged.append((tmp, target))
            write(tmp)
        _rename_all(staged, hold)
    except OSError as exc:
        raise write_error(target, exc) from None
    finally:
        for tmp, _ in staged:
            tmp.unlink(missing_ok=True)
    return list(files)


def _rename_all(staged: list[tuple[Path, Path]], hold: RenameHold | None = None) -> None:
    """Rename every staged file over its target with Ctrl-C and SIGTERM held back (RenameHold): once the renames
    begin they all complete, and the run ends as done, so the status reported matches what is on disk. Held
    until `hold` ends, the caller's (which may have more to finish: the CLI stops its workers); without one,
    until the last rename."""
    if hold is None:
        with RenameHold() as own:
            _rename_all(staged, own)
        return
    hold.begin()
    for tmp, target in staged:
        os.replace(tmp, target)


class RenameHold:
    """Ctrl-C and SIGTERM dropped from begin() (the first rename of the finished files) until end() (or the end of
    the `with`): a signal then would interrupt work that is done, or the shutting down after it, and report as
    interrupted a run whose files are all in place. Before and after, the handlers in place apply. Python runs
    signal handlers in the main thread only, so swapping them there holds a signal back whichever thread the
    kernel delivers it to; in another thread begin() only records that the renames began (`begun`)."""

    def __init__(self) -> None:
        self.begun = False
        self._previous: dict[int, object] = {}

    def begin(self) -> None:
        if not self.begun and threading.current_thread() is threading.main_thread():
            for signum in HELD_SIGNALS:  # each handler noted before it is swapped: end() puts back whatever was
                self._previous[signum] = signal.getsignal(signum)  # swapped, should a signal cut this short
                signal.signal(signum, _hold)
        self.begun = True

    def end(self) -> None:
        previous, self._previous = self._previous, {}
        for signum, handler in previous.items():
            signal.signal(signum, signal.SIG_DFL if handler is None else handler)  # (None: set outside Python)

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        self.end()


def _hold(signum, frame) -> None:
    """A signal arriving while the finished files are renamed into place (or after, see RenameHold): dropped."""


def _json_writer(data: dict) -> Callable[[Path], None]:
    return lambda path: path.write_text(json_text(data) + "\n", encoding="utf-8")
