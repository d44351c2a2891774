"""The training protocol of Fig. 4.9 and the pessimistic collision classifier (Sec. 4.2.2)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.linear_model import LinearRegression

from tailor.refinement.learning.classifiers import FAIL, SUCCESS, confusion, labels, train_collision_model
from tailor.errors import DataError
from tailor.refinement.models.features import (compute_features, feature_names, feature_space, first_examples,
                                                intermediate_examples)
from tailor.refinement.learning.duration_protocol import held_out_mae, split_episodes, train_duration_model
from synthetic_episodes import gather

OBSERVED = ("x", "y", "phi", "v")  # the observed parameters of the soccer actions (read from the log)


@pytest.mark.parametrize("n", [8, 9, 10, 11, 101])
def test_split_is_a_seeded_partition_into_half_quarter_quarter(n):
    split = split_episodes(n, seed=3)
    parts = [split.train, split.validation, split.test]
    assert [len(p) for p in parts] == [n // 2, 3 * n // 4 - n // 2, n - 3 * n // 4]
    np.testing.assert_array_equal(np.sort(np.concatenate(parts)), np.arange(n))  # no episode in two sets
    again = split_episodes(n, seed=3)
    assert all(np.array_equal(a, b) for a, b in zip(parts, [again.train, again.validation, again.test]))
    other = split_episodes(n, seed=4)
    assert not np.array_equal(split.train, other.train)


class Recorder(RegressorMixin, BaseEstimator):
    """A linear regressor that remembers which rows it was fitted on (to check no test data leaks in)."""

    fitted: list[np.ndarray] = []

    def fit(self, X, y):
        Recorder.fitted.append(np.asarray(X).copy())
        self.model_ = LinearRegression().fit(X, y)
        return self

    def predict(self, X):
        return self.model_.predict(X)


def rows_of(episodes, n_i):
    return compute_features("pose", intermediate_examples(episodes, n_i, OBSERVED)[0])


def test_duration_protocol_uses_each_part_for_its_purpose():
    episodes = gather("soccer", "goToPose", 48, seed=5)
    episodes[7] = dataclasses.replace(episodes[7], outcome="timeout")  # failures train no duration model
    episodes[20] = dataclasses.replace(episodes[20], outcome="collision")
    used = [e for e in episodes if e.succeeded]
    split = split_episodes(len(used), seed=9)
    train = [used[i] for i in split.train]
    validation = [used[i] for i in split.validation]
    test = [used[i] for i in split.test]

    Recorder.fitted = []
    result = train_duration_model("goToPose", episodes, seed=9, feature_space="pose", observed=OBSERVED,
                                  n_i_candidates=(1, 4, 9), leaf_candidates=(10,),
                                  episode_fractions=(0.5, 1.0), make_model=lambda seed, leaf: Recorder(),
                                  make_reference=lambda seed, leaf: LinearRegression())
    report, fits = result.report, list(Recorder.fitted)
    assert len(fits) == 6  # 3 n_i candidates, 2 points of Fig. 4.6, the stored model
    assert (report["episodes"], report["episodes_gathered"], report["test_episodes"]) == (46, 48, 12)
    assert report["outcomes"] == {"collision": 1, "success": 46, "timeout": 1}

    # 1. n_i: models on the half, scored on the validation quarter; the best is chosen
    for fitted, n_i in zip(fits[:3], (1, 4, 9)):
        np.testing.assert_array_equal(fitted, rows_of(train, n_i))
    scores = [row["mae"] for row in report["n_i_curve"]]
    for row, n_i in zip(report["n_i_curve"], (1, 4, 9)):
        model = Recorder().fit(rows_of(train, n_i), intermediate_examples(train, n_i, OBSERVED)[1])
        assert row["mae"] == pytest.approx(held_out_mae(model, validation, "pose"), rel=1e-12)
        assert row["examples"] == len(rows_of(train, n_i))
    n_i = (1, 4, 9)[int(np.argmin(scores))]
    assert report["n_i"] == n_i

    # 2. the evaluated model: three quarters with that n_i, scored on the test quarter; Fig. 4.6 ends with it
    learn = train + validation
    np.testing.assert_array_equal(fits[3], rows_of(learn[:17], n_i))  # half of 34 episodes
    np.testing.assert_array_equal(fits[4], rows_of(learn, n_i))
    test_rows = rows_of(test, 1)
    for fitted in fits[:5]:  # no test episode ever trains a model that is scored
        assert not any((fitted == row).all(axis=1).any() for row in test_rows)
    params, targets, _ = intermediate_examples(learn, n_i, OBSERVED)
    X_test, durations = compute_features("pose", first_examples(test)[0]), first_examples(test)[1]
    expected = np.mean(np.abs(LinearRegression().fit(compute_features("pose", params), targets).predict(X_test)
                              - durations))
    assert report["mae"] == pytest.approx(expected, rel=1e-12)
    assert report["mae_hgb"] == pytest.approx(expected, rel=1e-12)  # the reference is the same linear model here
    assert [row["episodes"] for row in report["episodes_curve"]] == [17, 34]

    # 3. the stored model: all successful episodes
    np.testing.assert_array_equal(fits[5], rows_of(used, n_i))
    assert result.model.n_i == n_i and result.model.report is report
    assert report["mean_duration"] == pytest.approx(np.mean([e.duration for e in used]))
    assert report["simulated_hours"] == pytest.approx(sum(e.duration for e in episodes) / 3600)


def test_model_tree_learns_the_synthetic_durations():
    episodes = gather("soccer", "goToPose", 400, seed=6)
    report = train_duration_model("goToPose", episodes, seed=0, feature_space="pose", observed=OBSERVED,
                                  n_i_candidates=(1, 5), episode_fractions=(1.0,),
                                  leaf_candidates=(10, 40)).report
    # the synthetic noise is 0.05 s and durations average ~5.5 s
    assert report["mae"] < 0.1 * report["mean_duration"]
    assert report["leaves"] >= 2


def test_too_few_successes_is_a_data_error():
    episodes = [dataclasses.replace(e, outcome="ball_lost") for e in gather("soccer", "dribbleBall", 20, seed=1)]
    with pytest.raises(DataError, match="dribbleBall: 0 successful episodes of 20; need at least 8"):
        train_duration_model("dribbleBall", episodes, seed=0, feature_space="pose", observed=OBSERVED)


def test_confusion_matrix_by_hand():
    predicted = np.array([FAIL, FAIL, FAIL, SUCCESS, SUCCESS, FAIL, SUCCESS, SUCCESS])
    observed = np.array([FAIL, FAIL, SUCCESS, FAIL, SUCCESS, FAIL, SUCCESS, SUCCESS])
    result = confusion(predicted, observed)
    assert result["counts"] == {"predicted_fail_observed_fail": 3, "predicted_fail_observed_success": 1,
                                "predicted_success_observed_fail": 1, "predicted_success_observed_success": 3}
    assert (result["accuracy"], result["false_success"]) == (0.75, 0.25)
    assert (result["predicted_fail"], result["observed_fail"]) == (0.5, 0.5)


def test_collision_classifier_is_pessimistic_and_evaluated_on_fresh_episodes():
    train, fresh = gather("soccer", "goToPoseAtBall", 400, seed=2), gather("soccer", "goToPoseAtBall", 300, seed=3)
    result = train_collision_model("goToPose", train, fresh, seed=0, feature_space="pose")
    report = result.report
    X_fresh = compute_features("pose", first_examples(fresh)[0])
    expected = confusion(result.model.tree.predict(X_fresh).astype(int), labels(fresh))
    assert report["confusion"] == expected and report["fresh_episodes"] == 300
    # synthetic rule: collision iff |angle_at| > 2.0, which a tree finds almost exactly
    assert report["accuracy"] > 0.97 and report["false_success"] <= 0.02
    chosen = [row for row in report["cross_validation"]
              if (row["cost"], row["min_samples_leaf"]) == (report["cost_false_success"], report["min_samples_leaf"])]
    assert chosen[0]["false_success"] <= 0.01
    assert "angle_at" in result.model.rules_text()


class Shrunk(RegressorMixin, BaseEstimator):
    """A linear model pulled towards the mean by `pull` (its validation MAE grows with it), reporting
    `leaves` leaves: lets a test set how accurate and how large each leaf size's tree is."""

    def __init__(self, pull: float = 0.0, leaves: int = 1):
        self.pull = pull
        self.leaves = leaves

    def fit(self, X, y):
        self.model_, self.mean_ = LinearRegression().fit(X, y), float(np.mean(y))
        self.n_leaves_ = self.leaves
        return self

    def predict(self, X):
        return (1 - self.pull) * self.model_.predict(X) + self.pull * self.mean_


@pytest.mark.parametrize("leaves, pulls, chosen", [
    # small trees: the largest leaf size within 3% of the best MAE
    ({5: 80, 10: 40, 20: 20, 40: 10}, {5: 0.0, 10: 0.0, 20: 0.01, 40: 0.5}, 20),
    # 80 episodes, 40 of them in the half: the stored tree would have twice the leaves, at most 400
    ({5: 800, 10: 400, 20: 200, 40: 100}, {5: 0.0, 10: 0.0, 20: 0.3, 40: 0.5}, 20),
    # no leaf size keeps the tree small enough: the largest
    ({5: 800, 10: 700, 20: 600, 40: 500}, {5: 0.0, 10: 0.0, 20: 0.3, 40: 0.5}, 40),
])
def test_leaf_size_choice(leaves, pulls, chosen):
    episodes = gather("soccer", "goToPose", 80, seed=8)
    report = train_duration_model("goToPose", episodes, seed=1, feature_space="pose", observed=OBSERVED,
                                  n_i_candidates=(2,), leaf_candidates=(5, 10, 20, 40),
                                  episode_fractions=(1.0,),
                                  make_model=lambda seed, leaf: Shrunk(pulls[leaf], leaves[leaf])).report
    curve = {row["min_samples_leaf"]: row for row in report["leaf_curve"]}
    assert sorted(curve) == [5, 10, 20, 40]
    assert [curve[leaf]["projected_leaves"] for leaf in (5, 10, 20, 40)] == [2 * leaves[k] for k in (5, 10, 20, 40)]
    assert curve[5]["mae"] == curve[10]["mae"] < curve[20]["mae"] < curve[40]["mae"]
    assert report["min_samples_leaf"] == chosen and report["leaves"] == leaves[chosen]


class Sized(RegressorMixin, BaseEstimator):
    """Shrunk whose size and accuracy follow from its examples and leaf size: `leaves_per_example` * rows / leaf
    leaves; pull `pulls[(many, leaf)]`, `many` meaning more rows than `few`."""

    def __init__(self, leaf: int = 10, few: int = 0, pulls: dict | None = None):
        self.leaf = leaf
        self.few = few
        self.pulls = pulls

    def fit(self, X, y):
        rows = len(X)
        self.inner_ = Shrunk(self.pulls[(rows > self.few, self.leaf)]).fit(X, y)
        self.n_leaves_ = 15 * rows // self.leaf
        return self

    def predict(self, X):
        return self.inner_.predict(X)


def test_n_i_is_chosen_among_trees_small_enough_to_store():
    """The best n_i at the default leaf size would need 600 leaves; made small enough (leaf 20) it loses to a
    smaller n_i whose tree fits at the default leaf size, and that is chosen."""
    episodes = gather("soccer", "goToPose", 80, seed=8)
    used = [e for e in episodes if e.succeeded]
    train = [used[i] for i in split_episodes(len(used), seed=1).train]
    few = len(rows_of(train, 2))
    assert len(rows_of(train, 5)) > few
    pulls = {(True, 10): 0.0, (True, 20): 0.3, (False, 10): 0.1, (False, 20): 0.5}
    report = train_duration_model("goToPose", episodes, seed=1, feature_space="pose", observed=OBSERVED,
                                  n_i_candidates=(2, 5), leaf_candidates=(10, 20),
                                  episode_fractions=(1.0,),
                                  make_model=lambda seed, leaf: Sized(leaf, few, pulls)).report
    n_i_curve = {row["n_i"]: row for row in report["n_i_curve"]}
    assert n_i_curve[5]["mae"] < n_i_curve[2]["mae"]  # uncapped, n_i = 5 is better ...
    assert n_i_curve[5]["projected_leaves"] > 400 >= n_i_curve[2]["projected_leaves"]  # ... but too large
    assert (report["n_i"], report["min_samples_leaf"]) == (2, 10)
    assert [(row["n_i"], row["min_samples_leaf"]) for row in report["leaf_curve"]] == [(2, 10), (2, 20)]
    assert report["leaves"] <= 400


def test_n_i_whose_capped_tree_wins_is_chosen_with_its_leaf_size():
    episodes = gather("soccer", "goToPose", 80, seed=8)
    used = [e for e in episodes if e.succeeded]
    few = len(rows_of([used[i] for i in split_episodes(len(used), seed=1).train], 2))
    pulls = {(True, 10): 0.0, (True, 20): 0.05, (False, 10): 0.3, (False, 20): 0.5}
    report = train_duration_model("goToPose", episodes, seed=1, feature_space="pose", observed=OBSERVED,
                                  n_i_candidates=(2, 5), leaf_candidates=(10, 20),
                                  episode_fractions=(1.0,),
                                  make_model=lambda seed, leaf: Sized(leaf, few, pulls)).report
    assert (report["n_i"], report["min_samples_leaf"]) == (5, 20)


def test_collision_region_grid_faces_the_goal_and_matches_the_features():
    """Fig. 4.8's starts as the soccer robot declares them (SUCCESS_REGION), in the pose space's parameters."""
    from tailor.refinement.learning.plots import REGION_SAMPLES, region_params
    from tailor.sims.soccer import SUCCESS_REGION

    order = feature_space("pose").parameters
    x, y, params = region_params(SUCCESS_REGION, order, 0.0)
    assert x.shape == (REGION_SAMPLES, REGION_SAMPLES)
    features = compute_features("pose", params)
    names = feature_names("pose")
    np.testing.assert_allclose(features[:, names.index("dist")], np.hypot(x, y).ravel())
    away = ~np.isclose(features[:, names.index("dist")], 0.0)
    np.testing.assert_allclose(features[away, names.index("angle_to")], 0.0, atol=1e-9)  # facing the goal
    # the goal heads +x: a start on the +x axis approaches head-on (angle_at pi), one on -x from behind (0)
    row = REGION_SAMPLES // 2
    assert abs(features[row * REGION_SAMPLES + REGION_SAMPLES - 1, names.index("angle_at")]) == pytest.approx(np.pi)
    assert features[row * REGION_SAMPLES, names.index("angle_at")] == pytest.approx(0.0)
    _, _, turned = region_params(SUCCESS_REGION, order, np.pi)
    np.testing.assert_allclose(compute_features("pose", turned)[away, names.index("angle_to")], np.pi, atol=1e-9)
    # every other parameter as declared: standing, the goal pose at the origin heading +x, arriving at 0.15 m/s
    np.testing.assert_array_equal(params[:, [3, 4, 5, 6, 7]], np.tile([0.0, 0.0, 0.0, 0.0, 0.15], (len(params), 1)))


def test_the_duration_curve_sweeps_the_declared_angle_in_the_declared_situation():
    """Fig. 4.7's situation of the soccer robot: the goal 1.5 m ahead, standing, arriving at rest, phig swept (the
    angle of approach where the goal lies straight ahead)."""
    from tailor.refinement.learning.plots import curve_params
    from tailor.sims.soccer import APPROACH_ANGLE

    angles = np.linspace(-np.pi, np.pi, 9)[:-1]  # (angle_at wraps pi to -pi)
    params = curve_params(APPROACH_ANGLE, feature_space("pose").parameters, angles)
    expected = np.zeros((8, 8))
    expected[:, 4], expected[:, 6] = 1.5, angles
    np.testing.assert_array_equal(params, expected)
    np.testing.assert_allclose(compute_features("pose", params)[:, feature_names("pose").index("angle_at")], angles)
    # the same situation whatever order a space reads the parameters in
    shuffled = ("phig", "vg", "x", "y", "phi", "v", "xg", "yg")
    np.testing.assert_array_equal(curve_params(APPROACH_ANGLE, shuffled, angles)[:, [2, 3, 4, 5, 6, 7, 0, 1]], params)


def test_a_simulator_gets_the_model_pictures_it_declares_and_no_others():
    """Figs. 4.7 and 4.8 where the simulator declares them, for the models whose spaces read the parameters they
    set; the learning curves for every simulator; nothing guessed from a parameter's name."""
    from types import SimpleNamespace

    from tailor.refinement.learning.plots import caption, training_plots

    pose = {"goToPose": SimpleNamespace(feature_space="pose", report={}),
            "approachBall": SimpleNamespace(feature_space="approach", report={})}
    line = {"move": SimpleNamespace(feature_space="line", report={})}
    classifiers = {"goToPose": SimpleNamespace(feature_space="pose_walls", action="goToPose")}
    assert list(training_plots("soccer", pose, classifiers)) == [
        "mae_vs_n_i.png", "mae_vs_episodes.png", "angle_at_polar.png", "goToPose.success_region.png"]
    assert list(training_plots("soccer", line, {})) == ["mae_vs_n_i.png", "mae_vs_episodes.png"]  # reads no pose
    for simulator in ("arm", "kitchen", ""):  # none declared: no picture of a pose, whatever the spaces read
        assert list(training_plots(simulator, pose, classifiers)) == ["mae_vs_n_i.png", "mae_vs_episodes.png"]
    assert caption("angle_at_polar.png", "soccer") == (
        "Predicted duration over the angle of approach in one situation (Fig. 4.7)")
    assert caption("goToPose.success_region.png") == (
        "Where the success classifier of goToPose predicts failure, over start positions (Fig. 4.8)")
