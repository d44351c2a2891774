"""The certified optimizer (branch and bound over the features' bounds) and `auto`: its lower bound is a true
lower bound (checked against dense sampling and brute force on small cases), it finds optima the genetic
algorithm misses, and `auto` says which optimizer ran and why the others did not."""

from __future__ import annotations

import re
from dataclasses import replace

import numpy as np
import pytest
from rule_models import RuleModel, rule
from sklearn.tree import DecisionTreeClassifier
from tailor.refinement.learning.classifiers import tree_arrays
from tailor.refinement.models.model_tree import ModelTree
from tailor.refinement.optimizers import (
    OPTIMIZERS,
    FreeParameter,
    Objective,
    Term,
    brute_force,
    certified,
    intervals,
    optimize,
)
from tailor.refinement.optimizers.structure import NotApplicable
from tailor.refinement.optimizers.synthetic import (
    FeatureMap,
    feature_bounds,
    feature_function,
    random_objective,
)

INF = np.inf
GRID = {1: 20001, 2: 401, 3: 61}
SLACK = 1e-9  # rounding of the sums


def sampled_minimum(objective: Objective, points: int, seed: int = 0) -> float:
    """The least valid (worst-case) cost over a grid and random points: an upper bound of the true minimum."""
    grid = brute_force(objective, GRID[len(objective.free)]) if not any(objective.neighbourhood) else None
    rng = np.random.default_rng(seed)
    theta = rng.uniform(objective.low, objective.high, size=(points, len(objective.free)))
    cost = np.where(objective.valid(theta), objective.robust_cost(theta), np.inf)
    best = float(cost.min())
    if grid is not None:
        best = min(best, grid.cost)
    else:
        axes = [np.linspace(p.low, p.high, 201 if len(objective.free) <= 2 else 31) for p in objective.free]
        theta = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(axes))
        best = min(best, float(np.where(objective.valid(theta), objective.robust_cost(theta), np.inf).min()))
    return best


def bound_holds(result, objective: Objective) -> bool:
    """The certificate is a true lower bound: no sampled valid choice is below it, and the choice is its cost."""
    best = sampled_minimum(objective, 20000)
    return (result.lower_bound <= best + SLACK * (1 + abs(best))
            and result.cost == pytest.approx(float(objective.robust_cost(np.array([result.values]))[0])))


@pytest.mark.parametrize("seed", range(16))
def test_the_lower_bound_is_below_every_sampled_cost_and_the_gap_within_the_tolerance(seed):
    """Curved features (a distance over a free parameter), jumps (wrapped angles, sign flips): App. C.3 does not
    apply; the bound is true and the gap closes."""
    rng = np.random.default_rng(seed)
    objective = random_objective(rng, [1, 2, 2, 3][seed % 4], 2, n_leaves=30, extra_kind="curved")
    result = certified.minimize(objective)
    assert result.method == "certified"
    assert bound_holds(result, objective)
    assert result.gap <= certified.tolerance_of(result.cost)
    assert result.cost <= sampled_minimum(objective, 20000) + certified.tolerance_of(result.cost)


@pytest.mark.parametrize("seed", range(4))
def test_the_bound_holds_for_the_worst_case_over_a_neighbourhood(seed):
    rng = np.random.default_rng(50 + seed)
    plain = random_objective(rng, 2, 2, n_leaves=20, extra_kind="mixed")
    objective = replace(plain, neighbourhood=(0.1, 0.03))
    result = certified.minimize(objective)
    assert "neighbourhood" in result.note
    assert bound_holds(result, objective)
    assert result.gap <= certified.tolerance_of(result.cost)
    # the worst case is never below the point's cost: the bound of the worst case is above the plain minimum
    assert result.lower_bound >= certified.minimize(plain).lower_bound - SLACK


def test_a_bound_loosened_to_an_invalid_one_is_caught(monkeypatch):
    """The check above is not vacuous: a tree bound raised by 0.2 s (no longer a lower bound) fails it."""
    objective = random_objective(np.random.default_rng(3), 2, 2, n_leaves=30, extra_kind="curved")
    honest = certified.minimize(objective)
    assert bound_holds(honest, objective)
    minimum = intervals.minimum
    monkeypatch.setattr(intervals, "minimum", lambda *args: minimum(*args) + 0.2)
    loose = certified.minimize(objective)
    assert not bound_holds(loose, objective)


def narrow_dip() -> Objective:
    """One free heading; the feature is the distance to a point off the line (curved: App. C.3 does not apply);
    the tree predicts 2 s + 0.2 s per metre, except 0.5 s in a slot 2e-4 m wide."""
    maps = [FeatureMap("curved", 0, 0.7, 0.5)]
    dist = float(np.hypot(2.1 - 0.7, 0.5))
    tree = RuleModel([rule([-INF], [dist], [0.2], 2.0), rule([dist], [dist + 2e-4], [0.0], 0.5),
                      rule([dist + 2e-4], [INF], [0.2], 2.0)])
    term = Term(tree, feature_function(maps), label="dip", feature_bounds=feature_bounds(maps), reads=(0,))
    return Objective((FreeParameter("p.phi", -np.pi, np.pi),), (term,))


def inner_slot() -> Objective:
    """One free value x in [-1, 1] with a neighbourhood of radius 0.1 (stencil 0, +-0.05, +-0.1): the tree predicts
    1 + |x|, but 3 s on the slot (0.0375, 0.0625], which near x = 0 only the stencil's inner offset +0.05 meets.
    The worst case's minimum is 1.1125 at x = -0.0125 and 0.0125; over the point and the stencil's ends alone it
    would be 1.1 at x = 0, 1.1% lower."""
    maps = [FeatureMap("affine", 0, 1.0, 0.0)]  # the feature is x itself
    tree = RuleModel([rule([-INF], [0.0], [-1.0], 1.0), rule([0.0], [0.0375], [1.0], 1.0),
                      rule([0.0375], [0.0625], [0.0], 3.0), rule([0.0625], [INF], [1.0], 1.0)])
    term = Term(tree, feature_function(maps), label="slot", feature_bounds=feature_bounds(maps), reads=(0,))
    return Objective((FreeParameter("p.x", -1.0, 1.0),), (term,), neighbourhood=(0.1,))


def test_the_inner_offsets_of_the_stencil_bound_a_narrow_box():
    """Where the worst case at the optimum lies at an inner offset of the stencil, the bound over the point and
    the ends stays 1.1% below it however small the boxes: the inner offsets close the gap."""
    objective = inner_slot()
    assert sorted(objective.offsets[:, 0]) == pytest.approx([-0.1, -0.05, 0.0, 0.05, 0.1])
    result = certified.minimize(objective, budget=4000)
    assert 1.1125 - SLACK <= result.cost <= 1.1125 * (1 + certified.TOLERANCE)
    assert 0.0125 <= abs(result.values[0]) <= 0.0125 + 1.1125 * certified.TOLERANCE  # (slope 1 s per unit)
    assert result.gap <= certified.tolerance_of(result.cost) and bound_holds(result, objective)


def test_without_the_inner_offsets_that_gap_does_not_close(monkeypatch):
    monkeypatch.setattr(certified, "INNER_WIDTH", 0.0)
    result = certified.minimize(inner_slot(), budget=4000)
    assert result.gap > 0.01 and "budget of 4000 boxes spent" in result.note


def test_a_constructed_tree_whose_optimum_the_ga_misses_and_the_certified_optimizer_finds():
    objective = narrow_dip()
    ga = optimize(objective, "ga", seed=0)
    assert ga.cost > 2.0  # the genetic algorithm never lands in the slot
    result = optimize(objective, "certified")
    assert result.method == "certified" and result.cost == pytest.approx(0.5)
    assert result.lower_bound <= 0.5 + SLACK and result.gap <= certified.tolerance_of(0.5)
    chosen = optimize(objective)  # auto: the features are not piecewise affine, the bound decides
    assert chosen.method == "certified" and chosen.cost == pytest.approx(0.5)
    assert "analytic not applicable" in chosen.note


def test_auto_switched_to_the_ga_alone_misses_it(monkeypatch):
    """With the certified optimizer switched off, auto runs the genetic algorithm and misses the slot: the
    test above depends on it."""
    def off(*args, **kwargs):
        raise NotApplicable("switched off")

    monkeypatch.setattr(certified, "minimize", off)
    result = optimize(narrow_dip())
    assert result.method == "ga" and result.cost > 2.0 and "certified not applicable: switched off" in result.note


def test_auto_takes_analytic_where_it_applies_and_says_why_the_others_did_not():
    rng = np.random.default_rng(1)
    affine = random_objective(rng, 2, 2, n_leaves=20)
    assert optimize(affine).method == "analytic"
    assert optimize(affine).lower_bound <= brute_force(affine, 401).cost + SLACK
    curved = random_objective(np.random.default_rng(1), 2, 2, n_leaves=20, extra_kind="curved")
    result = optimize(curved)
    assert result.method == "certified" and result.note.startswith("analytic not applicable")
    unbounded = Objective(curved.free, tuple(replace(t, feature_bounds=None, no_bounds="its space declares none")
                                             for t in curved.terms))
    result = optimize(unbounded, seed=2)
    assert result.method == "ga" and result.gap is None
    assert "certified not applicable: term 'term0' cannot be bounded: its space declares none" in result.note


def test_an_enclosure_that_does_not_shrink_to_a_point_is_not_searched():
    """A sound but coarse enclosure (wide at a single point) could never close the gap: the optimizer says so at
    once and auto runs the genetic algorithm, the gap unknown, rather than spend its budget on it."""
    objective = random_objective(np.random.default_rng(1), 2, 2, n_leaves=20, extra_kind="curved")
    first = objective.terms[0]
    coarse = replace(first, feature_bounds=lambda lo, hi: tuple(
        (b - 1.0, b + 1.0)[k] for k, b in enumerate(first.feature_bounds(lo, hi))))
    widened = Objective(objective.free, (coarse,) + objective.terms[1:])
    with pytest.raises(NotApplicable, match="cannot be bounded closely: its feature 0 is enclosed in"):
        certified.minimize(widened)
    result = optimize(widened, seed=0)
    assert result.method == "ga" and result.gap is None and "cannot be bounded closely" in result.note


def test_auto_keeps_the_better_choice_and_the_bound_where_the_budget_ends(monkeypatch):
    monkeypatch.setattr("tailor.refinement.optimizers.AUTO_BUDGET", 50)
    objective = random_objective(np.random.default_rng(3), 3, 2, n_leaves=30, extra_kind="curved")
    result = optimize(objective, seed=1)
    assert "the genetic algorithm too" in result.note and "choice kept" in result.note
    assert result.lower_bound is not None and result.gap > certified.tolerance_of(result.cost)
    assert bound_holds(result, objective)


def guarded(seed: int) -> Objective:
    """Two terms over two free parameters, the first guarded by a decision tree over its features (a success
    classifier, Alg. 6) that fails near a random centre."""
    rng = np.random.default_rng(seed)
    objective = random_objective(rng, 2, 2, n_leaves=25, extra_kind="curved")
    term = objective.terms[0]
    theta = rng.uniform(objective.low, objective.high, size=(400, 2))
    F = term.features(theta)
    centre = rng.uniform(objective.low, objective.high)
    labels = (np.abs(theta - centre) / (objective.high - objective.low)).sum(axis=1) > 0.35
    tree = tree_arrays(DecisionTreeClassifier(max_leaf_nodes=8, random_state=0).fit(F, labels.astype(int)))

    class Region:  # what the certified optimizer asks of a success classifier: its leaves
        def regions(self):
            return tree.leaf_boxes(F.shape[1])

        def success_rules(self):
            return tree.success_boxes(F.shape[1])

    guarded_term = replace(term, valid=lambda t: tree.predict(term.features(t)), region=Region(),
                           region_features=term.features, region_bounds=term.feature_bounds)
    return Objective(objective.free, (guarded_term, objective.terms[1]))


def with_margin(objective: Objective, share: float) -> Objective:
    """The guard of `guarded` asked also `share` of each range to either side (Term.valid with a guard margin,
    as refine.action_term builds it: the moved point kept within the ranges)."""
    term = objective.terms[0]
    margin = tuple(share * (p.high - p.low) for p in objective.free)

    def valid(theta):
        theta = np.atleast_2d(theta)
        ok = np.asarray(term.valid(theta), dtype=bool)
        for j, m in enumerate(margin):
            for sign in (-1.0, 1.0):
                moved = theta.copy()
                moved[:, j] = np.clip(moved[:, j] + sign * m, objective.low[j], objective.high[j])
                ok &= np.asarray(term.valid(moved), dtype=bool)
        return ok

    return Objective(objective.free, (replace(term, valid=valid, region_margin=margin),) + objective.terms[1:])


@pytest.mark.parametrize("seed", range(4))
def test_boxes_predicted_to_fail_are_dropped_only_where_the_bound_proves_it(seed):
    objective = guarded(seed)
    result = certified.minimize(objective)
    assert objective.valid(np.array([result.values]))[0]
    assert bound_holds(result, objective)  # against the valid points only
    assert result.gap <= certified.tolerance_of(result.cost)


@pytest.mark.parametrize("seed", range(4))
def test_boxes_whose_guard_margin_fails_are_dropped_only_where_the_bound_proves_it(seed):
    """With a guard margin a valid choice needs success that far to either side too: boxes moved by it are
    tested as well, and the bound stays below every valid sampled cost (and closes)."""
    objective = with_margin(guarded(seed), 0.03)
    result = certified.minimize(objective)
    assert objective.valid(np.array([result.values]))[0]
    assert bound_holds(result, objective)
    assert result.gap <= certified.tolerance_of(result.cost)


def test_the_tree_bound_encloses_the_predictions_of_a_fitted_model_tree():
    rng = np.random.default_rng(0)
    X = rng.uniform(-1, 1, size=(3000, 3))
    tree = ModelTree(min_samples_leaf=10).fit(X, np.sin(3 * X[:, 0]) + X[:, 1] * np.abs(X[:, 2]))
    table = intervals.leaf_table(tree)
    low = rng.uniform(-1.2, 0.8, size=(200, 3))
    high = low + rng.uniform(0, 0.5, size=(200, 3))
    bound = intervals.minimum(table, intervals.Candidates.every(table, 200), low, high, 200)
    inside = low[:, None] + (high - low)[:, None] * rng.uniform(size=(200, 300, 3))
    predicted = tree.predict(inside.reshape(-1, 3)).reshape(200, 300)
    assert np.all(bound <= predicted.min(axis=1) + SLACK)
    points = intervals.minimum(table, intervals.Candidates.every(table, 200), low, low, 200)
    np.testing.assert_allclose(points, tree.predict(low), atol=1e-9)  # a point box: its own prediction


@pytest.mark.parametrize("kind", ["bound", "affine", "abs", "wrap", "sign", "curved", "mixed"])
def test_the_synthetic_feature_bounds_enclose_the_features(kind):
    rng = np.random.default_rng(4)
    maps = [FeatureMap(kind, -1 if kind == "bound" else 0, 1.3, 0.8, other=1 if kind == "mixed" else -1)]
    low = rng.uniform(-4, 3, size=(500, 2))
    high = low + rng.uniform(0, 1, size=(500, 2)) ** 3
    f_lo, f_hi = feature_bounds(maps)(low, high)
    theta = low[:, None] + (high - low)[:, None] * rng.uniform(size=(500, 200, 2))
    theta[:, 0], theta[:, -1] = low, high
    F = feature_function(maps)(theta.reshape(-1, 2)).reshape(500, 200)
    assert np.all(F >= f_lo) and np.all(F <= f_hi)


def test_the_line_space_bounds_enclose_its_features():
    from tailor.refinement.models.features import feature_space

    space = feature_space("line")
    rng = np.random.default_rng(5)
    low = rng.uniform(-3, 3, size=(400, 4))
    low[:, [1, 3]] = rng.uniform(-0.5, 0.5, size=(400, 2))
    high = low + rng.uniform(0, 1, size=(400, 4)) ** 2
    f_lo, f_hi = space.bounds(low, high)
    params = low[:, None] + (high - low)[:, None] * rng.uniform(size=(400, 100, 4))
    params[:, 0], params[:, -1] = low, high
    F = space(params.reshape(-1, 4)).reshape(400, 100, 3)
    assert np.all(F >= f_lo[:, None]) and np.all(F <= f_hi[:, None])
    point_lo, point_hi = space.bounds(low, low)  # a point: its own features
    np.testing.assert_array_equal(point_lo, space(low))
    np.testing.assert_array_equal(point_hi, space(low))


def test_the_registry_and_the_default():
    assert {"auto", "analytic", "certified", "ga", "sample"} == set(OPTIMIZERS)
    from tailor.refinement import pipeline
    from tailor.refinement.optimizers import DEFAULT_OPTIMIZER

    assert DEFAULT_OPTIMIZER == "auto" and pipeline.Options().optimizer == "auto"


# --- refinement of a chain of moves along a rail, learned in the core `line` space (which declares bounds) ------


def line_models():
    from tailor.refinement.models.action_models import ActionModel
    from tailor.refinement.models.features import compute_features, feature_names

    rng = np.random.default_rng(0)
    params = np.column_stack([rng.uniform(-5, 5, 4000), rng.uniform(-0.5, 0.5, 4000), rng.uniform(-5, 5, 4000),
                              rng.uniform(-0.5, 0.5, 4000)])
    F = compute_features("line", params)
    dist, v, vg = F.T
    duration = 0.5 + dist / 0.8 + 0.6 * np.abs(v - 0.4) + 0.4 * np.abs(vg - v) + 0.3 * (v < 0)
    tree = ModelTree(min_samples_leaf=10).fit(F, duration)
    return {"move": ActionModel("move", "line", feature_names("line"), tree, n_i=1)}


def rail(points):
    """Moves through `points` (the first the start at rest, the last a stop), each way-point's position free
    within 0.3 m and its speed within +-0.5 m/s."""
    from tailor.refinement.action_sequence import ActionSequence, ExecutableAction, Parameter

    def point(k, last):
        x = points[k]
        if k == 0 or last:
            return Parameter(f"p{k}.x", "x", x, x, x), Parameter(f"p{k}.v", "v", 0.0, 0.0, 0.0)
        return Parameter(f"p{k}.x", "x", None, x - 0.3, x + 0.3), Parameter(f"p{k}.v", "v", None, -0.5, 0.5)

    actions = []
    for k in range(1, len(points)):
        (x, v), (xg, vg) = point(k - 1, False), point(k, k == len(points) - 1)
        actions.append(ExecutableAction(k, f"(move p{k - 1} p{k})", "move",
                                        (x, v, replace(xg, name="xg"), replace(vg, name="vg"))))
    return ActionSequence("rail", "line", tuple(actions), {})


def test_refine_certifies_windows_of_a_chain_learned_in_the_line_space():
    from tailor.refinement.refine import refine

    models = line_models()
    sequence = rail([-2.5, -1.0, 1.0, 2.5])
    refined = refine(sequence, models, horizon=2, method="certified")
    assert [w.method for w in refined.windows] == ["certified", "certified"]  # (the last move's start is fixed)
    assert all(w.gap <= certified.tolerance_of(w.cost) for w in refined.windows)
    ga = refine(sequence, models, horizon=2, method="ga", compare="certified")
    for by_ga, by_bound in zip(ga.windows, ga.compared):  # the same windows: never above the GA's choice
        assert by_bound.cost <= by_ga.cost * (1 + certified.TOLERANCE)
        assert by_bound.lower_bound <= by_ga.cost + SLACK


def test_auto_budget_is_boxes_fewer_for_each_free_parameter_beyond_four():
    """auto's budget counts boxes, not seconds (the same window gets the same choice on any machine), and shrinks
    where a window has more free parameters than any bundled window certified."""
    from tailor.refinement.optimizers import AUTO_BUDGET, AUTO_WIDE, auto_budget

    assert auto_budget(2) == auto_budget(4) == AUTO_BUDGET
    assert auto_budget(6) == AUTO_BUDGET // AUTO_WIDE ** 2 < auto_budget(5) < AUTO_BUDGET


@pytest.mark.parametrize("seed", range(4))
def test_a_validity_check_is_never_asked_about_no_points(seed):
    """Once every half of a step is pruned or bounded within the tolerance there is nothing to evaluate: a
    validity check (a limit on a measure, a success classifier) that cannot take an empty batch is not called."""
    objective = random_objective(np.random.default_rng(seed), 2, 2, n_leaves=30, extra_kind="curved")
    term = objective.terms[0]

    def strict(theta):
        assert len(np.atleast_2d(theta)), "validity asked about an empty batch"
        return np.ones(len(np.atleast_2d(theta)), dtype=bool)

    result = certified.minimize(Objective(objective.free, (replace(term, valid=strict),) + objective.terms[1:]))
    assert result.gap <= certified.tolerance_of(result.cost)


def test_auto_gives_up_at_once_on_a_gap_its_budget_could_not_close_and_not_on_one_it_can():
    """Six free parameters and a gap of 5700% after the first 64 boxes: closing it within auto's budget would take
    it falling faster than certified.FASTEST / 6 halvings per doubling of the boxes, so auto stops there and runs
    the GA (certified alone, without a prospect, searches on); four free parameters whose gap closes within the
    budget (after 27,000 boxes) are searched to the end."""
    wide = random_objective(np.random.default_rng(1), 6, 3, n_leaves=30, extra_kind="curved")
    result = optimize(wide, seed=0)
    assert result.method == "ga" and "even at the fastest fall" in result.note
    assert int(re.search(r"(\d+) boxes", result.note).group(1)) <= certified.WIDE
    alone = certified.minimize(wide, budget=2000)
    assert "fastest" not in alone.note and int(re.search(r"(\d+) boxes", alone.note).group(1)) >= 2000
    closing = random_objective(np.random.default_rng(0), 4, 3, n_leaves=30, extra_kind="curved")
    result = optimize(closing, seed=0)
    assert result.method == "certified" and result.gap <= certified.tolerance_of(result.cost)
