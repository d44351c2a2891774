"""The house drawn from its imports (docs/architecture.md): no circles, no arrow running back up a floor, the
command line above the three wings, and `tailor plan` free of the learners, optimizers and simulators.

Every `import` counts, also one inside a function: an import deferred to dodge a circle is still a circle.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NOT_PACKAGE = {"tests", "domains", "docs", ".git", ".venv", ".ci", "build"}

# The floors, lowest first: a module may import its own floor's modules and those of floors below, never above.
# Modules on one floor in different rooms (planner_bridge and sims; a robot and the models) do not import each other.
FLOORS = (
    ("foundation", ("tailor.errors", "tailor.progress", "tailor.outputs", "tailor.engine_registration")),
    ("planner_bridge", ("tailor.planner_bridge",)),
    ("sims", ("tailor.sims",)),
    ("robots", ()),  # tailor.sims.<robot>: one package per simulator that registers in sims.registry
    ("models", ("tailor.refinement.models",)),
    ("optimizers", ("tailor.refinement.optimizers",)),
    ("core", ("tailor.refinement",)),
    ("learning", ("tailor.refinement.learning",)),
    ("execution", ("tailor.refinement.execution",)),
    ("evaluation", ("tailor.refinement.evaluation",)),
    ("cli", ("tailor.cli",)),
)
RANK = {name: rank for rank, (name, _) in enumerate(FLOORS)}
ROOMS_APART = {("planner_bridge", "sims"), ("sims", "planner_bridge"), ("robots", "planner_bridge"),
               ("planner_bridge", "robots"), ("robots", "models"), ("models", "robots")}


def modules() -> dict[str, Path]:
    """Every module of the installed namespace `tailor` in this source tree, by its dotted name."""
    found = {}
    for path in ROOT.rglob("*.py"):
        rel = path.relative_to(ROOT)
        if rel.parts[0] in NOT_PACKAGE or rel.parts[0].startswith("."):
            continue
        parts = ("tailor", *rel.with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        found[".".join(parts)] = path
    return found


def imports(path: Path, known: dict[str, Path]) -> set[str]:
    """The project modules `path` imports, anywhere in it."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0 and node.module.startswith("tailor"):
            for alias in node.names:
                name = f"{node.module}.{alias.name}"
                out.add(name if name in known else node.module)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name.startswith("tailor"))
    return {m for m in out if m in known}


def graph() -> dict[str, set[str]]:
    known = modules()
    return {name: imports(path, known) - {name} for name, path in known.items()}


def floor(module: str) -> str | None:
    """The floor of a module (None: the namespace package `tailor` itself, which everything imports)."""
    if module == "tailor":
        return None
    parts = module.split(".")
    if parts[1] == "sims" and len(parts) > 2 and (ROOT / "sims" / parts[2]).is_dir():
        return "robots"  # a robot's package: tailor.sims.<robot>
    best = None
    for name, prefixes in FLOORS:
        for prefix in prefixes:
            if (module == prefix or module.startswith(prefix + ".")) and (best is None or len(prefix) > len(best[1])):
                best = (name, prefix)
    assert best is not None, f"{module} lies on no floor of docs/architecture.md"
    return best[0]


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm, iteratively)."""
    index, low, on, stack, out, counter = {}, {}, set(), [], [], [0]
    for start in edges:
        if start in index:
            continue
        work = [(start, iter(sorted(edges[start])))]
        index[start] = low[start] = counter[0]
        counter[0] += 1
        stack.append(start)
        on.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = counter[0]
                    counter[0] += 1
                    stack.append(child)
                    on.add(child)
                    work.append((child, iter(sorted(edges[child]))))
                elif child in on:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    out.append(sorted(component))
    return out


def upward(edges: dict[str, set[str]]) -> list[str]:
    """Every arrow from a module to one on a higher floor, or across rooms kept apart."""
    bad = []
    for source, targets in sorted(edges.items()):
        here = floor(source)
        for target in sorted(targets):
            there = floor(target)
            if here is None or there is None:
                continue
            if RANK[there] > RANK[here] or (here, there) in ROOMS_APART:
                bad.append(f"{source} ({here}) -> {target} ({there})")
            elif here == "robots" and there == "robots" and source.split(".")[2] != target.split(".")[2]:
                bad.append(f"{source} -> {target}: one robot imports another")
    return bad


def test_the_imports_draw_no_circle():
    assert cycles(graph()) == []


def test_no_arrow_runs_back_up_a_floor():
    assert upward(graph()) == []


def test_the_checks_would_see_a_circle_and_an_upward_arrow():
    edges = {"tailor.refinement.models.a": {"tailor.refinement.meta_filter"},
             "tailor.refinement.meta_filter": {"tailor.refinement.models.a"}, "tailor.sims.x": set()}
    assert cycles(edges) == [["tailor.refinement.meta_filter", "tailor.refinement.models.a"]]
    assert upward(edges) == ["tailor.refinement.models.a (models) -> tailor.refinement.meta_filter (core)"]
    assert upward({"tailor.sims.soccer.world": {"tailor.sims.arm.world"}, "tailor.sims.arm.world": set()}) == [
        "tailor.sims.soccer.world -> tailor.sims.arm.world: one robot imports another"]


def test_no_module_of_the_core_names_a_robot_package():
    robots = {m for m in modules() if floor(m) == "robots"}
    for source, targets in graph().items():
        if floor(source) in ("core", "models", "optimizers", "learning", "evaluation", "cli", "sims"):
            assert not (targets & robots), f"{source} imports {sorted(targets & robots)}"


HEAVY = ("deap", "sklearn", "scipy", "pymunk", "matplotlib")


@pytest.mark.parametrize("argv", [["plan", "soccer", "score"], ["domains"], ["--help"], ["plan", "--help"]])
def test_plan_and_domains_import_no_learner_optimizer_or_simulator(argv):
    """`tailor plan` and `tailor domains` (and the help) load neither DEAP, scikit-learn, SciPy, pymunk nor
    matplotlib: their time is the planner's."""
    script = ("import sys\nfrom tailor.cli.main import main\n"
              "try:\n    main(sys.argv[1:])\nexcept SystemExit:\n    pass\n"
              f"print(sorted({{m.split('.')[0] for m in sys.modules}} & set({HEAVY!r})))")
    done = subprocess.run([sys.executable, "-c", script, *argv], capture_output=True, text=True, timeout=120)
    assert done.stdout.strip().splitlines()[-1] == "[]", done.stderr[-2000:]
