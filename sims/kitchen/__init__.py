"""The kitchen simulator (pymunk, top view): a B21-like robot fetching cups between tables (Sec. 5.5).

`SIMULATOR` is what the package registers (entry point `tailor.simulators: kitchen`): navigate, grip and put
(Table 2.1), the simulator factory, the experience scenarios, the random situations of scenarios 1 and 2, the
kitchen's feature spaces, its quantities' and measures' units, and for the closed loop (Ch. 8.1) its
disturbance "cup" and its variant "slow_floor" (sims.kitchen.disturbances).

Declaring the robot loads no physics: the simulator module (sims.kitchen.simulator, which imports pymunk) is
imported when a simulator is first created or an episode first runs, so that `tailor domains` and
`tailor plan` stay light; `KitchenSim`, `Noise` and `simulate_sequence` still import from here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from tailor.sims.kitchen.disturbances import DISTURBANCES, VARIANTS
from tailor.sims.kitchen.drawing import draw_scene
from tailor.sims.kitchen.features import GOAL, GRASP, PASSING, ROUTE, SPOT
from tailor.sims.kitchen.scenarios import SITUATIONS, run_goto, run_grip, run_put, subgoal_episode
from tailor.sims.registry import deferred_names
from tailor.sims.protocol import ActionSpec, Quantity, Scenario, SimulatorEntry

if TYPE_CHECKING:
    from tailor.sims.kitchen.simulator import KitchenSim, Noise

_METRES, _ANGLE = Quantity("m"), Quantity("rad", angle=True)
# a spot's frame and offsets, a cup's and a put location's position, and the logged and drawn state
_LENGTHS = ("ox", "oy", "along", "dist", "x", "y", "tx", "ty", "ext", "gripper_x", "gripper_y")
UNITS = {**{q: _METRES for q in _LENGTHS}, **{q: _ANGLE for q in ("ophi", "heading", "phi", "pan")},
         "v": Quantity("m/s"), "cruise": Quantity("m/s"),
         # the measures of its actions besides the duration (sims.kitchen.simulator: what each one is)
         "energy": Quantity("J"), "error": _METRES, "heading_error": _ANGLE}


def _create(seed: int, noise: Noise | None = None, disturbance: str | None = None,
            variant: str | None = None) -> KitchenSim:
    # deferred: the simulator module loads pymunk, which declaring the robot must not
    from tailor.sims.kitchen.simulator import KitchenSim, Noise

    return KitchenSim(seed, Noise() if noise is None else noise, disturbance, variant)


SIMULATOR = SimulatorEntry(
    name="kitchen",
    actions={
        "navigate": ActionSpec("navigate", "kitchen", observed=PASSING, internal=tuple(f"{q}g" for q in GOAL),
                               observed_quantities=PASSING, internal_quantities=GOAL),
        "grip": ActionSpec("grip", "kitchen", observed=SPOT, internal=("cx", "cy"),
                           observed_quantities=SPOT, internal_quantities=("x", "y")),
        "put": ActionSpec("put", "kitchen", observed=SPOT, internal=("tx", "ty"),
                          observed_quantities=SPOT, internal_quantities=("tx", "ty")),
    },
    create=_create,
    scenarios={"navigate": Scenario("navigate", "navigate", run_goto, run_goto.__doc__ or ""),
               "grip": Scenario("grip", "grip", run_grip, run_grip.__doc__ or ""),
               "put": Scenario("put", "put", run_put, run_put.__doc__ or "")},
    situations=SITUATIONS,
    subgoal_episode=subgoal_episode,
    views=(("x", "y", "phi"),),
    feature_spaces=(ROUTE, GRASP),
    units=UNITS,
    scene_objects=("robot", "table {object}", "cup {object}"),
    draw_scene=draw_scene,
    disturbances=DISTURBANCES,
    variants=VARIANTS,
    description="B21-like base with a pan/extend arm among tables (pymunk), routes through a visibility graph",
)

# names of the simulator module, imported on first use (see above)
__getattr__ = deferred_names(__name__, "simulator", ("KitchenSim", "Noise", "simulate_sequence"))


__all__ = ["SIMULATOR", "KitchenSim", "Noise", "simulate_sequence"]
