"""The kitchen simulator (pymunk, top view): a B21-like robot fetching cups between tables (Sec. 5.5).

`SIMULATOR` is what the package registers (entry point `tailor.simulators: kitchen`): navigate, grip and put
(Table 2.1), the simulator factory, the experience scenarios, the random situations of scenarios 1 and 2, and
the kitchen's feature spaces.
"""

from tailor.sims.kitchen.drawing import draw_scene
from tailor.sims.kitchen.features import GRASP, ROUTE, SPOT
from tailor.sims.kitchen.scenarios import SITUATIONS, run_goto, run_grip, run_put, subgoal_episode
from tailor.sims.kitchen.simulator import KitchenSim, Noise, simulate_sequence
from tailor.sims.protocol import ActionSpec, Scenario, SimulatorEntry


def _create(seed: int, noise: Noise | None = None) -> KitchenSim:
    return KitchenSim(seed, Noise() if noise is None else noise)


SIMULATOR = SimulatorEntry(
    name="kitchen",
    actions={
        "navigate": ActionSpec("navigate", "kitchen", observed=SPOT, internal=tuple(f"{q}g" for q in SPOT),
                               observed_quantities=SPOT, internal_quantities=SPOT),
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
    scene_objects=("robot", "table {object}", "cup {object}"),
    draw_scene=draw_scene,
    description="B21-like base with a pan/extend arm among tables (pymunk), routes through a visibility graph",
)

__all__ = ["SIMULATOR", "KitchenSim", "Noise", "simulate_sequence"]
