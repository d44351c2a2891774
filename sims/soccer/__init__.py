"""The soccer simulator (pymunk): field, Pioneer-like robot with a ball guide, ball, and its actions; a team
of them for the coordination experiments (sims.soccer.team).

`SIMULATOR` is what the package registers (entry point `tailor.simulators: soccer`): the three actions with
their pose parameters (Table 2.1), the simulator factory, the experience scenarios and the random situations,
the feature spaces of a navigation to a pose (sims.soccer.pose) and the actions' own (sims.soccer.features,
sims.soccer.walls), its quantities' and measures' units, the pictures of its learned models (Figs. 4.7,
4.8), and what a closed loop may meet (Ch. 8.1): the disturbance "nudge" and the robot variant "weak_motors".

Declaring the robot loads no physics: the simulator module (sims.soccer.simulator, which imports pymunk) is
imported when a simulator is first created or an episode first runs, so that `tailor domains` and
`tailor plan` stay light; `SoccerSim`, `Noise` and `simulate_sequence` still import from here.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from tailor.sims.registry import deferred_names
from tailor.sims.protocol import ActionSpec, DurationCurve, Quantity, Scenario, SimulatorEntry, SuccessRegion
from tailor.sims.soccer.actions import ACTION_FUNCTIONS, approachBall, dribbleBall, goToPose
from tailor.sims.soccer.features import APPROACH, DRIBBLE, GOTO_SPACE
from tailor.sims.soccer.pose import POSE_DELTA_SPACE, POSE_SPACE, POSITION_SPACE
from tailor.sims.soccer.scenarios import RANGES, SITUATIONS, subgoal_episode
from tailor.sims.soccer.team import TEAM
from tailor.sims.soccer.walls import POSE_WALLS
from tailor.sims.soccer.world import NUDGE, NUDGE_ROLL, NUDGE_WINDOW, WEAK_MOTOR_FACTOR, WEAK_TOP_SPEED, variant_dynamics

if TYPE_CHECKING:
    from tailor.sims.soccer.simulator import Noise, SoccerSim

_POSE = dict(observed=("x", "y", "phi", "v"), internal=("xg", "yg", "phig", "vg"),
             observed_quantities=("x", "y", "phi", "v"), internal_quantities=("x", "y", "phi", "v"))


METRES, RADIANS = Quantity("m"), Quantity("rad", angle=True)
UNITS = {"x": METRES, "y": METRES, "phi": RADIANS, "v": Quantity("m/s"), "ball_x": METRES, "ball_y": METRES,
         # the measures of its actions besides the duration (sims.soccer.simulator: what each one is)
         "energy": Quantity("J"), "error": METRES, "heading_error": RADIANS}

# Fig. 4.7's situation: goal 1.5 m straight ahead of a robot standing at the origin facing +x, arriving at rest;
# the bearing to the goal is 0, so the goal heading phig is the angle of approach angle_at
SITUATION_DIST = 1.5  # m
SITUATION_V = 0.0  # m/s
SITUATION_VG = 0.0  # m/s
APPROACH_ANGLE = DurationCurve(
    varied="phig", label="angle_at", meaning="the angle of approach",
    situation={"x": 0.0, "y": 0.0, "phi": 0.0, "v": SITUATION_V,
               "xg": SITUATION_DIST, "yg": 0.0, "vg": SITUATION_VG},
    description=f"dist {SITUATION_DIST} m, angle_to 0, v {SITUATION_V} m/s, vg {SITUATION_VG} m/s")
# Fig. 4.8: standing starts on a square round the goal pose (at the origin, heading +x), facing the goal and
# turned 135 degrees from it (not 180: there the sign of angle_at flips with the last bit of the heading, which
# would speckle the picture), arriving at mid-range of the collision experience's speeds (0 to 0.3 m/s)
REGION_HALF_SIZE = 3.0  # m
REGION_VG = 0.15  # m/s
SUCCESS_REGION = SuccessRegion(
    x="x", y="y", heading="phi", half_size=REGION_HALF_SIZE,
    turns=((0.0, "robot standing, facing the goal"),
           (0.75 * math.pi, "robot standing, turned 135 deg from the goal")),
    situation={"v": 0.0, "xg": 0.0, "yg": 0.0, "phig": 0.0, "vg": REGION_VG},
    description=f"{{action}} to the goal pose, arriving at {REGION_VG} m/s, from a standing start at each point",
    goal="goal pose (heading +x)", goal_heading="phig")


# Ch. 8.1: what can differ from the world the models were learned in (world.DISTURBANCES, world.VARIANTS)
DISTURBANCES = {
    NUDGE: f"an opponent pushes the ball once, at a random time {NUDGE_WINDOW[0]:g}-{NUDGE_WINDOW[1]:g} s "
           f"after the start, in a random direction (away from a robot that has it), so that it rolls "
           f"{NUDGE_ROLL[0]:g}-{NUDGE_ROLL[1]:g} m",
}
VARIANTS = {
    "weak_motors": f"the robot's motors are {1.0 - WEAK_MOTOR_FACTOR:.0%} weaker: its accelerations (a_max, "
                   f"alpha_max) are {WEAK_MOTOR_FACTOR:g} times the modelled robot's, its top speeds (v_max, "
                   f"w_max) {WEAK_TOP_SPEED:g} times",
}


def _create(seed: int, noise: Noise | None = None, disturbance: str | None = None,
            variant: str | None = None) -> SoccerSim:
    """A soccer simulator: default noise where `noise` is None, the disturbance and robot variant named."""
    # deferred: the simulator module loads pymunk, which declaring the robot must not
    from tailor.sims.soccer.simulator import Noise, SoccerSim

    return SoccerSim(seed, Noise() if noise is None else noise, variant_dynamics(variant), disturbance)


SIMULATOR = SimulatorEntry(
    name="soccer",
    actions={name: ActionSpec(name, "soccer", **_POSE) for name in ACTION_FUNCTIONS},
    create=_create,
    scenarios={name: Scenario(name, r.action, r.run, r.__doc__ or "") for name, r in RANGES.items()},
    situations=SITUATIONS,
    scene_objects=("robot", "ball"),
    views=((("x", "y", "phi"), ("ball_x", "ball_y")),),  # the field from above: robot with heading, and ball
    subgoal_episode=subgoal_episode,
    team=TEAM,
    # Table 4.1's pose rows; approachBall's, goToPose's and dribbleBall's: the pose features and the path each
    # controller plans; the success classifier's: the walls
    feature_spaces=(POSE_SPACE, POSE_DELTA_SPACE, POSITION_SPACE, APPROACH, DRIBBLE, GOTO_SPACE, POSE_WALLS),
    units=UNITS,
    model_pictures=(APPROACH_ANGLE, SUCCESS_REGION),
    description="RoboCup mid-size field, Pioneer-like robot with a ball guide, a ball (pymunk)",
    disturbances=DISTURBANCES,
    variants=VARIANTS,
)

# names of the simulator module, imported on first use (see above)
__getattr__ = deferred_names(__name__, "simulator", ("Noise", "SoccerSim", "simulate_sequence"))


__all__ = ["ACTION_FUNCTIONS", "Noise", "SIMULATOR", "SoccerSim", "approachBall", "dribbleBall", "goToPose",
           "simulate_sequence"]
