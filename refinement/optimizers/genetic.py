"""The genetic algorithm of Sec. 5.4.3: one float gene per free parameter, fitness-proportionate selection.

Population 25 x the number of free parameters, initialized uniformly within the ranges; each generation the
best 2% (at least one) pass unchanged, the rest are chosen by roulette on the fitness t_max + t_min - t
(t over the current population; a parameterization a model marks invalid gets fitness 0, the lowest),
paired for two-point crossover with probability 0.65 and mutated with clipped Gaussian noise. The loop stops
when the best cost has not improved for 50 generations, or after 500.

The operators are those of DEAP (`tools.selRoulette`, `tools.cxTwoPoint`, `tools.cxBlend`,
`tools.mutGaussian`), written here on a whole population at once: DEAP's functions draw from the global
`random` module and loop in Python per individual, while refinement must be seeded by its own argument only
and evaluate a generation with one vectorized call of the objective. tests/test_optimizers_genetic.py
checks each one against DEAP's own.
"""

from __future__ import annotations

import time

import numpy as np

from refinement.optimizers.objective import Objective, OptimizationResult

POPULATION_PER_PARAMETER = 25
ELITE_FRACTION = 0.02
CROSSOVER_PROB = 0.65
BLEND_ALPHA = 0.5  # cxBlend with a single gene, where two-point crossover has no inner point
MUTATION_SIGMA = 0.1  # standard deviation of the Gaussian mutation, as a fraction of the parameter's range
STALL_GENERATIONS = 50
MAX_GENERATIONS = 500


def fitness(cost: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """t_max + t_min - t over the valid individuals (non-negative for durations); 0 for invalid ones."""
    if not valid.any():
        return np.zeros(len(cost))
    t = cost[valid]
    t_max, t_min = t.max(), t.min()
    return np.where(valid, t_max - cost + max(t_min, 0.0), 0.0)


def select_roulette(fit: np.ndarray, k: int, rng: np.random.Generator) -> np.ndarray:
    """Indices of k spins of a roulette with slots proportional to fit (as DEAP's selRoulette)."""
    order = np.argsort(-fit, kind="stable")
    total = np.cumsum(fit[order])
    if total[-1] <= 0:  # no individual is better than another: every slot equally wide
        return order[rng.integers(0, len(fit), size=k)]
    spins = rng.random(k) * total[-1]
    return order[np.minimum(np.searchsorted(total, spins, side="right"), len(fit) - 1)]


def crossover(genes: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Consecutive pairs mate with CROSSOVER_PROB: two-point (as cxTwoPoint), or cxBlend with one gene."""
    genes = genes.copy()
    n_pairs = len(genes) // 2
    first, second = genes[0 : 2 * n_pairs : 2], genes[1 : 2 * n_pairs : 2]
    mate = rng.random(n_pairs) < CROSSOVER_PROB
    size = genes.shape[1]
    if size == 1:
        gamma = (1 + 2 * BLEND_ALPHA) * rng.random((n_pairs, 1)) - BLEND_ALPHA
        a = (1 - gamma) * first + gamma * second
        b = gamma * first + (1 - gamma) * second
    else:
        cut1 = rng.integers(1, size + 1, size=n_pairs)
        cut2 = rng.integers(1, size, size=n_pairs)
        cut2 = np.where(cut2 >= cut1, cut2 + 1, cut2)
        lo, hi = np.minimum(cut1, cut2), np.maximum(cut1, cut2)
        column = np.arange(size)[None, :]
        swap = (column >= lo[:, None]) & (column < hi[:, None])
        a = np.where(swap, second, first)
        b = np.where(swap, first, second)
    genes[0 : 2 * n_pairs : 2] = np.where(mate[:, None], a, first)
    genes[1 : 2 * n_pairs : 2] = np.where(mate[:, None], b, second)
    return genes


def mutate(genes: np.ndarray, sigma: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Gaussian noise on each gene with probability 1 / n_genes (as mutGaussian's indpb)."""
    hit = rng.random(genes.shape) < 1.0 / genes.shape[1]
    return genes + np.where(hit, rng.normal(0.0, 1.0, genes.shape) * sigma, 0.0)


def minimize(objective: Objective, seed: int = 0) -> OptimizationResult:
    """Run the GA; seeded by `seed` only, one vectorized objective call per generation."""
    start = time.perf_counter()
    rng = np.random.default_rng(seed)
    low, high = objective.low, objective.high
    n_free = len(low)
    size = POPULATION_PER_PARAMETER * max(1, n_free)
    n_elite = max(1, round(ELITE_FRACTION * size))
    sigma = MUTATION_SIGMA * (high - low)
    population = rng.uniform(low, high, size=(size, n_free))
    best_cost, best_genes, best_valid = np.inf, population[0], False
    stall = generation = evaluations = 0
    while generation < MAX_GENERATIONS and stall < STALL_GENERATIONS:
        cost = objective.cost(population)
        valid = objective.valid(population)
        evaluations += size
        generation += 1
        rank = np.lexsort((cost, ~valid))  # valid first, then by cost
        top = rank[0]
        if (valid[top], -cost[top]) > (best_valid, -best_cost):
            stall = 0
            best_cost, best_genes, best_valid = float(cost[top]), population[top].copy(), bool(valid[top])
        else:
            stall += 1
        elite = population[rank[:n_elite]]
        chosen = population[select_roulette(fitness(cost, valid), size - n_elite, rng)]
        offspring = np.clip(mutate(crossover(chosen, rng), sigma, rng), low, high)
        population = np.concatenate([elite, offspring])
    return OptimizationResult(
        values=tuple(float(v) for v in best_genes),
        cost=best_cost,
        method="ga",
        evaluations=evaluations,
        seconds=time.perf_counter() - start,
        note=f"{generation} generations" + ("" if best_valid else "; no valid parameterization found"),
    )
