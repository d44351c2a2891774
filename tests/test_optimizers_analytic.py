"""Analytic minimization of sums of model trees (App. C.3): the dissertation's examples and brute force."""

import numpy as np
import pytest
from rule_models import RuleModel, identity, rule
from tailor.refinement.optimizers import FreeParameter, Objective, Term, brute_force, optimize
from tailor.refinement.optimizers.analytic import merge, term_boxes
from tailor.refinement.optimizers.structure import detect
from tailor.refinement.optimizers.synthetic import FeatureMap, feature_function, random_objective, wrap

INF = np.inf
GRID = {1: 4001, 2: 401, 3: 61}


# App. C.3.1: the fictional tree over (dist, angle)
C31 = RuleModel([
    rule([-INF, -INF], [0.59, INF], [1.39, 0.68], 0.09),
    rule([0.59, -INF], [1.52, 0.62], [1.35, 0.22], 0.13),
    rule([0.59, 0.62], [1.52, INF], [-0.01, 0.80], 1.15),
    rule([1.52, -INF], [INF, INF], [1.32, 0.51], 0.15),
])


def test_single_tree_minimum_of_appendix_c31():
    free = (FreeParameter("dist", 0, 3), FreeParameter("angle", 0, np.pi))
    objective = Objective(free, (Term(C31, identity),))
    structure = detect(objective.terms[0], objective.low, objective.high, ("dist", "angle"))
    lo, hi, grad, const = term_boxes(structure, C31)
    minima = np.sort(const + np.sum(grad * np.where(grad > 0, lo, hi), axis=1))
    np.testing.assert_allclose(minima, [0.09, 0.9265, 1.6308, 2.1564], atol=1e-9)  # C.3.1: 0.09 .93 1.63 2.16
    result = optimize(objective)
    assert result.method == "analytic"
    assert result.values == (0.0, 0.0) and result.cost == pytest.approx(0.09)


def test_bound_variable_of_appendix_c32():
    """angle bound to 0.7: R2 is dropped and the minimum is 0.57 at dist = 0 (C.3.2)."""
    term = Term(C31, lambda theta: np.column_stack([theta[:, 0], np.full(len(theta), 0.7)]))
    objective = Objective((FreeParameter("dist", 0, 3),), (term,))
    structure = detect(term, objective.low, objective.high, ("dist",))
    lo, hi, grad, const = term_boxes(structure, C31)
    minima = np.sort(const + np.sum(grad * np.where(grad > 0, lo, hi), axis=1))
    np.testing.assert_allclose(minima, [0.566, 1.6948, 2.5134], atol=1e-9)  # C.3.2 prints 0.57, 1.69, 2.50
    result = optimize(objective)
    assert result.values == (0.0,) and result.cost == pytest.approx(0.566)


def test_merged_rule_sets_of_appendix_c33():
    """Two trees over (a, b) merge into exactly the six non-contradictory rules of C.3.3."""
    tree1 = RuleModel([
        rule([-INF, -INF], [1, 3], [3, 2], 1),
        rule([-INF, 3], [1, INF], [4, 5], 6),
        rule([1, -INF], [INF, INF], [3, 4], 1),
    ])
    tree2 = RuleModel([
        rule([-INF, -INF], [INF, 2], [1, 1], 1),
        rule([-INF, 2], [2, INF], [1, 3], 2),
        rule([2, 2], [INF, INF], [1, 2], 3),
    ])
    free = (FreeParameter("a", 0, 3), FreeParameter("b", 0, 5))
    terms = (Term(tree1, identity), Term(tree2, identity))
    low, high = np.array([0.0, 0.0]), np.array([3.0, 5.0])
    boxes = [term_boxes(detect(t, low, high, ("a", "b")), t.model) for t in terms]
    lo, hi, grad, const = merge(*boxes)
    got = sorted(zip(map(tuple, lo), map(tuple, hi), map(tuple, grad), const))
    expected = sorted([  # (a, b) ranges and the summed linear models of the six rules
        ((0, 0), (1, 2), (4, 3), 2), ((0, 2), (1, 3), (4, 5), 3), ((0, 3), (1, 5), (5, 8), 8),
        ((1, 0), (3, 2), (4, 5), 2), ((1, 2), (2, 5), (4, 7), 3), ((2, 2), (3, 5), (4, 6), 4),
    ])
    assert len(got) == 6
    for g, e in zip(got, expected):
        for x, y in zip(g, e):
            np.testing.assert_allclose(x, y, atol=1e-9)
    result = optimize(Objective(free, terms))
    assert result.values == (0.0, 0.0) and result.cost == pytest.approx(2.0)


def test_breakpoints_are_located_precisely():
    """A wrap jump, an abs kink and a sign flip at known places are found to 1e-9."""
    maps = [FeatureMap("wrap", 0, 0.3, 0), FeatureMap("abs", 0, -1.1, 0), FeatureMap("sign", 0, 2.0, 0.5)]
    term = Term(C31, feature_function(maps))
    structure = detect(term, np.array([-np.pi]), np.array([np.pi]), ("phi",))
    expected = sorted([wrap(np.array(0.3 - np.pi)).item(), -1.1, wrap(np.array(-1.1 + np.pi)).item(), 2.0,
                       wrap(np.array(2.0 - np.pi)).item()])
    np.testing.assert_allclose(structure.edges[0][1:-1], expected, atol=1e-9)
    assert list(structure.var_of) == [0, 0, 0]


@pytest.mark.parametrize("seed", range(24))
def test_analytic_matches_brute_force_on_random_trees(seed):
    rng = np.random.default_rng(seed)
    n_free, n_terms = int(rng.integers(1, 4)), int(rng.integers(1, 4))
    objective = random_objective(rng, n_free, n_terms, n_leaves=20)
    result = optimize(objective, "analytic")
    grid = brute_force(objective, GRID[n_free])
    assert result.method == "analytic", result.note
    assert np.all((np.array(result.values) >= objective.low) & (np.array(result.values) <= objective.high))
    assert objective.cost(np.array([result.values]))[0] == result.cost  # a true cost, not a prediction
    assert result.cost <= grid.cost + 1e-9


@pytest.mark.parametrize("seed", range(6))
def test_analytic_equals_fine_grid_in_one_dimension(seed):
    rng = np.random.default_rng(100 + seed)
    objective = random_objective(rng, 1, 1 + seed % 3, n_leaves=30)
    result = optimize(objective, "analytic")
    grid = brute_force(objective, 200_001)  # spacing 3e-5 rad
    assert result.method == "analytic"
    assert grid.cost - 1e-2 <= result.cost <= grid.cost + 1e-9


def test_validity_is_respected():
    rng = np.random.default_rng(7)
    objective = random_objective(rng, 2, 2, n_leaves=20)
    best = optimize(objective)
    phi = best.values[0]  # forbid the unconstrained optimum's neighbourhood
    term = objective.terms[0]
    forbidden = Term(term.model, term.features, valid=lambda th: np.abs(wrap(th[:, 0] - phi)) > 0.5)
    constrained = Objective(objective.free, (forbidden,) + objective.terms[1:])
    result = optimize(constrained)
    grid = brute_force(constrained, 401)
    assert result.method == "analytic"
    assert abs(wrap(np.array(result.values[0] - phi))) > 0.5
    assert best.cost <= result.cost <= grid.cost + 1e-9


@pytest.mark.parametrize("kind, reason", [("curved", "not piecewise affine"), ("mixed", "depends on both")])
def test_falls_back_to_ga_where_not_mergeable(kind, reason):
    objective = random_objective(np.random.default_rng(3), 2, 2, n_leaves=20, extra_kind=kind)
    result = optimize(objective, "analytic", seed=5)
    assert result.method == "ga"
    assert reason in result.note and result.note.startswith("analytic not applicable")
    assert objective.cost(np.array([result.values]))[0] == result.cost
