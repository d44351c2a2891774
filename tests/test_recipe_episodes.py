"""A duration model may learn from more episodes than the recipe's default (`episodes` in its
[training.models.ACTION] table): how many are gathered, and which each model learns from."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import pytest

from tailor.errors import BindingError
from tailor.planner_bridge.bundled import DOMAINS_DIR
from tailor.refinement.learning import training
from tailor.refinement.learning.recipe import load_recipe

SOCCER = DOMAINS_DIR / "soccer"


def test_the_soccer_recipe_gives_approach_ball_its_own_episodes():
    recipe = load_recipe(SOCCER)
    own = {m.action: m.episodes for m in recipe.models}
    assert own == {"goToPose": None, "approachBall": 24000, "dribbleBall": None, "goToPosition": None}
    assert all(c.episodes is None for c in recipe.classifiers)


def _run(tmp_path, monkeypatch, own_episodes: bool) -> tuple[list, dict]:
    gathered, learned = [], {}

    def gather(simulator, scenario, episodes, seed, jobs, progress):
        gathered.append((scenario, episodes))
        return [SimpleNamespace(scenario=scenario, index=i, seed=(scenario, seed, i), succeeded=True)
                for i in range(episodes)]

    def train(action, episodes, seed, feature_space, observed, **kwargs):
        learned[action] = [e.index for e in episodes]
        return SimpleNamespace(model=SimpleNamespace(report={}))

    monkeypatch.setattr(training, "train_duration_model", train)
    monkeypatch.setattr(training, "train_collision_model",
                        lambda action, episodes, fresh, *a, **k: SimpleNamespace(model=SimpleNamespace(report={})))
    monkeypatch.setattr(training, "_learn_at_subgoals", lambda *a, **k: None)
    monkeypatch.setattr(training, "write_outputs", lambda *a, **k: [])
    monkeypatch.setattr(training, "trust_warnings", lambda report: [])
    recipe = load_recipe(SOCCER)  # (the duration alone: the stand-in episodes have no measures)
    recipe = replace(recipe, models=tuple(replace(m, episodes=10 if m.action == "approachBall" else m.episodes,
                                                  measures=("duration",)) for m in recipe.models))
    training.train_domain(recipe, 4, 0, tmp_path, fresh_episodes=2, progress=False, gather=gather,
                          own_episodes=own_episodes)
    return gathered, learned


def test_a_model_with_its_own_episodes_learns_from_the_first_that_many(tmp_path, monkeypatch):
    gathered, learned = _run(tmp_path, monkeypatch, own_episodes=True)
    assert ("approachBall", 10) in gathered and ("goToPose", 4) in gathered
    assert learned["approachBall"] == list(range(10)) and learned["goToPose"] == list(range(4))


def test_an_explicit_episode_count_applies_to_every_model(tmp_path, monkeypatch):
    """`tailor train --episodes N` (own_episodes off): N of every scenario, the models' own counts ignored."""
    gathered, learned = _run(tmp_path, monkeypatch, own_episodes=False)
    assert ("approachBall", 4) in gathered and learned["approachBall"] == list(range(4))


def test_a_bad_own_episode_count_is_one_line(tmp_path):
    domain = tmp_path / "soccer"
    domain.mkdir()
    for f in SOCCER.iterdir():
        if f.is_file():
            (domain / f.name).write_bytes(f.read_bytes())
    toml = domain / "actions.toml"
    toml.write_text(toml.read_text().replace("episodes = 24000", "episodes = 0"))
    with pytest.raises(BindingError, match=r"models\.approachBall episodes must be a positive integer, not 0"):
        load_recipe(domain)


def _recipe_with(training_table: dict):
    from tailor.refinement.binding import load_domain_binding
    from tailor.refinement.learning.recipe import recipe_from_binding

    binding = load_domain_binding(SOCCER)
    return recipe_from_binding(replace(binding, training=training_table), SOCCER)


def test_a_model_that_names_no_feature_space_learns_on_generated_features():
    recipe = _recipe_with({"models": {"goToPose": {"scenario": "goToPose"}, "dribbleBall": {"feature_space": "auto"},
                                      "approachBall": {"feature_space": "approach"}}})
    assert {m.action: m.feature_space for m in recipe.models} == {"goToPose": "auto", "dribbleBall": "auto",
                                                                   "approachBall": "approach"}


def test_a_classifier_still_names_its_feature_space():
    with pytest.raises(BindingError, match=r"classifiers.goToPose feature_space = 'auto' is not a feature space"):
        _recipe_with({"models": {"goToPose": {}}, "classifiers": {"goToPose": {"feature_space": "auto"}}})
    with pytest.raises(BindingError, match=r"feature_space = 'posee' is not a feature space \(known: .*auto"):
        _recipe_with({"models": {"goToPose": {"feature_space": "posee"}}})
