"""The training recipe of a domain: data in its binding's `[training]` table, read here.

    [training]
    episodes = 6000            # per scenario, the default of `tailor train`
    fresh_episodes = 1000      # fresh episodes each classifier is evaluated on (Table 4.4)

    [training.models.navigate]         # a duration model per executable action ...
    scenario = "navigate"              # ... learned from this experience scenario (or a list of them)
    feature_space = "pose"             # ... in this feature space (Table 4.1); "auto" (the default where none is
                                       # named): features generated from the action's quantities and selected
                                       # by cross-validated error (learning.feature_selection)
    episodes = 24000                   # optional: this many of each of its scenarios (default: episodes above)
    measures = ["duration", "energy", "error"]   # optional: a model tree per measure (default: duration only),
                                       # each a measure the simulator's episodes report (Ch. 8.1), stored in
                                       # the action's one model file (models.action_models)

    [training.classifiers.navigate]    # a success classifier (Sec. 4.2.2), optional
    scenario = "navigateToObject"
    feature_space = "pose"

    [[training.subgoal_experience]]    # optional: experience at refined subgoals (Sec. 8.1)
    situations = "tour"                # the simulator's situation generator drawing the chains
    action = "navigate"                # the action that learns from it
    share = 0.5                        # situations per episode of a scenario
    rounds = 3                         # gathered in rounds, each with the model the round before retrained
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from tailor.refinement.binding import Binding, known_measures, load_domain_binding
from tailor.refinement.binding_domain import did_you_mean
from tailor.errors import BindingError
from tailor.refinement.models.expression_space import AUTO
from tailor.refinement.models.features import feature_spaces
from tailor.refinement.objective_grammar import DURATION
from tailor.sims.experience import MAX_EPISODES
from tailor.sims.protocol import ActionSpec


@dataclass(frozen=True)
class ModelRecipe:
    """A learned model of `action` (a duration model tree or a success classifier)."""

    action: str
    scenarios: tuple[str, ...]  # experience scenarios whose episodes it learns from, together
    feature_space: str
    episodes: int | None = None  # episodes of each scenario it learns from; None: the recipe's (duration models)
    measures: tuple[str, ...] = (DURATION,)  # a model tree per measure (duration models; the duration first)

    @property
    def further_measures(self) -> tuple[str, ...]:
        """The measures learned besides the duration."""
        return tuple(m for m in self.measures if m != DURATION)


@dataclass(frozen=True)
class SubgoalExperience:
    """`action` also learns from episodes that start at the subgoals refinement chooses in random situations
    drawn by the simulator's situation generator `situations` (Sec. 8.1, learning.subgoal_experience)."""

    situations: str
    action: str
    share: float
    rounds: int


@dataclass(frozen=True)
class TrainingRecipe:
    """What `tailor train DOMAIN` learns, and where the domain's data lies."""

    domain: str
    domain_dir: Path
    simulator: str
    models: tuple[ModelRecipe, ...]
    classifiers: tuple[ModelRecipe, ...]
    episodes: int
    fresh_episodes: int
    subgoal_experience: tuple[SubgoalExperience, ...]
    specs: Mapping[str, ActionSpec]  # the simulator's actions
    own_spaces: bool = True  # the simulator's own feature spaces compete in feature selection

    @property
    def duration_actions(self) -> tuple[str, ...]:
        return tuple(m.action for m in self.models)


def recipe_from_binding(binding: Binding, domain_dir: Path) -> TrainingRecipe:
    """Validate the binding's [training] table; every problem is a one-line BindingError naming the file."""

    def fail(message: str) -> BindingError:
        return BindingError(f"[training] {message}", file=binding.file)

    table = binding.training
    if not table:
        raise fail("missing: the domain's binding says nothing about what to learn (add a [training] table)")
    _keys(table, {"episodes", "fresh_episodes", "models", "classifiers", "subgoal_experience"}, "", fail)
    entry = binding.entry
    episodes = _positive_int(table.get("episodes", 1000), "episodes", fail)
    fresh = _positive_int(table.get("fresh_episodes", 1000), "fresh_episodes", fail)
    models = _models(table.get("models"), "models", entry, fail)
    if not models:
        raise fail("models: no [training.models.ACTION] table: nothing to learn")
    classifiers = _models(table.get("classifiers", {}), "classifiers", entry, fail)
    chains = []
    raw_chains = table.get("subgoal_experience", [])
    if not isinstance(raw_chains, list):
        raise fail("subgoal_experience must be an array of tables ([[training.subgoal_experience]])")
    for k, chain in enumerate(raw_chains):
        where = f"subgoal_experience[{k}]"
        if not isinstance(chain, dict):
            raise fail(f"{where} must be a table")
        _keys(chain, {"situations", "action", "share", "rounds"}, where, fail)
        action = chain.get("action")
        if not isinstance(action, str) or action not in {m.action for m in models}:
            raise fail(f"{where} action = {action!r} has no duration model to retrain")
        situations = chain.get("situations")
        if not isinstance(situations, str) or situations not in entry.situations:
            raise fail(f"{where} situations = {situations!r} is not a situation generator of simulator "
                       f"{entry.name!r} (known: {', '.join(entry.situations) or 'none'})")
        share = chain.get("share", 0.5)
        if isinstance(share, bool) or not isinstance(share, (int, float)) or not 0 <= share <= 10:
            raise fail(f"{where} share must be a number in [0, 10], not {share!r}")
        if entry.subgoal_episode is None:
            raise fail(f"{where}: simulator {entry.name!r} cannot start episodes at subgoals")
        chains.append(SubgoalExperience(situations, action, float(share),
                                        _positive_int(chain.get("rounds", 1), f"{where} rounds", fail)))
    return TrainingRecipe(binding.domain or Path(domain_dir).name, Path(domain_dir), entry.name, models, classifiers,
                          episodes, fresh, tuple(chains), entry.actions)


def black_box(recipe: TrainingRecipe) -> TrainingRecipe:
    """The recipe as for a robot whose controller tailor does not know: every duration model on generated
    features (Sec. 4.1.1), the simulator's own feature spaces neither chosen nor competing. Success classifiers
    keep their spaces (a decision tree learns on a named space only)."""
    return replace(recipe, models=tuple(replace(m, feature_space=AUTO) for m in recipe.models), own_spaces=False)


def load_recipe(domain_dir: Path) -> TrainingRecipe:
    """The recipe in the binding of the domain in `domain_dir`."""
    return recipe_from_binding(load_domain_binding(domain_dir), Path(domain_dir))


def _keys(table: Mapping[str, Any], allowed: set[str], where: str, fail) -> None:
    for key in table:
        if key not in allowed:
            raise fail(f"{where + ': ' if where else ''}unknown key '{key}' (expected one of "
                       f"{', '.join(sorted(allowed))}){did_you_mean(key, allowed)}")


def _positive_int(value: Any, where: str, fail) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise fail(f"{where} must be a positive integer, not {value!r}")
    if "episodes" in where and value > MAX_EPISODES:
        raise fail(f"{where} = {value} is more than {MAX_EPISODES:,} episodes")
    return value


def _models(section: Any, key: str, entry, fail) -> tuple[ModelRecipe, ...]:
    if section is None:
        return ()
    if not isinstance(section, dict):
        raise fail(f"'{key}' must be a table of tables ([training.{key}.ACTION])")
    out = []
    for action, table in section.items():
        where = f"{key}.{action}"
        if not isinstance(table, dict):
            raise fail(f"[training.{where}] must be a table")
        _keys(table, {"scenario", "feature_space", "episodes", "measures"} if key == "models"
              else {"scenario", "feature_space"}, where, fail)
        if action not in entry.actions:
            raise fail(f"{where}: {action!r} is not an action of simulator {entry.name!r} "
                       f"(known: {', '.join(entry.actions)})")
        # without a scenario named, the action's own; none where the simulator has none (a real robot's
        # binding: its models learn from recorded executions, `tailor train --log`)
        scenarios = table.get("scenario", action if action in entry.scenarios else [])
        scenarios = [scenarios] if isinstance(scenarios, str) else scenarios
        if "scenario" in table and (not isinstance(scenarios, list) or not scenarios):
            raise fail(f"{where} scenario must be a scenario name or a non-empty list of them")
        for scenario in scenarios:
            if not isinstance(scenario, str) or scenario not in entry.scenarios:
                raise fail(f"{where} scenario = {scenario!r} is not an experience scenario of simulator "
                           f"{entry.name!r} (known: {', '.join(entry.scenarios)})")
            if entry.scenarios[scenario].action != action:
                raise fail(f"{where} scenario = {scenario!r} runs {entry.scenarios[scenario].action}, not {action}")
        space = table.get("feature_space", AUTO if key == "models" else None)
        spaces = feature_spaces()
        measures = _measures(table.get("measures", [DURATION]), where, entry, fail)
        if space == AUTO and key == "models":
            episodes = _positive_int(table["episodes"], f"{where} episodes", fail) if "episodes" in table else None
            out.append(ModelRecipe(action, tuple(scenarios), AUTO, episodes, measures))
            continue
        if not isinstance(space, str) or space not in spaces:
            known = ", ".join(sorted(spaces) + ([AUTO] if key == "models" else []))
            raise fail(f"{where} feature_space = {space!r} is not a feature space (known: {known})")
        if len(spaces[space].parameters) != len(entry.actions[action].parameters):
            raise fail(f"{where} feature_space = {space!r} reads {len(spaces[space].parameters)} parameters, "
                       f"{action} has {len(entry.actions[action].parameters)}")
        episodes = _positive_int(table["episodes"], f"{where} episodes", fail) if "episodes" in table else None
        out.append(ModelRecipe(action, tuple(scenarios), space, episodes, measures))
    return tuple(out)



def _measures(value: Any, where: str, entry, fail) -> tuple[str, ...]:
    """A model's `measures` list: names of measures of the simulator, the duration among them, none twice."""
    if not isinstance(value, list) or not value or not all(isinstance(m, str) for m in value):
        raise fail(f"{where} measures must be a non-empty list of measure names, e.g. "
                   f"[\"duration\", \"energy\"], not {value!r}")
    known = known_measures(entry)
    for measure in value:
        if measure not in known:
            raise fail(f"{where} measures: {measure!r} is not a measure of simulator {entry.name!r} (known: "
                       f"{', '.join(known)}){did_you_mean(measure, known)}")
    if len(set(value)) != len(value):
        raise fail(f"{where} measures names a measure twice: {value}")
    if DURATION not in value:
        raise fail(f"{where} measures must include \"duration\": every action model predicts it (the others "
                   "are stored beside it)")
    return (DURATION, *(m for m in value if m != DURATION))
