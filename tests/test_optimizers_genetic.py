"""The genetic algorithm of Sec. 5.4.3: optimum on small cases, determinism, validity, DEAP's operators (each
vectorized operator against DEAP's own function, fed the same draws), the polish."""

import random

import deap.tools.crossover
import deap.tools.mutation
import deap.tools.selection
import numpy as np
import pytest
from deap import base, tools
from tailor.refinement.optimizers import Objective, Term, brute_force, genetic, optimize
from tailor.refinement.optimizers import genetic_operators as ops
from tailor.refinement.optimizers.synthetic import random_objective, wrap


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


def test_runs_in_threads_at_once_reproduce_the_serial_results_bit_for_bit():
    """Each run draws from a generator of its own (with module-global generators swapped in and out, threaded
    refinement gave 12.75197, 12.757473, ... against 12.755467 serially)."""
    from concurrent.futures import ThreadPoolExecutor

    objectives = [random_objective(np.random.default_rng(k), 2, 2, n_leaves=20) for k in range(6)]
    serial = [optimize(objective, "ga", seed=k) for k, objective in enumerate(objectives)]
    with ThreadPoolExecutor(4) as pool:
        threaded = list(pool.map(lambda k: optimize(objectives[k], "ga", seed=k), range(6)))
    assert [(r.values, r.cost) for r in threaded] == [(r.values, r.cost) for r in serial]


def test_draws_from_the_global_generator_in_another_thread_change_nothing():
    """A Dask worker runs its tasks in a thread while its event loop draws from `random`: the GA's draws are its
    own (with the shared global generator, refinement on Dask gave other subgoals from run to run)."""
    import threading

    objective = random_objective(np.random.default_rng(11), 2, 2, n_leaves=20)
    alone = optimize(objective, "ga", seed=4)
    stop = threading.Event()

    def draw() -> None:
        while not stop.is_set():
            random.random()

    thread = threading.Thread(target=draw)
    thread.start()
    try:
        busy = [optimize(objective, "ga", seed=4) for _ in range(3)]
    finally:
        stop.set()
        thread.join()
    assert all((r.values, r.cost, r.evaluations) == (alone.values, alone.cost, alone.evaluations) for r in busy)


class CountingModel:
    """Records the batch size of every prediction (one per generation)."""

    def __init__(self, model):
        self.model, self.batches = model, []

    def predict(self, F):
        self.batches.append(len(F))
        return self.model.predict(F)

    def rules(self):
        return self.model.rules()


def test_population_and_generation_count(monkeypatch):
    monkeypatch.setattr(genetic, "POLISH_ROUNDS", 0)  # the generations alone
    objective = random_objective(np.random.default_rng(2), 3, 1, n_leaves=10)
    spy = CountingModel(objective.terms[0].model)
    term = Term(spy, objective.terms[0].features)
    result = genetic.minimize(Objective(objective.free, (term,)), seed=0)
    # 25 x 3 free parameters, one vectorized call per generation, of those changed since they were copied
    assert spy.batches[0] == 75 and max(spy.batches) <= 75
    assert genetic.STALL_GENERATIONS < len(spy.batches) <= genetic.MAX_GENERATIONS
    assert result.evaluations == 75 * len(spy.batches)  # every individual judged (some by the one it copies)
    assert result.note == f"{len(spy.batches)} generations"


def test_the_polish_takes_only_better_moves_and_counts_its_candidates():
    """From a poor point the compass search moves downhill; from the GA's best it never makes it worse; each
    round is one call of 2 x steps x genes candidates."""
    objective = random_objective(np.random.default_rng(2), 3, 1, n_leaves=10)
    start = np.array([0.5 * (lo + hi) for lo, hi in zip(objective.low, objective.high)])
    cost = float(objective.cost(start[None])[0])
    genes, polished, valid, judged = genetic.polish(objective, start, cost, True)
    assert valid and polished < cost and polished == objective.cost(genes[None])[0]
    assert judged % (2 * len(genetic.POLISH_STEPS) * 3) == 0
    assert np.all(genes >= objective.low) and np.all(genes <= objective.high)
    again = genetic.polish(objective, genes, polished, True)
    assert again[1] <= polished
    result = optimize(objective, "ga", seed=3)
    settled = genetic.polish(objective, np.array(result.values), result.cost, True)
    assert settled[1] == result.cost and settled[3] == 2 * len(genetic.POLISH_STEPS) * 3  # the GA's choice is already polished: no move is better


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


class Fitness(base.Fitness):
    weights = (1.0,)


class Individual(list):
    """A DEAP individual: genes and a fitness."""

    def __init__(self, genes, fitness: float):
        super().__init__(genes)
        self.fitness = Fitness((fitness,))


class Scripted:
    """Stands in for the `random` module inside DEAP's operator modules: returns the given draws in order
    (gauss(mu, sigma) as mu + sigma times the next standard normal one)."""

    def __init__(self, uniform=(), integers=(), normal=()):
        self.uniform, self.integers, self.normal = iter(uniform), iter(integers), iter(normal)

    def random(self) -> float:
        return float(next(self.uniform))

    def randint(self, a: int, b: int) -> int:
        value = int(next(self.integers))
        assert a <= value <= b
        return value

    def gauss(self, mu: float, sigma: float) -> float:
        return mu + sigma * float(next(self.normal))


def test_roulette_chooses_like_deaps_selroulette(monkeypatch):
    """The same spins choose the same individuals as tools.selRoulette over a population ranked by fitness
    (its own ranking: ties and zero fitness included); a spin never picks an individual of fitness 0."""
    rng = np.random.default_rng(0)
    fit = np.sort(np.round(rng.exponential(size=40), 1))[::-1]
    fit[-3:] = 0.0
    population = [Individual([i], f) for i, f in enumerate(fit)]
    spins = ops.draw_spins(np.random.default_rng(7), 500)
    monkeypatch.setattr(deap.tools.selection, "random", Scripted(uniform=spins))
    theirs = [ind[0] for ind in tools.selRoulette(population, 500)]
    ours = ops.roulette(fit, spins)
    assert ours.tolist() == theirs and not np.isin([37, 38, 39], ours).any()
    assert set(ops.roulette(np.zeros(5), spins[:50])) <= set(range(5))  # all alike: every one as likely


def test_two_point_crossover_is_deaps_cxtwopoint(monkeypatch):
    rng = np.random.default_rng(1)
    for n in (2, 3, 6):
        a, b = rng.uniform(size=(30, n)), rng.uniform(size=(30, n))
        first, second = ops.draw_cuts(rng, 30, n)
        ours = ops.two_point(a, b, first, second)
        monkeypatch.setattr(deap.tools.crossover, "random",
                            Scripted(integers=np.column_stack([first, second]).ravel()))
        theirs = [tools.cxTwoPoint(list(x), list(y)) for x, y in zip(a, b)]
        assert ours[0].tolist() == [x for x, _ in theirs] and ours[1].tolist() == [y for _, y in theirs]


def test_blend_crossover_is_deaps_cxblend(monkeypatch):
    rng = np.random.default_rng(2)
    a, b = rng.uniform(size=(30, 1)), rng.uniform(size=(30, 1))
    u = ops.draw_blend(rng, 30, 1)
    ours = ops.blend(a, b, u, genetic.BLEND_ALPHA)
    monkeypatch.setattr(deap.tools.crossover, "random", Scripted(uniform=u.ravel()))
    theirs = [tools.cxBlend(list(x), list(y), alpha=genetic.BLEND_ALPHA) for x, y in zip(a, b)]
    assert ours[0].tolist() == [x for x, _ in theirs] and ours[1].tolist() == [y for _, y in theirs]


def test_gaussian_mutation_is_deaps_mutgaussian(monkeypatch):
    """With a fixed mean and a standard deviation per gene, as the GA uses it: the same genes changed by the
    same amounts, the others untouched."""
    rng = np.random.default_rng(3)
    sigma = np.array([0.1, 0.5, 2.0])
    genes = rng.uniform(-1, 1, size=(200, 3))
    u, z = ops.draw_mutation(rng, genes.shape)
    ours = ops.gaussian(genes, u, z, sigma, 1 / 3)
    monkeypatch.setattr(deap.tools.mutation, "random", Scripted(uniform=u.ravel(), normal=z[u < 1 / 3]))
    theirs = [tools.mutGaussian(list(row), mu=0.0, sigma=sigma.tolist(), indpb=1 / 3)[0] for row in genes]
    assert ours.tolist() == theirs
    assert 0 < np.mean(ours != genes) < 0.5


def test_a_generation_judges_only_the_individuals_changed_since_they_were_copied():
    """The elite and the offspring neither mated nor mutated keep their cost (the same values, fewer calls)."""
    objective = random_objective(np.random.default_rng(2), 3, 1, n_leaves=10)
    spy = CountingModel(objective.terms[0].model)
    counted = Objective(objective.free, (Term(spy, objective.terms[0].features),))
    genes = np.random.default_rng(0).uniform(objective.low, objective.high, size=(75, 3))
    cost, valid = genetic.judge(counted, genes)
    copied = np.concatenate([genes[:70], genes[:5]])
    changed = np.concatenate([genes[:70], genes[:5] + 0.01])
    again, _ = genetic.judge(counted, changed, (copied, cost[np.r_[:70, :5]], valid[np.r_[:70, :5]]))
    assert spy.batches == [75, 5]
    np.testing.assert_array_equal(again[:70], cost[:70])
    np.testing.assert_array_equal(again[70:], objective.cost(genes[:5] + 0.01))


def test_offspring_stay_within_the_ranges_and_name_their_parents():
    low, high = np.array([0.0, -1.0, 5.0]), np.array([1.0, 1.0, 6.0])
    rng = np.random.default_rng(3)
    genes = rng.uniform(low, high, size=(75, 3))
    for _ in range(20):
        fit = rng.random(75)
        order = np.argsort(-fit)
        offspring, parents = genetic.next_generation(rng, genes, fit, order, 2, low, high)
        assert offspring.shape == (75, 3) and parents.shape == (75,)
        assert np.all(offspring >= low) and np.all(offspring <= high)
        np.testing.assert_array_equal(offspring[:2], genes[order[:2]])  # the elite, unchanged
        unchanged = np.all(offspring == genes[parents], axis=1)
        assert 0 < unchanged[2:].mean() < 0.5  # most offspring mated or mutated, some neither
        genes = offspring
