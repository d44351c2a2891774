"""Subgoal refinement over a horizon (Sec. 5.4), checked against brute force on instantiated plans.

The action models here are model trees fitted to known travel-time functions of the pose features, so the
tests do not depend on the trained soccer models.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from tailor.planner_bridge import AbstractPlan
from tailor.refinement.models.action_models import ActionModel
from tailor.refinement.belief import parse_belief
from tailor.refinement.binding import load_domain_binding
from tailor.refinement.models.features import compute_features, feature_names
from tailor.refinement.instantiate import instantiate
from tailor.refinement.models.model_tree import ModelTree
from tailor.refinement.refine import refine

ROOT = Path(__file__).resolve().parent.parent
FIXTURES = Path(__file__).resolve().parent / "fixtures" / "binding"


def _travel_time(F: np.ndarray) -> np.ndarray:
    """A travel time over the pose features (v, vg, dist, angle_to, angle_at): turning costs, speed helps."""
    v, vg, dist, angle_to, angle_at = F.T
    return 0.8 + dist / 0.8 + 0.9 * angle_to + 0.6 * np.abs(angle_at) - 0.8 * v + 0.5 * vg


def _model(action: str, seed: int, n: int = 6000, min_samples_leaf: int = 20) -> ActionModel:
    """A model tree of `_travel_time` fitted on n random pose parameterizations."""
    rng = np.random.default_rng(seed)
    params = np.column_stack([
        rng.uniform(-3, 3, n), rng.uniform(-2, 2, n), rng.uniform(-math.pi, math.pi, n), rng.uniform(0, 0.3, n),
        rng.uniform(-3, 3, n), rng.uniform(-2, 2, n), rng.uniform(-math.pi, math.pi, n), rng.uniform(0, 0.3, n),
    ])
    F = compute_features("pose", params)
    tree = ModelTree(min_samples_leaf=min_samples_leaf).fit(F, _travel_time(F))
    return ActionModel(action, "pose", feature_names("pose"), tree, n_i=1)


@pytest.fixture(scope="module")
def models():
    return {"approachBall": _model("approachBall", 0), "dribbleBall": _model("dribbleBall", 1),
            "goToPose": _model("goToPose", 2)}


def _sequence(plan_file: str, objects: dict):
    plan = AbstractPlan.from_json(__import__("json").loads((FIXTURES / plan_file).read_text()))
    binding = load_domain_binding(ROOT / "domains" / "soccer")
    return instantiate(plan, binding, parse_belief({"objects": objects}))


SCORE = {"pos1": {"x": -2.0, "y": -1.0, "phi": 0.3, "v": 0.0}, "pos2": {"x": 0.5, "y": 0.5},
         "pos3": {"x": -1.0, "y": 2.0, "phi": 2.6, "v": 0.0}}


def _grid_total(sequence, models, ids, n_phi=721, speeds=(0.0, 0.1, 0.2, 0.3)):
    best = (math.inf, None)
    for phi in np.linspace(-math.pi, math.pi, n_phi):
        for v in speeds:
            bound = sequence.bind(dict(zip(ids, (phi, v))))
            total = sum(float(models[a.action].predict_duration(a.values()[None])[0]) for a in bound.actions)
            best = min(best, (total, (phi, v)), key=lambda b: b[0])
    return best


@pytest.mark.parametrize("method", ["analytic", "ga"])
def test_horizon_two_finds_the_brute_force_minimum_of_the_summed_models(models, method):
    sequence = _sequence("score_plan.json", SCORE)
    ids = [p.id for p in sequence.free_parameters()]
    assert ids == ["pos2.phi", "pos2.v"]
    refined = refine(sequence, models, horizon=2, method=method, seed=3)
    grid_best, _ = _grid_total(sequence, models, ids)
    assert refined.predicted_total <= grid_best + (1e-9 if method == "analytic" else 0.02 * grid_best)
    assert refined.predicted_total >= grid_best - 0.05  # the grid is fine: nothing far below it exists
    assert all(not p.free for a in refined.sequence.actions for p in a.params)


def test_greedy_minimizes_the_first_action_only_and_is_not_better_in_total(models):
    sequence = _sequence("score_plan.json", SCORE)
    # without the margin from the splits (MARGIN_SHARE), the analytic optimum is the exact one, checked on a grid
    greedy = refine(sequence, models, horizon=1, method="analytic", margin_share=0.0)
    refined = refine(sequence, models, horizon=2, method="analytic", margin_share=0.0)
    first = sequence.actions[0]
    ids = [p.id for p in sequence.free_parameters()]
    grid = [(float(models["goToPose"].predict_duration(first.values(dict(zip(ids, (phi, v))))[None])[0]))
            for phi in np.linspace(-math.pi, math.pi, 721) for v in (0.0, 0.1, 0.2, 0.3)]
    assert greedy.predicted[0] <= min(grid) + 1e-9
    assert refined.predicted[0] >= greedy.predicted[0] - 1e-9  # refinement gives up speed on the approach ...
    assert refined.predicted_total <= greedy.predicted_total + 1e-9  # ... to be faster over both actions
    # the shared parameter is one value: the approach's goal heading is dribbleBall's start heading
    a, d = refined.sequence.actions
    assert a.params[6].value == d.params[2].value and a.params[7].value == d.params[3].value


WAYPOINTS = {"p0": {"x": -3.0, "y": -1.0, "phi": 0.0, "v": 0.0}, "w1": {"x": -2.0, "y": 0.5},
             "w2": {"x": -0.5, "y": -0.5}, "w3": {"x": 1.0, "y": 0.5},
             "w4": {"x": 2.5, "y": -0.5, "phi": -0.588, "v": 0.0}}


def test_longer_horizons_fix_one_subgoal_per_window(models):
    sequence = _sequence("waypoints_plan.json", WAYPOINTS)
    assert [p.id for p in sequence.free_parameters()] == ["w1.phi", "w1.v", "w2.phi", "w2.v", "w3.phi", "w3.v"]
    totals = {}
    for h in (1, 2, 4):
        refined = refine(sequence, models, horizon=h, method="analytic", seed=0)
        assert len(refined.windows) == 3  # one optimization per action that still has a free subgoal
        assert [len(w.values) for w in refined.windows] == [2 * min(h, 3 - i) for i in range(3)]
        totals[h] = refined.predicted_total
    assert totals[2] <= totals[1] + 1e-9


def test_a_missing_model_is_a_one_line_error(models):
    from tailor.errors import ModelFileError

    sequence = _sequence("score_plan.json", SCORE)
    with pytest.raises(ModelFileError, match="no action model for executable action 'dribbleBall'"):
        refine(sequence, {"goToPose": models["goToPose"]}, horizon=2)
