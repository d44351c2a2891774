"""The genetic algorithm of Sec. 5.4.3: optimum on small cases, determinism, validity, DEAP's operators."""

import random
from collections import Counter

import numpy as np
import pytest
from deap import base, tools

from refinement.optimizers import Objective, Term, brute_force, optimize
from refinement.optimizers import genetic
from refinement.optimizers.synthetic import random_objective, wrap


class _Fitness(base.Fitness):
    weights = (1.0,)


class _Ind(list):
    def __init__(self, genes):
        super().__init__(genes)
        self.fitness = _Fitness()


@pytest.mark.parametrize("seed, n_free", [(0, 1), (1, 1), (2, 2), (3, 2)])
def test_ga_finds_the_brute_force_optimum_on_small_cases(seed, n_free):
    objective = random_objective(np.random.default_rng(seed), n_free, 1, n_leaves=6, n_features=2)
    result = optimize(objective, "ga", seed=seed)
    grid = brute_force(objective, {1: 20001, 2: 601}[n_free])
    assert result.method == "ga"
    assert objective.cost(np.array([result.values]))[0] == result.cost
    assert abs(result.cost - grid.cost) <= 0.02 * (1 + abs(grid.cost))


def test_same_seed_same_result_and_seeds_differ():
    objective = random_objective(np.random.default_rng(11), 2, 2, n_leaves=20)
    first, again = optimize(objective, "ga", seed=4), optimize(objective, "ga", seed=4)
    assert (first.values, first.cost, first.evaluations) == (again.values, again.cost, again.evaluations)
    other = optimize(objective, "ga", seed=5)
    assert other.values != first.values
    state = random.getstate()  # the GA must not touch the global generators
    optimize(objective, "ga", seed=4)
    assert random.getstate() == state


class CountingModel:
    """Records the batch size of every prediction (one per generation)."""

    def __init__(self, model):
        self.model, self.batches = model, []

    def predict(self, F):
        self.batches.append(len(F))
        return self.model.predict(F)

    def rules(self):
        return self.model.rules()


def test_population_and_generation_count():
    objective = random_objective(np.random.default_rng(2), 3, 1, n_leaves=10)
    spy = CountingModel(objective.terms[0].model)
    term = Term(spy, objective.terms[0].features)
    result = genetic.minimize(Objective(objective.free, (term,)), seed=0)
    assert set(spy.batches) == {75}  # 25 x 3 free parameters, one vectorized call per generation
    assert genetic.STALL_GENERATIONS < len(spy.batches) <= genetic.MAX_GENERATIONS
    assert result.evaluations == 75 * len(spy.batches)
    assert result.note == f"{len(spy.batches)} generations"


def test_invalid_parameterizations_get_the_lowest_fitness():
    cost = np.array([3.0, 1.0, 2.0, 0.5])
    valid = np.array([True, True, True, False])
    np.testing.assert_allclose(genetic.fitness(cost, valid), [1.0, 3.0, 2.0, 0.0])  # t_max + t_min - t


def test_ga_avoids_invalid_region():
    objective = random_objective(np.random.default_rng(8), 1, 1, n_leaves=10)
    phi = optimize(objective).values[0]
    term = objective.terms[0]
    guarded = Term(term.model, term.features, valid=lambda th: np.abs(wrap(th[:, 0] - phi)) > 1.0)
    result = optimize(Objective(objective.free, (guarded,)), "ga", seed=1)
    assert abs(wrap(np.array(result.values[0] - phi))) > 1.0


def test_roulette_selects_like_deap():
    """Selection frequencies of our roulette and DEAP's selRoulette agree (both proportional to fitness)."""
    fit = np.array([0.5, 3.0, 1.0, 0.0, 1.5])
    ours = Counter(genetic.select_roulette(fit, 60_000, np.random.default_rng(0)).tolist())
    population = [_Ind([i]) for i in range(len(fit))]
    for ind, f in zip(population, fit):
        ind.fitness.values = (float(f),)
    state = random.getstate()
    random.seed(0)
    theirs = Counter(ind[0] for ind in tools.selRoulette(population, 60_000))
    random.setstate(state)
    share = fit / fit.sum()
    for i in range(len(fit)):
        assert ours[i] / 60_000 == pytest.approx(share[i], abs=0.01)
        assert theirs[i] / 60_000 == pytest.approx(share[i], abs=0.01)


def test_two_point_crossover_swaps_like_deap():
    """The distribution of swapped gene segments equals DEAP's cxTwoPoint on four genes."""
    n = 20_000
    parents = np.tile(np.array([[0.0, 0, 0, 0], [1.0, 1, 1, 1]]), (n, 1))
    children = genetic.crossover(parents, np.random.default_rng(0))[0::2]
    mated = children.any(axis=1)
    assert mated.mean() == pytest.approx(genetic.CROSSOVER_PROB, abs=0.015)
    ours = Counter(tuple(c) for c in children[mated].astype(int))
    state = random.getstate()
    random.seed(0)
    theirs = Counter(tuple(tools.cxTwoPoint([0, 0, 0, 0], [1, 1, 1, 1])[0]) for _ in range(n))
    random.setstate(state)
    assert set(ours) == set(theirs)
    total = sum(ours.values())
    for mask, count in theirs.items():
        assert ours[mask] / total == pytest.approx(count / n, abs=0.02)


def test_single_gene_uses_blend_crossover():
    """With one gene there is no inner cut point: cxBlend (alpha 0.5) mixes the pair, keeping its sum."""
    parents = np.array([[0.0], [2.0]] * 500)
    children = genetic.crossover(parents, np.random.default_rng(3))
    np.testing.assert_allclose(children[0::2] + children[1::2], 2.0)
    mated = children[0::2, 0] != 0.0
    assert mated.mean() == pytest.approx(genetic.CROSSOVER_PROB, abs=0.06)
    gamma = children[0::2, 0][mated] / 2.0
    assert -0.5 <= gamma.min() < -0.3 and 1.3 < gamma.max() <= 1.5  # gamma uniform in [-alpha, 1 + alpha]
