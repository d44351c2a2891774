"""Action models and the collision classifier: JSON round trips, the tree arrays, and loader errors."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from sklearn.tree import DecisionTreeClassifier

from tailor.refinement.models.action_models import (
    ACTION_MODEL_SCHEMA,
    ActionModel,
    CollisionModel,
    load_action_models,
    load_collision_model,
    write_json_atomic,
)
from tailor.refinement.learning.classifiers import tree_arrays
from tailor.errors import ModelFileError
from tailor.refinement.models.features import compute_features, feature_names
from tailor.refinement.models.model_tree import ModelTree
from synthetic_episodes import random_params, synthetic_duration


@pytest.fixture(scope="module")
def action_model() -> ActionModel:
    params = random_params(600, seed=10)
    tree = ModelTree(min_samples_leaf=20).fit(compute_features("pose", params), synthetic_duration(params))
    return ActionModel("goToPose", "pose", feature_names("pose"), tree, 5, {"mae": 0.1})


@pytest.fixture(scope="module")
def collision_model() -> CollisionModel:
    params = random_params(800, seed=11)
    X = compute_features("pose", params)
    y = (np.abs(X[:, 4]) < 1.5) & (X[:, 2] > 1.0)
    classifier = DecisionTreeClassifier(min_samples_leaf=5, class_weight={0: 4.0, 1: 1.0}, random_state=0).fit(X, y)
    return CollisionModel("goToPose", "pose", feature_names("pose"), tree_arrays(classifier), {"accuracy": 0.9})


def test_action_model_predicts_through_its_features(action_model):
    params = random_params(50, seed=12)
    expected = action_model.duration.predict(compute_features("pose", params))
    np.testing.assert_array_equal(action_model.predict_duration(params), expected)
    assert np.mean(np.abs(expected - synthetic_duration(params))) < 0.5  # it learned something


def test_action_model_json_round_trip_predicts_identically(action_model, tmp_path):
    write_json_atomic(tmp_path / "goToPose.json", action_model.to_json())
    loaded = load_action_models(tmp_path)
    assert list(loaded) == ["goToPose"]
    model = loaded["goToPose"]
    assert (model.action, model.feature_space, model.feature_names, model.n_i, model.report) == (
        "goToPose", "pose", feature_names("pose"), 5, {"mae": 0.1})
    params = random_params(2000, seed=13)
    np.testing.assert_array_equal(model.predict_duration(params), action_model.predict_duration(params))
    assert model.to_json() == action_model.to_json()
    assert [p.name for p in tmp_path.iterdir()] == ["goToPose.json"]  # no temp file left behind


def test_model_files_name_their_feature_space_and_files_of_the_old_key_still_load(action_model, collision_model,
                                                                                 tmp_path):
    """Written as `feature_space` (as the binding names it); files written as `feature_set` before (the bundled
    soccer and arm models among them) load as they did."""
    from pathlib import Path

    for model in (action_model, collision_model):
        data = model.to_json()
        assert data["feature_space"] == "pose" and "feature_set" not in data
    old = action_model.to_json()
    old["feature_set"] = old.pop("feature_space")
    write(tmp_path / "goToPose.json", old)
    assert load_action_models(tmp_path)["goToPose"].feature_space == "pose"
    old = collision_model.to_json()
    old["feature_set"] = old.pop("feature_space")
    write(tmp_path / "goToPose.collision.json", old)
    assert load_collision_model(tmp_path / "goToPose.collision.json").feature_space == "pose"
    domains = Path(__file__).resolve().parent.parent / "domains"
    for folder in sorted(domains.glob("*/models")):
        files = {p.name for p in folder.glob("*.json")} - {"meta.json"}
        actions = tuple(sorted(n.removesuffix(".json") for n in files if not n.endswith(".collision.json")))
        if folder.parent.name in ("soccer", "arm"):
            assert "feature_set" in json.loads((folder / f"{actions[0]}.json").read_text())  # an old file ...
        assert set(load_action_models(folder, actions)) == set(actions)  # ... that loads (as the new ones do)
        for name in sorted(n for n in files if n.endswith(".collision.json")):
            assert load_collision_model(folder / name).action == name.removesuffix(".collision.json")


def test_collision_tree_arrays_predict_like_scikit_learn(collision_model):
    params = random_params(800, seed=11)
    X = compute_features("pose", params)
    y = (np.abs(X[:, 4]) < 1.5) & (X[:, 2] > 1.0)
    classifier = DecisionTreeClassifier(min_samples_leaf=5, class_weight={0: 4.0, 1: 1.0}, random_state=0).fit(X, y)
    fresh = random_params(5000, seed=14)
    np.testing.assert_array_equal(collision_model.predict_success(fresh),
                                  classifier.predict(compute_features("pose", fresh)))
    np.testing.assert_array_equal(collision_model.tree.apply(X), classifier.apply(X))


def test_simplified_tree_merges_leaves_that_agree():
    from tailor.refinement.models.decision_tree import DecisionTree

    # 0: dist <= 2 ? 1 : 4;  1: v <= 0.5 ? 2 (Fail) : 3 (Fail);  4: angle_at <= 0 ? 5 (Success) : 6
    # 6: v <= 0.2 ? 7 (Success) : 8 (Success)
    tree = DecisionTree(children_left=np.array([1, 2, -1, -1, 5, -1, 7, -1, -1]),
                        children_right=np.array([4, 3, -1, -1, 6, -1, 8, -1, -1]),
                        feature=np.array([2, 0, -1, -1, 4, -1, 0, -1, -1]),
                        threshold=np.array([2.0, 0.5, 0, 0, 0.0, 0, 0.2, 0, 0]),
                        success=np.array([0, 0, 0, 0, 1, 1, 1, 1, 1], dtype=bool),
                        samples=np.array([90, 40, 30, 10, 50, 20, 30, 25, 5]))
    simple = tree.simplified()
    np.testing.assert_array_equal(simple.children_left, [1, -1, -1])
    np.testing.assert_array_equal(simple.children_right, [2, -1, -1])
    np.testing.assert_array_equal(simple.feature, [2, -1, -1])
    np.testing.assert_array_equal(simple.success, [False, False, True])
    np.testing.assert_array_equal(simple.samples, [90, 40, 50])
    X = compute_features("pose", random_params(2000, seed=17))
    np.testing.assert_array_equal(simple.predict(X), tree.predict(X))
    assert simple.export_text(feature_names("pose")) == "dist <= 2.000: Fail (40)\ndist > 2.000: Success (50)"


def test_collision_regions_partition_feature_space(collision_model):
    X = compute_features("pose", random_params(3000, seed=15))
    boxes = collision_model.regions()
    assert len(boxes) == collision_model.tree.n_leaves
    inside = np.array([box.contains(X) for box in boxes])  # (leaves, n)
    np.testing.assert_array_equal(inside.sum(axis=0), 1)
    success = np.array([box.success for box in boxes])
    np.testing.assert_array_equal(success[np.argmax(inside, axis=0)], collision_model.tree.predict(X))
    assert sum(box.samples for box in boxes) == 800


def test_collision_model_json_round_trip(collision_model, tmp_path):
    path = tmp_path / "goToPose.collision.json"
    write_json_atomic(path, collision_model.to_json())
    loaded = load_collision_model(path)
    params = random_params(3000, seed=16)
    np.testing.assert_array_equal(loaded.predict_success(params), collision_model.predict_success(params))
    assert loaded.rules_text() == collision_model.rules_text()
    assert loaded.rules_text().splitlines()[0].startswith(("v ", "vg ", "dist ", "angle_to ", "angle_at "))
    assert load_action_models(tmp_path, ()) == {}  # the classifier's file is not a duration model


def test_rules_text_of_a_hand_built_tree():
    from tailor.refinement.models.decision_tree import DecisionTree

    tree = DecisionTree(children_left=np.array([1, -1, 3, -1, -1]), children_right=np.array([2, -1, 4, -1, -1]),
                        feature=np.array([4, -1, 2, -1, -1]), threshold=np.array([-1.0, 0, 2.5, 0, 0]),
                        success=np.array([False, False, True, True, False]), samples=np.array([10, 3, 7, 5, 2]))
    assert tree.export_text(feature_names("pose")) == "\n".join([
        "angle_at <= -1.000: Fail (3)",
        "angle_at > -1.000",
        "|   dist <= 2.500: Success (5)",
        "|   dist > 2.500: Fail (2)",
    ])
    X = np.array([[0, 0, 1.0, 0, -2.0], [0, 0, 1.0, 0, 0.0], [0, 0, 3.0, 0, 0.0], [0, 0, 2.5, 0, -1.0]])
    np.testing.assert_array_equal(tree.predict(X), [False, True, False, False])


# -- loader errors ---------------------------------------------------------------------------------------


def write(path, data) -> None:
    path.write_text(json.dumps(data) if not isinstance(data, str) else data, encoding="utf-8")


def test_loader_missing_directory_and_file(tmp_path):
    with pytest.raises(ModelFileError, match="nowhere: model directory not found"):
        load_action_models(tmp_path / "nowhere")
    with pytest.raises(ModelFileError, match=r"models: no action model files"):
        (tmp_path / "models").mkdir()
        load_action_models(tmp_path / "models")
    with pytest.raises(ModelFileError, match=r"dribbleBall\.json: file not found"):
        load_action_models(tmp_path / "models", ("dribbleBall",))
    with pytest.raises(ModelFileError, match=r"goToPose\.collision\.json: file not found"):
        load_collision_model(tmp_path / "goToPose.collision.json")


def test_loader_rejects_non_json(tmp_path):
    write(tmp_path / "goToPose.json", '{"schema": "tailor.action_model/1",\n  oops}')
    with pytest.raises(ModelFileError, match=r"goToPose\.json:2:3: not JSON"):
        load_action_models(tmp_path)
    write(tmp_path / "goToPose.json", "[1, 2]")
    with pytest.raises(ModelFileError, match=r"goToPose\.json: expected a JSON object"):
        load_action_models(tmp_path)


def mutate(data: dict, path: tuple, value) -> dict:
    data = json.loads(json.dumps(data))
    target = data
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    return data


@pytest.mark.parametrize("path, value, message", [
    (("schema",), "tailor.action_model/0", "schema is 'tailor.action_model/0', expected 'tailor.action_model/1'"),
    (("feature_space",), "polar", "unknown feature space 'polar'"),
    (("feature_names",), ["v", "dist"], "feature_names ['v', 'dist'] do not match feature space 'pose'"),
    (("n_i",), 0, "'n_i' must be a positive integer"),
    (("duration",), [1, 2], "'duration' must be a model tree object"),
    (("report",), 3, "'report' must be an object"),
    (("action",), "dribbleBall", "holds the model of 'dribbleBall', not of its file name's action"),
])
def test_loader_rejects_wrong_fields(action_model, tmp_path, path, value, message):
    write(tmp_path / "goToPose.json", mutate(action_model.to_json(), path, value))
    with pytest.raises(ModelFileError, match="goToPose.json: " + re.escape(message)):
        load_action_models(tmp_path)


def test_loader_rejects_a_tree_of_the_wrong_shape(action_model, collision_model, tmp_path):
    data = action_model.to_json()
    data["feature_space"], data["feature_names"] = "pose_delta", list(feature_names("pose_delta"))
    write(tmp_path / "goToPose.json", data)
    with pytest.raises(ModelFileError, match="goToPose.json: duration model tree takes 5 features, feature space has 6"):
        load_action_models(tmp_path)

    path = tmp_path / "goToPose.collision.json"
    tree = collision_model.to_json()["tree"]
    for key, value, message in (("threshold", tree["threshold"][:-1], "threshold must have shape"),
                                ("feature", [7] * len(tree["feature"]), "a node tests a feature outside 0..4"),
                                ("children_left", [0] * len(tree["feature"]), "a node has exactly one child")):
        write(path, mutate(collision_model.to_json(), ("tree", key), value))
        with pytest.raises(ModelFileError, match="goToPose.collision.json: invalid decision tree: " + f"({message})"):
            load_collision_model(path)
    write(path, mutate(collision_model.to_json(), ("schema",), ACTION_MODEL_SCHEMA))
    with pytest.raises(ModelFileError, match="expected 'tailor.collision_model/1'"):
        load_collision_model(path)

