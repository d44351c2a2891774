"""Simulators and the executable actions of the action library (Table 2.1).

`tailor.sims` is robot-agnostic: the protocol a simulator follows (`protocol`), the registry that finds
simulators, built in or installed by entry point (`registry`), what they report (`episode`) and experience
gathering (`experience`). Each robot lives in a package of its own under `tailor.sims`, or in an installed package.
"""

from tailor.sims.episode import ActionCall, ActionResult, Episode, SequenceResult
from tailor.sims.protocol import ActionSpec, Scenario, Simulator, SimulatorEntry
from tailor.sims.registry import get, register, simulators

__all__ = ["ActionCall", "ActionResult", "ActionSpec", "Episode", "Scenario", "SequenceResult", "Simulator",
           "SimulatorEntry", "get", "register", "simulators"]
