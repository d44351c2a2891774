"""Our POCL engine known to unified-planning by name once tailor is imported: `OneshotPlanner(name="tailor-pocl")`
works after `import tailor`, in either order of the two imports, without tailor importing unified-planning
(about a second) when the user does not.

unified-planning builds each environment's engine factory from its `DEFAULT_ENGINES` table (name -> module,
class) and offers `Factory.add_engine` for later additions. Where its factory module is not loaded yet, a finder
adds our row to that table right after the module runs; where it is, and an environment exists already, the
public `add_engine` registers it there too.
"""

from __future__ import annotations

import importlib.abc
import importlib.util
import sys

ENGINE_NAME = "tailor-pocl"
ENGINE = ("tailor.planner_bridge.pocl_engine", "POCLEngine")
FACTORY_MODULE = "unified_planning.engines.factory"


def _add_default(factory_module) -> None:
    factory_module.DEFAULT_ENGINES.setdefault(ENGINE_NAME, ENGINE)


class _FactoryFinder(importlib.abc.MetaPathFinder):
    """Finds unified-planning's factory module as the other finders do, and adds our row once it has run."""

    def find_spec(self, name, path=None, target=None):
        if name != FACTORY_MODULE:
            return None
        sys.meta_path.remove(self)  # once: the real spec comes from the finders after us
        spec = importlib.util.find_spec(name)
        if spec is None or spec.loader is None or not hasattr(spec.loader, "exec_module"):
            return spec
        run = spec.loader.exec_module

        def exec_module(module) -> None:
            run(module)
            _add_default(module)

        spec.loader.exec_module = exec_module
        return spec


def install() -> None:
    """Make `tailor-pocl` an engine of unified-planning (now, or when its factory module is first imported)."""
    factory_module = sys.modules.get(FACTORY_MODULE)
    if factory_module is None:
        if not any(isinstance(finder, _FactoryFinder) for finder in sys.meta_path):
            sys.meta_path.insert(0, _FactoryFinder())
        return
    _add_default(factory_module)
    environment = sys.modules.get("unified_planning.environment")
    if environment is not None and getattr(environment, "GLOBAL_ENVIRONMENT", None) is not None:
        factory = environment.GLOBAL_ENVIRONMENT.factory
        if ENGINE_NAME not in factory.engines:
            factory.add_engine(ENGINE_NAME, *ENGINE)
