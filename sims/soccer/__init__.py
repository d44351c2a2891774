"""The soccer simulator (pymunk): field, Pioneer-like robot with a ball guide, ball, and its actions; a team
of them for the coordination experiments (sims.soccer.team).

`SIMULATOR` is what the package registers (entry point `tailor.simulators: soccer`): the three actions with
their pose parameters (Table 2.1), the simulator factory, the experience scenarios and the random situations,
and approachBall's own feature space (sims.soccer.features).
"""

from tailor.sims.protocol import ActionSpec, Scenario, SimulatorEntry
from tailor.sims.soccer.actions import ACTION_FUNCTIONS, approachBall, dribbleBall, goToPose
from tailor.sims.soccer.features import APPROACH, DRIBBLE, GOTO_SPACE
from tailor.sims.soccer.scenarios import RANGES, SITUATIONS, subgoal_episode
from tailor.sims.soccer.simulator import Noise, SoccerSim, simulate_sequence
from tailor.sims.soccer.team import TEAM
from tailor.sims.soccer.walls import POSE_WALLS

_POSE = dict(observed=("x", "y", "phi", "v"), internal=("xg", "yg", "phig", "vg"),
             observed_quantities=("x", "y", "phi", "v"), internal_quantities=("x", "y", "phi", "v"))


def _create(seed: int, noise: Noise | None = None) -> SoccerSim:
    return SoccerSim(seed, Noise() if noise is None else noise)


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
    # approachBall's, goToPose's and dribbleBall's: the pose features and the path each controller plans; the success
    # classifier's: the walls
    feature_spaces=(APPROACH, DRIBBLE, GOTO_SPACE, POSE_WALLS),
    description="RoboCup mid-size field, Pioneer-like robot with a ball guide, a ball (pymunk)",
)

__all__ = ["ACTION_FUNCTIONS", "Noise", "SIMULATOR", "SoccerSim", "approachBall", "dribbleBall", "goToPose",
           "simulate_sequence"]
