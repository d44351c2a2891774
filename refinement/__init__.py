"""Refinement: bind a plan to executable actions, learn action models, choose free parameters, dispatch.

The Python API, read top to bottom (the same stages `tailor refine` runs):

    plan = planner_bridge.plan_files(domain, problem)          # AbstractPlan with causal links
    sequence = instantiate(plan, load_domain_binding(dir), belief)   # Algorithm 3: BOUND / FREE parameters
    refined = refine(sequence, load_action_models(dir / "models"), horizon=2)   # Sec. 5.4
    result = dispatch(refined.sequence, seed=0)                # simulated durations and outcomes

`instantiate`, `refine` and `dispatch` share their names with their modules, so they are imported here (an
import of the module would otherwise shadow a lazily looked-up function); the other names are imported
lazily, so that `tailor plan` does not pay for the learners.
"""

from __future__ import annotations

import importlib

from refinement.dispatch import dispatch as dispatch
from refinement.instantiate import instantiate as instantiate
from refinement.refine import refine as refine

_EXPORTS = {
    "load_domain_binding": "refinement.binding",
    "load_binding": "refinement.binding",
    "BeliefState": "refinement.belief",
    "load_belief": "refinement.belief",
    "parse_belief": "refinement.belief",
    "belief_path_for": "refinement.belief",
    "ActionSequence": "refinement.action_sequence",
    "ExecutableAction": "refinement.action_sequence",
    "Parameter": "refinement.action_sequence",
    "ActionModel": "refinement.action_models",
    "load_action_models": "refinement.action_models",
    "load_collision_model": "refinement.action_models",
    "ModelTree": "refinement.model_tree",
    "RefinedSequence": "refinement.refine",
    "OPTIMIZERS": "refinement.optimizers",
    "optimize": "refinement.optimizers",
    "TailorError": "refinement.errors",
}

__all__ = sorted([*_EXPORTS, "dispatch", "instantiate", "refine"])


def __getattr__(name: str):
    if name not in _EXPORTS:
        raise AttributeError(f"module 'refinement' has no attribute {name!r}")
    value = getattr(importlib.import_module(_EXPORTS[name]), name)
    globals()[name] = value
    return value
