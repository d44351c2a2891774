"""Compare two planners on PDDL problems, side by side: time, plan length, ordering constraints and width.

    python -m tailor.planner_bridge.benchmark                      # the bundled problems
    python -m tailor.planner_bridge.benchmark --planners pocl pyperplan DOMAIN.pddl:PROBLEM.pddl FOLDER ...

A FOLDER stands for the problems p<N>.pddl of the domain.pddl in it, or of each domain folder in it (one
without a domain.pddl of its own takes that of the folder of the same name given before it); the bundled
problems come first unless DOMAIN:PROBLEM pairs are given. The classic test domains and the problems with
parallel structure are `tests/fixtures/pddl/<name>` and `tests/benchmarks/pocl`
(tests/benchmarks/test_pocl_vs_pyperplan.py runs the table on them).

Each plan is made in this process by plan_here (parse, compile, search, validate, causal links); for a
planner that finds no causal links (pyperplan) the sequence is deordered (planner_bridge.causal). Both plans
are counted the same way, from the transitive closure of their orderings between steps (the initial state and
the goal left out): `ord` is the size of its transitive reduction (the fewest orderings that say the same),
`pairs` the size of the closure (the ordered pairs of steps), `width` the most steps no ordering relates (the
longest antichain): fewer orderings and pairs, more width, is less commitment. `first plan` is the POCL search's
first plan, what the engine returns with least commitment off (pocl_engine, least_commitment=False), from which
the search for alternatives and the post-pass start. The `+post-pass` columns put
the second planner's sequence through the POCL planner's least-commitment post-pass (planner_bridge.pocl_order),
to show how much of the difference is the search and how much the post-pass ("-": not typed STRIPS; "~": the
post-pass hit its node limit, so its result is not proven the least ordered for those steps).
Time is the best of `--repeat` runs, after one warm-up run per planner (imports are not planning time).
"""

from __future__ import annotations

import argparse
import signal
import sys
import time
from pathlib import Path

from tailor.errors import PlannerError, PlannerTimeoutError
from tailor.planner_bridge.abstract_plan import AbstractPlan, Step
from tailor.planner_bridge.bundled import DOMAIN_FILE, DOMAINS_DIR, PROBLEMS_DIR
from tailor.planner_bridge.causal import transitive_reduction
from tailor.planner_bridge.in_process import plan_here
from tailor.planner_bridge.pocl import Planner, linearization
from tailor.planner_bridge.pocl_ground import UnsupportedCondition, ground
from tailor.planner_bridge.pocl_order import least_commitment, sequence_plan
from tailor.planner_bridge.reading import read_problem
from tailor.planner_bridge.solving import canonical

PROBLEM_FILES = "p[0-9]*.pddl"  # a folder's problems
LIMIT_S = 30
# Branch-and-bound nodes for the post-pass of the second planner's sequences: more than the engine's own
# (pocl_order.NODE_LIMIT), so that the column proves what it shows (gripper/p01's 15 steps take about 98 000).
POST_PASS_NODES = 200_000


def default_problems(*folders: Path) -> list[tuple[Path, Path]]:
    """Every bundled problem, then the problems of the folders (see folders_problems)."""
    bundled = [(p.parent.parent / DOMAIN_FILE, p) for p in sorted(DOMAINS_DIR.glob(f"*/{PROBLEMS_DIR}/*.pddl"))]
    return bundled + folders_problems(*folders)


def folders_problems(*folders: Path) -> list[tuple[Path, Path]]:
    """The problems of each folder in turn (see folder_problems), each taking domains from the folders before it."""
    return [pair for k, folder in enumerate(folders) for pair in folder_problems(folder, folders[:k])]


def folder_problems(folder: Path, domains: tuple[Path, ...] = ()) -> list[tuple[Path, Path]]:
    """(domain, problem) for the problems p<N>.pddl of a domain folder, or of each domain folder in `folder`; a
    folder without a domain.pddl of its own takes that of the folder of the same name among `domains`."""
    folder = Path(folder)
    subfolders = [folder] if (folder / DOMAIN_FILE).is_file() else sorted(p for p in folder.iterdir() if p.is_dir())
    pairs = []
    for sub in subfolders:
        own = sub / DOMAIN_FILE
        borrowed = [Path(d) / DOMAIN_FILE for d in domains if Path(d).name == sub.name]
        domain = own if own.is_file() else next((d for d in borrowed if d.is_file()), own)
        pairs += [(domain, p) for p in sorted(sub.glob(PROBLEM_FILES))]
    return pairs


def closure(plan: AbstractPlan) -> set[tuple[int, int]]:
    """The ordered pairs of steps: the transitive closure of the plan's orderings."""
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


def orderings(plan: AbstractPlan) -> int:
    """How many orderings the transitive reduction of the plan's closure has (whatever the planner returned)."""
    return len(transitive_reduction(closure(plan)))


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
    """One planner on one problem: best seconds of `repeat` runs, steps, orderings, ordered pairs and width
    (and the AbstractPlan under "plan")."""
    runs = [_run(domain, problem, planner) for _ in range(repeat)]
    return min(runs, key=lambda row: row["seconds"]) | {"seconds": min(row["seconds"] for row in runs)}


def _run(domain: Path, problem: Path, planner: str) -> dict:
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
    return {"seconds": time.perf_counter() - start} | counts(plan) | {"plan": plan}


def counts(plan: AbstractPlan) -> dict:
    """Steps, orderings (transitively reduced), ordered pairs (the closure) and width of a plan."""
    return {"steps": len(plan.steps), "orderings": orderings(plan), "pairs": len(closure(plan)), "width": width(plan)}


def _task(domain: Path, problem: Path):
    """The POCL planner's ground task of the problem; None when it is not typed STRIPS."""
    try:
        return ground(read_problem(domain, problem)[0])
    except UnsupportedCondition:
        return None


def _as_abstract(task, partial) -> AbstractPlan:
    """A POCL PartialPlan as an AbstractPlan with steps and orderings only (enough to count them)."""
    order = linearization(partial)
    ids = {step: k for k, step in enumerate(order, start=1)}
    actions = [task.actions[partial.steps[step]] for step in order]
    steps = tuple(Step(k, action.name, action.args) for k, action in enumerate(actions, start=1))
    pairs = tuple(sorted((ids[a], ids[b]) for a in order for b in order if partial.precedes(a, b)))
    return AbstractPlan("", "", "", steps, (), pairs)


def first_plan(domain: Path, problem: Path) -> dict | None:
    """Counts of the POCL search's first plan, what the engine returns with least commitment off (the
    search for alternatives and the post-pass start from it); None when the problem is not typed STRIPS."""
    task = _task(domain, problem)
    if task is None:
        return None
    result = Planner(task).search(LIMIT_S)
    if result.plan is None:
        return {"error": f"no plan ({result.status})", "seconds": LIMIT_S}
    return counts(_as_abstract(task, result.plan))


def post_passed(domain: Path, problem: Path, plan: AbstractPlan) -> dict | None:
    """Counts of `plan`'s sequence after the POCL planner's least-commitment post-pass; None when the problem
    is not typed STRIPS (the POCL grounder refuses it) or a step is not one of its ground actions."""
    task = _task(domain, problem)
    if task is None:
        return None
    number = {(action.name, action.args): k for k, action in enumerate(task.actions)}
    if any((step.action, step.args) not in number for step in plan.steps):
        return None
    stats: dict = {}
    better = least_commitment(task, sequence_plan(task, [number[(s.action, s.args)] for s in plan.steps]),
                              POST_PASS_NODES, stats)
    return counts(_as_abstract(task, better)) | {"exact": stats["exact"]}


def compare(pairs: list[tuple[Path, Path]], planners: tuple[str, str] = ("pocl", "pyperplan"), repeat: int = 1,
            progress=None) -> list[dict]:
    """One row per problem: {"name", "first" and "second": the planners' counts, "search": the POCL search's
    first plan when the first planner is pocl (see first_plan), "post": see post_passed}."""
    for planner in planners:  # warm-up: imports and engine registration are not the planner's time
        measure(*pairs[0], planner)
    rows = []
    for domain, problem in pairs:
        first, second = (measure(domain, problem, planner, repeat) for planner in planners)
        search = first_plan(domain, problem) if canonical(planners[0]) == "tailor-pocl" else None
        post = post_passed(domain, problem, second["plan"]) if "plan" in second else None
        rows.append({"name": f"{domain.parent.name}/{problem.stem}", "first": first, "search": search,
                     "second": second, "post": post})
        if progress is not None:
            progress.update()
    return rows


def _cells(row: dict | None, timed: bool) -> str:
    if row is None:
        return f"{'-':>5} {'-':>4} {'-':>5} {'-':>5}" + (f" {'':>7}" if timed else "")
    if "error" in row:
        room = 27 if timed else 23
        return f"{row['error'][:room]:<{room}}" + (f" {row['seconds']:>7.2f}" if timed else "")
    mark = "" if row.get("exact", True) else "~"  # the post-pass hit its node limit: not proven least ordered
    text = f"{row['steps']:>5} {row['orderings']:>4} {row['pairs']:>5} {str(row['width']) + mark:>5}"
    return text + (f" {row['seconds']:>7.2f}" if timed else "")


def _verdict(first: dict, second: dict) -> str:
    if "error" in first or "error" in second:
        return "-"
    return {-1: "fewer", 0: "same", 1: "MORE"}[(first["orderings"] > second["orderings"])
                                                 - (first["orderings"] < second["orderings"])]


def _tally(group: list[dict], key: str, more_is_better: bool = False) -> str:
    """How many rows have the first planner better, equal and worse on `key`."""
    sign = -1 if more_is_better else 1
    better = sum(sign * r["first"][key] < sign * r["second"][key] for r in group)
    worse = sum(sign * r["first"][key] > sign * r["second"][key] for r in group)
    words = ("wider", "narrower") if more_is_better else ("fewer", "more")
    return f"{better} {words[0]}, {len(group) - better - worse} same, {worse} {words[1]}"


def summary(rows: list[dict], planners: tuple[str, str]) -> list[str]:
    """Counts of fewer / as many / more orderings (and pairs, width), over the problems with parallel
    structure (some plan of it has width 2 or more) and over all problems."""
    lines = []
    solved = [r for r in rows if "error" not in r["first"] and "error" not in r["second"]]
    parallel = [r for r in solved if max(r["first"]["width"], r["second"]["width"]) >= 2]
    for label, group in (("with parallel structure (width >= 2 in either plan)", parallel), ("all", solved)):
        lines.append(f"{planners[0]} vs {planners[1]}, {len(group)} problems {label}: orderings "
                     f"{_tally(group, 'orderings')}; pairs {_tally(group, 'pairs')}; width {_tally(group, 'width', True)}")
    failed = [r["name"] for r in rows if "error" in r["first"] or "error" in r["second"]]
    if failed:
        lines.append(f"not solved by both: {', '.join(failed)}")
    return lines


def render(rows: list[dict], planners: tuple[str, str] = ("pocl", "pyperplan")) -> str:
    """The side-by-side table and its summary."""
    first, second = planners
    head = f"{'steps':>5} {'ord':>4} {'pairs':>5} {'width':>5}"
    lines = [(f"{'':<20} | {first:<31} | {first + ' first plan':<23} | {second + ' (deordered)':<31} | "
              f"{second + ' +post-pass':<23} |"),
             f"{'problem':<20} | {head} {'time s':>7} | {head} | {head} {'time s':>7} | {head} | {first} orderings"]
    for row in rows:
        lines.append(f"{row['name']:<20} | {_cells(row['first'], True)} | {_cells(row.get('search'), False)} | "
                     f"{_cells(row['second'], True)} | {_cells(row['post'], False)} | "
                     f"{_verdict(row['first'], row['second'])}")
    return "\n".join([*lines, "", *summary(rows, planners)]) + "\n"


def table(pairs: list[tuple[Path, Path]], planners=("pocl", "pyperplan"), repeat: int = 1) -> str:
    """The side-by-side table of `compare` (with a progress bar on stderr)."""
    from tqdm import tqdm

    with tqdm(total=len(pairs), desc="problems", unit="problem", file=sys.stderr, leave=False) as bar:
        return render(compare(pairs, tuple(planners), repeat, bar), tuple(planners))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--planners", nargs=2, default=["pocl", "pyperplan"], metavar="NAME",
                        help="the two planners compared (default: pocl pyperplan)")
    parser.add_argument("--repeat", type=int, default=3, metavar="N", help="runs per problem and planner")
    parser.add_argument("problems", nargs="*", metavar="DOMAIN:PROBLEM|FOLDER",
                        help="pairs of PDDL files, or folders of problems (default: the bundled problems)")
    args = parser.parse_args(argv)
    if args.repeat < 1:
        parser.error("--repeat must be at least 1")
    folders = tuple(Path(arg) for arg in args.problems if Path(arg).is_dir())
    given = [tuple(Path(p) for p in arg.split(":", 1)) for arg in args.problems if not Path(arg).is_dir()]
    pairs = (folders_problems(*folders) if given else default_problems(*folders)) + given
    try:
        sys.stdout.write(table(pairs, tuple(args.planners), args.repeat))
    except KeyboardInterrupt:
        sys.stderr.write("benchmark: interrupted\n")
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
