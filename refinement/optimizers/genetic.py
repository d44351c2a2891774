"""The genetic algorithm of Sec. 5.4.3, with DEAP's operators over the whole population at once.

One float gene per free parameter; population 25 x the number of free parameters, initialized uniformly
within the ranges; each generation the best 2% (at least one) pass unchanged, the rest are chosen by roulette
(`tools.selRoulette`) on the fitness t_max + t_min - t (t over the current population; a parameterization a
model marks invalid gets fitness 0, the lowest), mated pairwise on 65% of the pairs with `tools.cxTwoPoint`
(`tools.cxBlend` with a single gene, which has no inner cut point) and mutated with `tools.mutGaussian`,
clipped to the ranges. The loop stops when the best cost has not improved for 50 generations, or after 500 (a
progress bar over the generations where the caller shows progress: tailor.progress). The best individual is
then polished by a compass search (`polish`: a few batched calls, under 1% of a window's time): the GA ends
near an optimum but rarely on it (on the bundled way-point chain the polish lowered two windows in three; on one
window of six free parameters, over 60 seeds, the GA stayed in a worse basin 4 times instead of 12).

The population is an array (individuals x genes) and the operators work on all of it at once
(genetic_operators: each does what its DEAP operator does to every individual, fed the same draws; DEAP's loops
over individuals took a seventh of a window's time on the bundled way-point chain, a third without a
neighbourhood). Every draw comes from a numpy generator seeded with the run's
seed and owned by the run: refinement is seeded by its argument only, runs in several threads at once reproduce
the serial results, and no global generator is touched. A generation is evaluated with one vectorized call of
the objective, for the individuals that differ from the one they were copied from (the elite and the offspring
neither mated nor mutated keep its cost: with a neighbourhood each individual costs dozens of feature rows).
"""

from __future__ import annotations

import time

import numpy as np
from tailor.progress import progress_bar
from tailor.refinement.optimizers import genetic_operators as ops
from tailor.refinement.optimizers.objective import Objective, OptimizationResult

POPULATION_PER_PARAMETER = 25
ELITE_FRACTION = 0.02
CROSSOVER_PROB = 0.65
BLEND_ALPHA = 0.5  # cxBlend with a single gene
MUTATION_SIGMA = 0.1  # standard deviation of the Gaussian mutation, as a fraction of the parameter's range
STALL_GENERATIONS = 50
MAX_GENERATIONS = 500
POLISH_STEPS = (0.02, 0.005, 0.001)  # the compass search's steps along each gene, as fractions of its range
POLISH_ROUNDS = 20  # at most this many moves of the polished individual


def fitness(cost: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """t_max + t_min - t over the valid individuals (non-negative for durations); 0 for invalid ones."""
    if not valid.any():
        return np.zeros(len(cost))
    t = cost[valid]
    t_max, t_min = t.max(), t.min()
    return np.where(valid, t_max - cost + max(t_min, 0.0), 0.0)


def next_generation(rng: np.random.Generator, genes: np.ndarray, fit: np.ndarray, order: np.ndarray,
                    n_elite: int, low: np.ndarray, high: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The next population (the elite first; `order` ranks the current one best first) and, per individual,
    the index of the one of the current population it was copied from before crossover and mutation."""
    parents = np.concatenate([order[:n_elite], ops.roulette(fit, ops.draw_spins(rng, len(genes) - n_elite))])
    offspring = genes[parents[n_elite:]]
    mate = np.flatnonzero(rng.random(len(offspring) // 2) < CROSSOVER_PROB)  # pairs (0, 1), (2, 3), ...
    a, b = offspring[2 * mate], offspring[2 * mate + 1]
    if genes.shape[1] > 1:
        a, b = ops.two_point(a, b, *ops.draw_cuts(rng, len(mate), genes.shape[1]))
    else:
        a, b = ops.blend(a, b, ops.draw_blend(rng, len(mate), 1), BLEND_ALPHA)
    offspring[2 * mate], offspring[2 * mate + 1] = a, b
    mutated = ops.gaussian(offspring, *ops.draw_mutation(rng, offspring.shape), MUTATION_SIGMA * (high - low),
                           1.0 / genes.shape[1])
    return np.concatenate([genes[parents[:n_elite]], np.clip(mutated, low, high)]), parents


def judge(objective: Objective, genes: np.ndarray, inherited: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
          ) -> tuple[np.ndarray, np.ndarray]:
    """Cost (the worst case over the neighbourhood) and validity of each row of `genes`, in one vectorized call
    for the rows that differ (bit for bit) from `inherited`'s genes, the others taking its cost and validity:
    `inherited` is (genes, cost, valid) of the individual each row was copied from."""
    if inherited is None:
        return objective.robust_cost(genes), objective.valid(genes)
    before, cost, valid = inherited[0], inherited[1].copy(), inherited[2].copy()
    fresh = (np.ascontiguousarray(genes).view(np.uint64) != np.ascontiguousarray(before).view(np.uint64)).any(axis=1)
    if fresh.any():
        rows = genes[fresh]
        cost[fresh], valid[fresh] = objective.robust_cost(rows), objective.valid(rows)
    return cost, valid


def polish(objective: Objective, genes: np.ndarray, cost: float, valid: bool
           ) -> tuple[np.ndarray, float, bool, int]:
    """A compass search from `genes`: each round judges the moves of every POLISH_STEPS size along each gene
    either way (clipped to the ranges) in one call and takes the best if it is better; it stops where none is,
    or after POLISH_ROUNDS. The genes, cost and validity it ends at, and how many candidates it judged."""
    low, high = objective.low, objective.high
    moves = np.concatenate([sign * np.diag(step * (high - low)) for step in POLISH_STEPS for sign in (1.0, -1.0)])
    judged = 0
    for _ in range(POLISH_ROUNDS):
        candidates = np.clip(genes + moves, low, high)
        candidate_cost, candidate_valid = judge(objective, candidates)
        judged += len(candidates)
        top = np.lexsort((candidate_cost, ~candidate_valid))[0]
        if not (candidate_valid[top], -candidate_cost[top]) > (valid, -cost):
            break
        genes, cost, valid = candidates[top], float(candidate_cost[top]), bool(candidate_valid[top])
    return genes, cost, valid, judged


def minimize(objective: Objective, seed: int = 0) -> OptimizationResult:
    """Run the GA, then polish its best individual; seeded by `seed` only, one vectorized objective call per
    generation."""
    start = time.perf_counter()
    low, high = objective.low, objective.high
    size = POPULATION_PER_PARAMETER * max(1, len(low))
    n_elite = max(1, round(ELITE_FRACTION * size))
    rng = np.random.default_rng(seed)
    best_cost, best_genes, best_valid = np.inf, None, False
    stall = generation = evaluations = 0
    genes = rng.uniform(low, high, size=(size, len(low)))
    cost, valid = judge(objective, genes)
    with progress_bar(total=MAX_GENERATIONS, desc="genetic algorithm", unit="gen", leave=False) as bar:
        while True:
            evaluations += size
            generation += 1
            order = np.lexsort((cost, ~valid))  # valid first, then by cost
            top = order[0]
            if (valid[top], -cost[top]) > (best_valid, -best_cost):
                stall = 0
                best_cost, best_genes, best_valid = float(cost[top]), genes[top].copy(), bool(valid[top])
            else:
                stall += 1
            bar.set_postfix_str(f"best {best_cost:.2f}, stalled {stall}/{STALL_GENERATIONS}", refresh=False)
            bar.update(1)
            if generation >= MAX_GENERATIONS or stall >= STALL_GENERATIONS:
                break
            offspring, parents = next_generation(rng, genes, fitness(cost, valid), order, n_elite, low, high)
            cost, valid = judge(objective, offspring, (genes[parents], cost[parents], valid[parents]))
            genes = offspring
    best_genes, best_cost, best_valid, polished = polish(objective, best_genes, best_cost, best_valid)
    return OptimizationResult(
        values=tuple(float(v) for v in best_genes),
        cost=best_cost,
        method="ga",
        evaluations=evaluations + polished,
        seconds=time.perf_counter() - start,
        note=f"{generation} generations" + ("" if best_valid else "; no valid parameterization found")
        + ("; invalid parameterizations get fitness 0" if any(t.valid is not None for t in objective.terms) else "")
        + ("; worst case over the neighbourhood" if any(objective.neighbourhood) else ""),
    )
