"""Simulators and the executable actions of the action library (Table 2.1).

`tailor.sims` is robot-agnostic: the protocol a simulator follows and what it declares about its quantities and
pictures (`protocol`), the registry that finds simulators, built in or installed by entry point (`registry`), what
they report (`episode`) and experience gathering (`experience`). Each robot lives in a package of its own under
`tailor.sims`, or in an installed package.
"""

from tailor.sims.episode import ActionCall, ActionResult, Episode, SequenceResult
from tailor.sims.protocol import (ActionSpec, DurationCurve, Quantity, Scenario, Simulator, SimulatorEntry,
                                  SuccessRegion)
from tailor.sims.registry import get, register, simulators

__all__ = ["ActionCall", "ActionResult", "ActionSpec", "DurationCurve", "Episode", "Quantity", "Scenario",
           "SequenceResult", "Simulator", "SimulatorEntry", "SuccessRegion", "get", "register", "simulators"]
