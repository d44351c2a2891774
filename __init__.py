"""tailor: tailor robot action sequences to their task context with learned action models.

The repository's top-level folders are installed as one namespace: `tailor.planner_bridge` (PDDL in, a
partial-order plan with causal links out), `tailor.refinement` (instantiate, refine, dispatch; models,
learning, evaluation, the CLI), `tailor.sims` (the simulator protocol, its registry and the robots) and the
bundled `domains` as package data. Every error derives from `tailor.TailorError`.

The Python API (refinement.api), one call per stage:

    import tailor
    plan = tailor.plan(domain, problem)                # names of a bundled pair, files, or tailor.plan(up_problem)
    refined = tailor.refine(domain, problem)           # belief: the problem's file, a dict or a path
    refined.chosen                                     # the free parameters' values: {"pos2.phi": 2.356, ...}
    result = tailor.dispatch(refined)                  # simulated durations and outcomes
    for event in tailor.execute(domain, problem):      # closed loop: monitor, re-refine, replan, learn
        ...
    tailor.to_partial_order_plan(plan, up_problem)     # a unified-planning PartialOrderPlan
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

from tailor.errors import ArgumentTypeError, ArgumentValueError, TailorError
from tailor.engine_registration import install as install_engine

try:
    __version__ = version("tailor")
except PackageNotFoundError:  # run from a source tree that is not installed
    __version__ = "0+unknown"

install_engine()  # `OneshotPlanner(name="tailor-pocl")` works once tailor is imported (see engine_registration)

# name -> module: imported on first use, so `import tailor` (and the CLI) stays light
_API = {
    "plan": "tailor.refinement.api",
    "refine": "tailor.refinement.api",
    "dispatch": "tailor.refinement.api",
    "Refinement": "tailor.refinement.api",
    "execute": "tailor.refinement.execution",
    "Executor": "tailor.refinement.execution",
    "Executed": "tailor.refinement.execution",
    "AbstractPlan": "tailor.planner_bridge.abstract_plan",
    "link_plan": "tailor.planner_bridge.up_interop",
    "to_partial_order_plan": "tailor.planner_bridge.up_interop",
}


def __getattr__(name: str):
    if name in _API:
        import importlib

        value = getattr(importlib.import_module(_API[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'tailor' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_API))


__all__ = ["TailorError", "ArgumentTypeError", "ArgumentValueError", "__version__", *_API]
