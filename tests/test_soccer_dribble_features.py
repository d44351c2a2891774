"""dribbleBall's own feature space (sims/soccer/features.py, "dribble"): the Dubins path it plans with the ball,
clear of the walls, by hand and against the scalar planner its controller uses, and the bundled model's accuracy
on fresh dribbles against what the pose features reach."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from tailor.refinement.models.action_models import load_action_models
from tailor.refinement.models.features import compute_features, feature_space
from tailor.sims.experience import gather
from tailor.sims.soccer.dribble import FINAL_STRAIGHT, R_DRIBBLE
from tailor.sims.soccer.dubins import WORDS, shortest_path_inside
from tailor.sims.soccer.dubins import word_bounds as scalar_word_bounds
from tailor.sims.soccer.features import (
    APPROACH_FEATURES,
    DRIBBLE_BOX,
    axle_poses,
    dribble_path,
    dubins_words,
    shortest_word,
    word_bounds,
)
from tailor.sims.soccer.world import BALL_POINT_OFFSET

MODELS = Path(__file__).resolve().parent.parent / "domains" / "soccer" / "models"


def test_the_dribble_space_is_the_pose_space_plus_the_path_with_the_ball():
    rng = np.random.default_rng(0)
    params = np.column_stack([rng.uniform(-3, 3, (200, 3)), rng.uniform(0, 0.3, 200),
                              rng.uniform(-3, 3, (200, 3)), np.zeros(200)])
    features = compute_features("dribble", params)
    assert feature_space("dribble").names == APPROACH_FEATURES
    np.testing.assert_array_equal(features[:, :5], compute_features("pose", params))
    np.testing.assert_array_equal(features[:, 5:], dribble_path(params))


def test_dribble_path_by_hand():
    """On the goal's line behind it: the straight only. Facing away: the axle, D short of the pre-pose, turns
    (pi + a) R onto the inner tangent of the circles of radius R_DRIBBLE (sin a = 2R / D), drives it,
    sqrt(D^2 - 4R^2), turns a R onto the goal line, then FINAL_STRAIGHT."""
    d, R = 3.0, R_DRIBBLE
    aligned = dribble_path(np.array([[0.0, 0.0, 0.0, 0.2, d, 0.0, 0.0, 0.0]]))[0]
    np.testing.assert_allclose(aligned, [d, 0.0, d])
    away = dribble_path(np.array([[0.0, 0.0, math.pi, 0.2, d, 0.0, 0.0, 0.0]]))[0]
    D = d - FINAL_STRAIGHT - 2 * BALL_POINT_OFFSET  # the axle starts BALL_POINT_OFFSET ahead of the ball point
    a = math.asin(2 * R / D)
    arcs = (math.pi + a) * R + a * R
    length = arcs + math.sqrt(D * D - 4 * R * R) + FINAL_STRAIGHT
    np.testing.assert_allclose(away, [length, arcs, length], atol=1e-9)


def _params(rng: np.random.Generator, n: int) -> np.ndarray:
    """Starts anywhere up to the walls, goals anywhere on the field: many paths would leave the box."""
    return np.column_stack([rng.uniform(-4.4, 4.4, n), rng.uniform(-3.4, 3.4, n), rng.uniform(-math.pi, math.pi, n),
                            rng.uniform(0, 0.3, n), rng.uniform(-4, 4, n), rng.uniform(-3, 3, n),
                            rng.uniform(-math.pi, math.pi, n), np.zeros(n)])


def test_vectorized_bounds_equal_the_scalar_ones():
    start, pre = axle_poses(_params(np.random.default_rng(2), 300), FINAL_STRAIGHT)
    words, _ = dubins_words(start, pre, R_DRIBBLE)
    bounds = word_bounds(start, words, R_DRIBBLE)
    for i in range(len(start)):
        for j, word in enumerate(WORDS):
            if np.isnan(words[i, j]).any():
                assert np.isnan(bounds[i, j]).all()
            else:
                np.testing.assert_allclose(bounds[i, j], scalar_word_bounds(tuple(start[i]), word, tuple(words[i, j]),
                                                                            R_DRIBBLE), atol=1e-9)


def test_the_path_is_the_one_the_controller_plans_inside_the_walls():
    """The word sims.soccer.dubins.shortest_path_inside chooses (what dribbleBall follows), its length and its
    arcs, for 2000 random poses; near the walls it is often longer than the free shortest word."""
    params = _params(np.random.default_rng(3), 2000)
    features = dribble_path(params)
    start, pre = axle_poses(params, FINAL_STRAIGHT)
    for i in range(len(params)):
        path = shortest_path_inside(tuple(start[i]), tuple(pre[i]), R_DRIBBLE, DRIBBLE_BOX)
        arcs = sum(length for kind, length in zip(path.word, path.lengths) if kind != "S")
        np.testing.assert_allclose(features[i, :2], [sum(path.lengths) + FINAL_STRAIGHT, arcs], atol=1e-9)
    free = shortest_word(start, pre, R_DRIBBLE, FINAL_STRAIGHT)
    assert np.all(features[:, 0] >= free[:, 0] - 1e-9)
    assert np.mean(features[:, 0] > free[:, 0] + 0.1) > 0.05


def test_the_bundled_dribble_model_sees_its_path():
    """On 60 fresh dribbles (a seed no model learned from) the bundled model errs by well under the 0.61 s
    (3.7% of the mean) a model tree on the pose features alone reaches from the same experience (5-fold
    cross-validated; 0.38 s with the free shortest word, 0.31 s with the word planned inside the walls)."""
    model = load_action_models(MODELS, ("dribbleBall",))["dribbleBall"]
    assert model.feature_space == "dribble"
    episodes = [e for e in gather("soccer", "dribbleBall", 60, seed=424242, jobs=1, progress=False) if e.succeeded]
    assert len(episodes) >= 55
    params = np.array([e.params for e in episodes])
    measured = np.array([e.duration for e in episodes])
    error = np.abs(model.predict_duration(params) - measured)
    assert error.mean() < 0.48, np.round(error, 2)
