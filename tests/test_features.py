"""Feature spaces (Table 4.1): the registry, the generic "line" space, every registered space's invariance test,
the spaces the bundled domains name; and intermediate examples (Sec. 4.1.2)."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

from tailor.errors import DataError
from tailor.refinement.models.features import (
    FEATURE_SPACES,
    compute_features,
    feature_names,
    feature_space,
    feature_spaces,
    first_examples,
    intermediate_examples,
)
from tailor.sims import registry
from tailor.sims.episode import Episode
from synthetic_episodes import COLUMNS

ROOT = Path(__file__).resolve().parent.parent


def test_the_core_brings_only_spaces_of_no_particular_robot():
    """A robot's rows of Table 4.1 (a pose, joints) come with its package; the arm's own space is its "ramps"."""
    assert tuple(FEATURE_SPACES) == ("line",)
    assert feature_names("line") == ("dist", "v", "vg")
    assert feature_space("ramps") is next(s for s in registry.get("arm").feature_spaces if s.name == "ramps")
    assert not {"reach", "joints"} & set(feature_spaces())


def test_the_line_space_by_hand():
    params = np.array([[0.0, 0.5, 2.0, 0.1], [3.0, 0.5, 1.0, -0.2], [1.0, -0.3, 1.0, 0.4]])
    expected = np.array([[2.0, 0.5, 0.1], [2.0, -0.5, 0.2], [0.0, -0.3, 0.4]])  # signed toward the goal (+ at 0)
    np.testing.assert_allclose(compute_features("line", params), expected)


def _named_spaces() -> list[tuple[str, str]]:
    """(file, feature space) for every space a bundled binding or model file names."""
    named = []
    for binding in sorted(ROOT.glob("domains/*/actions.toml")):
        training = tomllib.loads(binding.read_text(encoding="utf-8")).get("training", {})
        for kind in ("models", "classifiers"):
            for table in training.get(kind, {}).values():
                named.append((binding.relative_to(ROOT).as_posix(), table["feature_space"]))
    for model in sorted(ROOT.glob("domains/*/models/*.json")):
        data = json.loads(model.read_text(encoding="utf-8"))
        for space in [data.get("feature_space", data.get("feature_set"))] + [
                w.get("feature_space", w.get("feature_set")) for w in data.get("window", [])]:
            if space is not None:
                named.append((model.relative_to(ROOT).as_posix(), space))
    return named


def test_every_feature_space_the_bundled_domains_name_resolves():
    named = _named_spaces()
    assert {space for _, space in named} >= {"goto", "approach", "dribble", "position", "pose_walls", "ramps",
                                             "route", "grasp"}
    for source, space in named:
        assert feature_space(space).name == space, source


@pytest.mark.parametrize("name", sorted(feature_spaces()))
def test_every_feature_space_passes_its_own_invariance_test(name):
    """The generic spaces and those the installed simulators bring (the arm's ramps)."""
    space = feature_spaces()[name]
    rng = np.random.default_rng(4)
    params = rng.uniform(-3.0, 3.0, (300, len(space.parameters)))
    before = space(params)
    finite = np.isfinite(before).all(axis=1)  # (the kitchen's route is inf where no route exists: a pose outside
    assert before.shape == (300, len(space.names)) and finite.mean() >= (0.95 if name == "route" else 1.0)  # rooms)
    assert space.transform is not None, f"{name} declares no invariance test ({space.invariance})"
    for _ in range(5):
        moved = space.transform(params, rng)
        assert not np.allclose(moved, params)  # the transform changes the parameters ...
        np.testing.assert_allclose(space(moved), before, atol=1e-9)  # ... but not the features


def test_compute_features_rejects_bad_input():
    with pytest.raises(ValueError, match=r"shape \(n, 4\)"):
        compute_features("line", np.zeros((3, 7)))
    with pytest.raises(DataError, match=r"unknown feature space 'speed' \(known: .*line.*\)"):
        compute_features("speed", np.zeros((1, 8)))
    assert compute_features("line", np.zeros(4)).shape == (1, 3)


def make_episode(rows: int, duration: float, seed: int = 0) -> Episode:
    t = np.arange(rows) * 0.1
    robot = np.column_stack([np.arange(rows) + 100.0 * seed, np.zeros(rows), np.zeros(rows), np.full(rows, 0.5)])
    state = np.column_stack([robot, np.full((rows, 2), np.nan)])  # no ball
    params = np.array([100.0 * seed, 0.0, 0.0, 0.5, 9.0, 1.0, 0.5, 0.2])
    return Episode("goToPose", params, t, state, COLUMNS, "success", duration, seed)


def test_intermediate_examples_take_the_first_n_i_rows_of_each_episode():
    episodes = [make_episode(5, 0.45, seed=0), make_episode(2, 0.15, seed=1)]
    params, targets, owner = intermediate_examples(episodes, 3, observed=("x", "y", "phi", "v"))
    np.testing.assert_array_equal(owner, [0, 0, 0, 1, 1])  # the short episode gives all it has
    np.testing.assert_allclose(targets, [0.45, 0.35, 0.25, 0.15, 0.05])
    np.testing.assert_array_equal(params[:, 0], [0.0, 1.0, 2.0, 100.0, 101.0])  # logged x at t_k
    np.testing.assert_array_equal(params[:, 3], 0.5)
    np.testing.assert_array_equal(params[:, 4:], np.tile([9.0, 1.0, 0.5, 0.2], (5, 1)))  # the goal stays

    first, durations = first_examples(episodes)
    np.testing.assert_array_equal(first, params[[0, 3]])
    np.testing.assert_array_equal(durations, [0.45, 0.15])
    with pytest.raises(ValueError, match="n_i must be at least 1"):
        intermediate_examples(episodes, 0, observed=("x", "y", "phi", "v"))


def test_intermediate_examples_read_the_observed_parameters_by_column_name():
    episode = make_episode(4, 0.35)
    # the state columns in another order: the observed parameters are still read by name
    order = [3, 5, 0, 4, 2, 1]
    shuffled = Episode(episode.action, episode.params, episode.t, episode.state[:, order],
                       tuple(COLUMNS[i] for i in order), episode.outcome, episode.duration, episode.seed)
    expected = intermediate_examples([episode], 4, ("x", "y", "phi", "v"))
    got = intermediate_examples([shuffled], 4, ("x", "y", "phi", "v"))
    for a, b in zip(expected, got):
        np.testing.assert_array_equal(a, b)
    # a line move observes (x, v): the logged x and v, then the episode's remaining parameters
    params, _, _ = intermediate_examples([episode], 2, ("x", "v"))
    np.testing.assert_array_equal(params[:, :2], [[0.0, 0.5], [1.0, 0.5]])
    np.testing.assert_array_equal(params[:, 2:], np.tile(episode.params[2:], (2, 1)))
    with pytest.raises(KeyError, match="no state column 'z'"):
        intermediate_examples([episode], 2, ("x", "z"))
