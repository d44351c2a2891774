"""tailor: tailor robot action sequences to their task context with learned action models.

The repository's top-level folders are installed as one namespace: `tailor.planner_bridge` (PDDL in, a
partial-order plan with causal links out), `tailor.refinement` (instantiate, refine, dispatch; models,
learning, evaluation, the CLI), `tailor.sims` (the simulator protocol, its registry and the robots) and the
bundled `domains` as package data. Every error derives from `tailor.TailorError`.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

from tailor.errors import TailorError

try:
    __version__ = version("tailor")
except PackageNotFoundError:  # run from a source tree that is not installed
    __version__ = "0+unknown"

__all__ = ["TailorError", "__version__"]
