"""Refinement: bind a plan to executable actions, learn action models, choose free parameters, dispatch.

The Python API, read top to bottom (the same stages `tailor refine` runs):

    plan = planner_bridge.plan_files(domain, problem)          # AbstractPlan with causal links
    sequence = instantiate(plan, load_domain_binding(dir), belief)   # Algorithm 3: BOUND / FREE parameters
    asserted = assert_subgoals(sequence, binding, success_models)     # Algorithm 5 (where a binding asks)
    refined = refine(asserted.sequence, load_action_models(dir / "models"), horizon=2,
                     success_models=success_models)           # Sec. 5.4, within predicted success (Alg. 6)
    result = dispatch(refined.sequence, seed=0)                # simulated durations and outcomes

The stages live in their modules (`tailor.refinement.instantiate.instantiate`, `...refine.refine`,
`...dispatch.dispatch`; `tailor.refinement.pipeline` chains them). The other names are looked up here lazily:
importing any module of this package loads nothing else, so `tailor plan` and `tailor domains` pay for neither
the optimizers nor the learners.
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    "load_domain_binding": "tailor.refinement.binding",
    "load_binding": "tailor.refinement.binding",
    "BeliefState": "tailor.refinement.belief",
    "load_belief": "tailor.refinement.belief",
    "parse_belief": "tailor.refinement.belief",
    "belief_path_for": "tailor.refinement.belief",
    "ActionSequence": "tailor.refinement.action_sequence",
    "ExecutableAction": "tailor.refinement.action_sequence",
    "Parameter": "tailor.refinement.action_sequence",
    "ActionModel": "tailor.refinement.models.action_models",
    "load_action_models": "tailor.refinement.models.action_models",
    "load_collision_model": "tailor.refinement.models.action_models",
    "load_success_models": "tailor.refinement.models.action_models",
    "assert_subgoals": "tailor.refinement.assertion",
    "AssertedSequence": "tailor.refinement.assertion",
    "Assertion": "tailor.refinement.assertion",
    "ModelTree": "tailor.refinement.models.model_tree",
    "RefinedSequence": "tailor.refinement.refine",
    "OPTIMIZERS": "tailor.refinement.optimizers",
    "optimize": "tailor.refinement.optimizers",
    "TailorError": "tailor.errors",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name not in _EXPORTS:
        raise AttributeError(f"module 'refinement' has no attribute {name!r}")
    value = getattr(importlib.import_module(_EXPORTS[name]), name)
    globals()[name] = value
    return value
