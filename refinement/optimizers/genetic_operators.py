"""DEAP's operators of Sec. 5.4.3 over a whole population at once, as numpy arrays.

`tools.selRoulette`, `tools.cxTwoPoint`, `tools.cxBlend` and `tools.mutGaussian` loop in Python over the
individuals (and their genes): in the genetic algorithm they took a fifth of its time per window. Each function
here does what its DEAP operator does to every row (or pair of rows) of a population (rows: individuals,
columns: genes), with the same draws, made by one numpy generator owned by the run (`draw_*`): fed the same draws,
DEAP's operator gives the same genes (tests/test_optimizers_genetic.py checks each against DEAP's own function).
"""

from __future__ import annotations

import numpy as np


def draw_spins(rng: np.random.Generator, k: int) -> np.ndarray:
    """selRoulette's draws: a uniform number in [0, 1) per individual chosen."""
    return rng.random(k)


def roulette(fitness: np.ndarray, spins: np.ndarray) -> np.ndarray:
    """Indices chosen with probability proportional to `fitness` (>= 0): for each spin u the first individual
    whose cumulative fitness exceeds u times the total, as selRoulette over a population ranked by fitness (its
    ranking changes which individual a spin picks, not how likely each is). Where the total is 0 (every
    individual invalid, or all alike at a cost of 0) each is as likely: selRoulette would choose none."""
    cumulative = np.cumsum(fitness)
    if not cumulative[-1] > 0:
        return np.minimum((spins * len(fitness)).astype(np.intp), len(fitness) - 1)
    last = int(np.flatnonzero(fitness > 0)[-1])  # rounding never picks an individual of fitness 0 past the end
    return np.minimum(np.searchsorted(cumulative, spins * cumulative[-1], side="right"), last)


def draw_cuts(rng: np.random.Generator, pairs: int, n_genes: int) -> tuple[np.ndarray, np.ndarray]:
    """cxTwoPoint's draws for each pair: randint(1, n) and randint(1, n - 1)."""
    return rng.integers(1, n_genes, size=pairs, endpoint=True), rng.integers(1, n_genes - 1, size=pairs,
                                                                              endpoint=True)


def two_point(a: np.ndarray, b: np.ndarray, first: np.ndarray, second: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """cxTwoPoint of each row of `a` with the same row of `b` (pairs, n) given its draws: the genes between the
    two cut points swapped (new arrays)."""
    second = np.where(second >= first, second + 1, second)
    start, stop = np.minimum(first, second), np.maximum(first, second)
    gene = np.arange(a.shape[1])
    swap = (gene >= start[:, None]) & (gene < stop[:, None])
    return np.where(swap, b, a), np.where(swap, a, b)


def draw_blend(rng: np.random.Generator, pairs: int, n_genes: int) -> np.ndarray:
    """cxBlend's draws: a uniform number in [0, 1) per gene of each pair."""
    return rng.random((pairs, n_genes))


def blend(a: np.ndarray, b: np.ndarray, u: np.ndarray, alpha: float) -> tuple[np.ndarray, np.ndarray]:
    """cxBlend of each row of `a` with the same row of `b` given its draws `u` (pairs, n): each gene moved to
    a random point of the parents' interval widened by alpha times its width to either side (new arrays)."""
    gamma = (1.0 + 2.0 * alpha) * u - alpha
    return (1.0 - gamma) * a + gamma * b, gamma * a + (1.0 - gamma) * b


def draw_mutation(rng: np.random.Generator, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """mutGaussian's draws: per gene a uniform number in [0, 1) (mutated where below indpb) and a standard
    normal one (its step, in standard deviations)."""
    return rng.random(shape), rng.standard_normal(shape)


def gaussian(genes: np.ndarray, u: np.ndarray, z: np.ndarray, sigma: np.ndarray, indpb: float) -> np.ndarray:
    """mutGaussian with mean 0 and a standard deviation per gene (column), given its draws: z * sigma added
    where u < indpb, the other genes untouched (a new array)."""
    return np.where(u < indpb, genes + z * sigma, genes)
