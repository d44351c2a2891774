"""Experience at refined subgoals (Sec. 8.1): a reproducible stream of situations, gathered in rounds."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from planner_bridge.bundled import DOMAINS_DIR
from refinement import training
from refinement.action_models import load_action_models
from refinement.subgoal_experience import gather_subgoal_experience


def test_consecutive_ranges_continue_one_stream_of_situations():
    models = load_action_models(DOMAINS_DIR / "soccer" / "models")
    whole = gather_subgoal_experience("soccer", "score", models, 4, seed=3, progress=False)
    parts = (gather_subgoal_experience("soccer", "score", models, 2, seed=3, progress=False)
             + gather_subgoal_experience("soccer", "score", models, 2, seed=3, progress=False, first=2))
    assert [e.action for e in whole] == ["dribbleBall"] * 4
    assert len({tuple(e.params) for e in whole}) == 4  # four different situations
    for a, b in zip(whole, parts):
        np.testing.assert_array_equal(a.params, b.params)
        assert (a.duration, a.outcome) == (b.duration, b.outcome)


def test_each_round_chooses_subgoals_with_the_model_the_round_before_retrained(monkeypatch):
    seen, trained = [], []

    def gather(domain, problem, models, episodes, seed, jobs=1, progress=True, first=0, job=None):
        seen.append((models["dribbleBall"], first, episodes))
        return [SimpleNamespace(action="dribbleBall", succeeded=True, index=first + i) for i in range(episodes)]

    def train(action, episodes, seed, **kwargs):
        model = f"model {len(trained)} on {len(episodes)}"
        trained.append(model)
        return SimpleNamespace(model=model)

    monkeypatch.setattr("refinement.subgoal_experience.gather_subgoal_experience", gather)
    monkeypatch.setattr("refinement.subgoal_experience.subgoal_job", lambda domain, problem, seed: "job")
    monkeypatch.setattr(training, "train_duration_model", train)
    recipe = training.TRAINING_DOMAINS["soccer"]
    models = {"dribbleBall": "first model"}
    report = training._learn_at_subgoals(recipe, models, {"dribbleBall": ["own"] * 10}, 7, 0, 1, False, (1,), (1.0,))

    assert recipe.subgoal_rounds == 3
    assert seen == [("first model", 0, 2), ("model 0 on 12", 2, 3), ("model 1 on 15", 5, 2)]
    assert models["dribbleBall"] == "model 2 on 17"  # the last retraining used all 7 subgoal episodes
    assert report == {"problem": "score", "action": "dribbleBall", "episodes": 7, "rounds": 3, "succeeded": 7}
