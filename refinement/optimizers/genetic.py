"""The genetic algorithm of Sec. 5.4.3, built from DEAP's operators.

One float gene per free parameter; population 25 x the number of free parameters, initialized uniformly
within the ranges; each generation the best 2% (at least one) pass unchanged, the rest are chosen by
`tools.selRoulette` on the fitness t_max + t_min - t (t over the current population; a parameterization a
model marks invalid gets fitness 0, the lowest; `sel_roulette` is selRoulette with a binary search),
mated pairwise with `tools.cxTwoPoint` on 65% of them
(`tools.cxBlend` with a single gene, which has no inner cut point) and mutated with `tools.mutGaussian`
(`mut_gaussian`: the same draws, the generator looked up once per individual), clipped to the ranges. The loop stops when the best cost has not improved for 50 generations, or after 500
(a progress bar over the generations where the caller shows progress: tailor.progress).

DEAP's operators draw from their modules' `random`: that name is bound, once, to a stand-in that draws from the
generator of the run in progress in the calling thread or task (a `random.Random(seed)` owned by the call, held
in a context variable), and from the global generator outside a run. So refinement is seeded by its argument
only, runs in several threads at once reproduce the serial results draw for draw, other threads drawing from
the global generator meanwhile (a Dask worker's event loop does) change nothing, and the caller's state is
untouched. The fitness and individual types are plain classes defined once here, not written into
`deap.creator`. A generation is evaluated with one vectorized call of the objective, for the individuals the
generation before did not hold already (the elite and the offspring neither mated nor mutated keep their cost:
with a neighbourhood each individual costs dozens of feature rows).
"""

from __future__ import annotations

import random
import sys
import time
from bisect import bisect_right
from contextlib import contextmanager
from contextvars import ContextVar
from itertools import accumulate
from operator import attrgetter

import numpy as np
import deap.tools.crossover  # noqa: F401  (DEAP_MODULES: loaded before seeded_random looks them up)
import deap.tools.mutation  # noqa: F401
import deap.tools.selection  # noqa: F401
from deap import base, tools

from tailor.refinement.optimizers.objective import Objective, OptimizationResult
from tailor.progress import progress_bar

POPULATION_PER_PARAMETER = 25
ELITE_FRACTION = 0.02
CROSSOVER_PROB = 0.65
BLEND_ALPHA = 0.5  # cxBlend with a single gene
MUTATION_SIGMA = 0.1  # standard deviation of the Gaussian mutation, as a fraction of the parameter's range
STALL_GENERATIONS = 50
MAX_GENERATIONS = 500


class Fitness(base.Fitness):
    weights = (1.0,)  # maximized: t_max + t_min - t

    def __init__(self, values=()):  # DEAP's, without re-checking the weights for each of thousands of fitnesses
        if values:
            self.values = values


class Individual(list):
    """A chromosome: one float gene per free parameter, with its DEAP fitness."""

    __slots__ = ("fitness",)

    def __init__(self, genes):
        super().__init__(genes)
        self.fitness = Fitness()


def fitness(cost: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """t_max + t_min - t over the valid individuals (non-negative for durations); 0 for invalid ones."""
    if not valid.any():
        return np.zeros(len(cost))
    t = cost[valid]
    t_max, t_min = t.max(), t.min()
    return np.where(valid, t_max - cost + max(t_min, 0.0), 0.0)


DEAP_MODULES = ("deap.tools.crossover", "deap.tools.mutation", "deap.tools.selection")  # they `import random`
_RUN: ContextVar[random.Random | None] = ContextVar("tailor_genetic_random", default=None)


def rng():
    """The generator of the GA run in progress in this thread or task; the `random` module outside a run."""
    return _RUN.get() or random


class _RunRandom:
    """Stands in for the `random` module inside DEAP's operator modules: its functions are the run's (rng()).
    The ones DEAP's operators call are methods (a generation calls them thousands of times), the rest looked up."""

    def random(self) -> float:
        return (_RUN.get() or random).random()

    def randint(self, a: int, b: int) -> int:
        return (_RUN.get() or random).randint(a, b)

    def gauss(self, mu: float = 0.0, sigma: float = 1.0) -> float:
        return (_RUN.get() or random).gauss(mu, sigma)

    def __getattr__(self, name: str):
        return getattr(rng(), name)


for _name in DEAP_MODULES:
    sys.modules[_name].random = _RunRandom()


@contextmanager
def seeded_random(seed: int):
    """Within this block, in this thread or task, DEAP's operators and this module draw from a private generator
    seeded with `seed` (the stream of `random.seed(seed)`, draw for draw); no other thread's draws, and not the
    global generator, are touched."""
    token = _RUN.set(random.Random(seed))
    try:
        yield
    finally:
        _RUN.reset(token)


def sel_roulette(individuals: list, k: int) -> list:
    """DEAP's `tools.selRoulette`, draw for draw (the same `random.random()` calls pick the same individuals),
    with a binary search over the cumulative fitness instead of DEAP's linear scan per spin."""
    ranked = sorted(individuals, key=_weighted, reverse=True)  # (DEAP compares fitnesses by these tuples)
    cumulative = list(accumulate(ind.fitness.wvalues[0] for ind in ranked))  # (weight 1: the values themselves)
    total = sum(ind.fitness.wvalues[0] for ind in individuals)
    chosen = []
    for _ in range(k):
        i = bisect_right(cumulative, rng().random() * total)
        if i < len(ranked):  # DEAP appends nothing when rounding puts the spin past the last slot
            chosen.append(ranked[i])
    return chosen


_weighted = attrgetter("fitness.wvalues")


def mut_gaussian(individual: list, mu: float, sigma: list[float], indpb: float) -> tuple[list]:
    """DEAP's `tools.mutGaussian` with one mean and a standard deviation per gene, draw for draw (the same
    `random()` and `gauss()` calls change the same genes alike), the run's generator looked up once a call."""
    draw = rng()
    uniform, gauss = draw.random, draw.gauss
    for i, s in enumerate(sigma[:len(individual)]):
        if uniform() < indpb:
            individual[i] += gauss(mu, s)
    return (individual,)


def toolbox(low: np.ndarray, high: np.ndarray) -> base.Toolbox:
    """DEAP's operators configured for this problem's ranges."""
    n_free = len(low)
    box = base.Toolbox()
    box.register("individual", lambda: Individual(rng().uniform(lo, hi) for lo, hi in zip(low, high)))
    box.register("clone", Individual)
    box.register("select", sel_roulette)
    if n_free > 1:
        box.register("mate", tools.cxTwoPoint)
    else:
        box.register("mate", tools.cxBlend, alpha=BLEND_ALPHA)
    box.register("mutate", mut_gaussian, mu=0.0, sigma=[float(s) for s in MUTATION_SIGMA * (high - low)],
                 indpb=1.0 / n_free)
    return box


def _next_generation(box: base.Toolbox, population: list, order: np.ndarray, n_elite: int,
                     low: np.ndarray, high: np.ndarray) -> list:
    elite = [box.clone(population[i]) for i in order[:n_elite]]
    offspring = [box.clone(ind) for ind in box.select(population, len(population) - n_elite)]
    for a, b in zip(offspring[0::2], offspring[1::2]):
        if rng().random() < CROSSOVER_PROB:
            box.mate(a, b)
    bounds = list(zip(low.tolist(), high.tolist()))
    for ind in offspring:
        box.mutate(ind)
        ind[:] = [lo if g < lo else hi if g > hi else g for g, (lo, hi) in zip(ind, bounds)]
    return elite + offspring


def _judge(objective: Objective, genes: np.ndarray, judged: dict[bytes, tuple[float, bool]]
           ) -> tuple[np.ndarray, np.ndarray, dict[bytes, tuple[float, bool]]]:
    """Cost and validity of each individual, in one vectorized call for those the previous generation did not
    hold already (its elite, and the offspring neither mated nor mutated): the same values, fewer evaluations
    of a costly objective (a worst case over a neighbourhood plans dozens of paths per individual)."""
    keys = [row.tobytes() for row in genes]
    fresh = [i for i, key in enumerate(keys) if key not in judged]
    cost, valid = np.empty(len(genes)), np.empty(len(genes), dtype=bool)
    if fresh:
        cost[fresh] = objective.robust_cost(genes[fresh])
        valid[fresh] = objective.valid(genes[fresh])
    for i, key in enumerate(keys):
        if key in judged:
            cost[i], valid[i] = judged[key]
    return cost, valid, {key: (float(c), bool(v)) for key, c, v in zip(keys, cost, valid)}


def minimize(objective: Objective, seed: int = 0) -> OptimizationResult:
    """Run the GA; seeded by `seed` only, one vectorized objective call per generation."""
    start = time.perf_counter()
    low, high = objective.low, objective.high
    size = POPULATION_PER_PARAMETER * max(1, len(low))
    n_elite = max(1, round(ELITE_FRACTION * size))
    box = toolbox(low, high)
    best_cost, best_genes, best_valid = np.inf, None, False
    stall = generation = evaluations = 0
    with seeded_random(seed), progress_bar(total=MAX_GENERATIONS, desc="genetic algorithm", unit="gen",
                                           leave=False) as bar:
        population = [box.individual() for _ in range(size)]
        judged: dict[bytes, tuple[float, bool]] = {}
        while generation < MAX_GENERATIONS and stall < STALL_GENERATIONS:
            genes = np.array(population, dtype=float)
            cost, valid, judged = _judge(objective, genes, judged)
            evaluations += size
            generation += 1
            for ind, f in zip(population, fitness(cost, valid)):
                ind.fitness.values = (float(f),)
            order = np.lexsort((cost, ~valid))  # valid first, then by cost
            top = order[0]
            if (valid[top], -cost[top]) > (best_valid, -best_cost):
                stall = 0
                best_cost, best_genes, best_valid = float(cost[top]), genes[top].copy(), bool(valid[top])
            else:
                stall += 1
            bar.set_postfix_str(f"best {best_cost:.2f}, stalled {stall}/{STALL_GENERATIONS}", refresh=False)
            bar.update(1)
            population = _next_generation(box, population, order, n_elite, low, high)
    return OptimizationResult(
        values=tuple(float(v) for v in best_genes),
        cost=best_cost,
        method="ga",
        evaluations=evaluations,
        seconds=time.perf_counter() - start,
        note=f"{generation} generations" + ("" if best_valid else "; no valid parameterization found")
        + ("; invalid parameterizations get fitness 0" if any(t.valid is not None for t in objective.terms) else "")
        + ("; worst case over the neighbourhood" if any(objective.neighbourhood) else ""),
    )
