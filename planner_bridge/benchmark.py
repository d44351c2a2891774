"""Compare planners on PDDL problems: time, plan length, ordering constraints and width of the partial order.

    python -m tailor.planner_bridge.benchmark                      # bundled domains and the test fixtures
    python -m tailor.planner_bridge.benchmark --planners pocl pyperplan DOMAIN.pddl:PROBLEM.pddl ...

Each plan is made in this process by plan_here (parse, compile, search, validate, causal links); for a
planner that finds no causal links (pyperplan) the sequence is deordered. `orderings` counts the transitively
reduced ordering constraints, `pairs` the ordered pairs of steps (its closure), `width` the most steps no
ordering relates (the longest antichain): more width and fewer pairs is less commitment.
Time is the best of `--repeat` runs, after one warm-up run per planner (imports are not planning time).
"""

from __future__ import annotations

import argparse
import signal
import sys
import time
from pathlib import Path

from tailor.planner_bridge.abstract_plan import AbstractPlan
from tailor.errors import PlannerError, PlannerTimeoutError

ROOT = Path(__file__).resolve().parent.parent
FIXTURES = ROOT / "tests" / "fixtures" / "pddl"
CLASSIC = ("gripper", "blocks", "logistics", "briefcase")
LIMIT_S = 30


def default_problems() -> list[tuple[Path, Path]]:
    """Every bundled problem, then the problems of the classic test domains (when the tests are at hand)."""
    pairs = [(p.parent.parent / "domain.pddl", p) for p in sorted(ROOT.glob("domains/*/problems/*.pddl"))]
    for name in CLASSIC:
        pairs += [(FIXTURES / name / "domain.pddl", p) for p in sorted((FIXTURES / name).glob("p*.pddl"))]
    return pairs


def closure(plan: AbstractPlan) -> set[tuple[int, int]]:
    after: dict[int, set[int]] = {s.id: set() for s in plan.steps}
    for first, second in plan.orderings:
        after[first].add(second)
    pairs = set()
    for start, successors in after.items():
        todo = list(successors)
        while todo:
            step = todo.pop()
            if (start, step) not in pairs:
                pairs.add((start, step))
                todo.extend(after[step])
    return pairs


def width(plan: AbstractPlan) -> int:
    """The longest antichain: by Dilworth's theorem, the steps minus a maximum matching of ordered pairs."""
    later: dict[int, list[int]] = {s.id: [] for s in plan.steps}
    for first, second in sorted(closure(plan)):
        later[first].append(second)
    matched: dict[int, int] = {}

    def augment(step: int, seen: set[int]) -> bool:
        for other in later[step]:
            if other not in seen:
                seen.add(other)
                if other not in matched or augment(matched[other], seen):
                    matched[other] = step
                    return True
        return False

    return len(plan.steps) - sum(augment(s.id, set()) for s in plan.steps)


def _alarm(signum, frame):
    raise PlannerTimeoutError(f"no plan within {LIMIT_S} s")


def measure(domain: Path, problem: Path, planner: str, repeat: int = 1) -> dict:
    """One planner on one problem: best seconds of `repeat` runs, steps, orderings, ordered pairs and width."""
    runs = [_run(domain, problem, planner) for _ in range(repeat)]
    return min(runs, key=lambda row: row["seconds"]) | {"seconds": min(row["seconds"] for row in runs)}


def _run(domain: Path, problem: Path, planner: str) -> dict:
    from tailor.planner_bridge.bridge import plan_here

    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(LIMIT_S)
    start = time.perf_counter()
    try:
        plan = plan_here(domain, problem, planner)
    except PlannerError as exc:
        return {"seconds": time.perf_counter() - start, "error": exc.message}
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    return {"seconds": time.perf_counter() - start, "steps": len(plan.steps), "orderings": len(plan.orderings),
            "pairs": len(closure(plan)), "width": width(plan)}


def table(pairs: list[tuple[Path, Path]], planners: list[str], repeat: int = 1) -> str:
    """One line per problem and planner."""
    for planner in planners:  # warm-up: imports and engine registration are not the planner's time
        measure(*pairs[0], planner)
    lines = [f"{'problem':<24} {'planner':<10} {'time s':>7} {'steps':>5} {'orderings':>9} {'pairs':>5} {'width':>5}"]
    for domain, problem in pairs:
        name = f"{domain.parent.name}/{problem.stem}"
        for planner in planners:
            row = measure(domain, problem, planner, repeat)
            if "error" in row:
                lines.append(f"{name:<24} {planner:<10} {row['seconds']:>7.2f}  {row['error']}")
            else:
                lines.append(f"{name:<24} {planner:<10} {row['seconds']:>7.2f} {row['steps']:>5} {row['orderings']:>9} "
                             f"{row['pairs']:>5} {row['width']:>5}")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--planners", nargs="+", default=["pocl", "pyperplan"], metavar="NAME")
    parser.add_argument("--repeat", type=int, default=3, metavar="N", help="runs per problem and planner")
    parser.add_argument("problems", nargs="*", metavar="DOMAIN:PROBLEM", help="pairs of PDDL files (default: all)")
    args = parser.parse_args(argv)
    pairs = [tuple(Path(p) for p in arg.split(":", 1)) for arg in args.problems] or default_problems()
    sys.stdout.write(table(pairs, args.planners, args.repeat))
    return 0


if __name__ == "__main__":
    sys.exit(main())
