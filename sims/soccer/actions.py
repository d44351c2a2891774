"""The soccer actions (Sec. 2.2, App. A.1): pure functions from the belief state and the subgoal to [v, phidot].

Every action has the signature `(x, y, phi, v, xg, yg, phig, vg) -> (v_cmd, phidot_cmd)`: the robot's
dynamic pose (its ball point, heading, signed speed) as believed, and the goal pose. They keep no state, so
the simulator (or a real robot) may call them at any rate.

- goToPose (here): an intermediate pose behind the goal pose lures the robot in (App. A.1): the reactive
  Dubins-path follower of approachBall (sims.soccer.follow, same turning radius and speeds) drives the axle
  onto the pose PRE_DISTANCE behind the goal on the line of phig, and straight in, arriving with vg. Unlike
  approachBall it does not see the ball (the collision classifier of Sec. 4.2.2 learns when that bumps it).
  An earlier lure *point* that moved into the goal as the robot closed in missed the pose tolerance on a
  noisy fraction of runs and looped round again (+3-8 s), which made its duration unpredictable.
- approachBall (sims.soccer.approach): a Dubins path round the ball to a pre-pose behind it, then straight in.
- dribbleBall (sims.soccer.dribble): a Dubins path with a wide turning radius and slow arcs, ball in the guide.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

from sims.soccer.approach import APPROACH, R_APPROACH, approachBall
from sims.soccer.control import Pose, axle_pose
from sims.soccer.dribble import dribbleBall
from sims.soccer.dubins import DubinsPath, shortest_path_inside

Command = tuple[float, float]
Action = Callable[[float, float, float, float, float, float, float, float], Command]

GOTO_STRAIGHT = 0.1  # m, goToPose's Dubins path ends this little behind the goal: it curves in, ball or not
GOTO = replace(APPROACH, final_straight=GOTO_STRAIGHT)


def goto_path(start: Pose, pre: Pose) -> DubinsPath:
    """The shortest Dubins path onto the intermediate pose that stays on the field (blind to any ball)."""
    return shortest_path_inside(start, pre, R_APPROACH, GOTO.box)


def goToPose(x: float, y: float, phi: float, v: float, xg: float, yg: float, phig: float, vg: float) -> Command:
    """Navigate to the goal pose via the intermediate pose PRE_DISTANCE behind it (App. A.1), then straight in
    with the goal heading, arriving with speed vg. It knows nothing of a ball: on the way it may bump one."""
    return GOTO.command(axle_pose(x, y, phi), v, axle_pose(xg, yg, phig), vg, goto_path)


ACTION_FUNCTIONS: dict[str, Action] = {
    "goToPose": goToPose, "approachBall": approachBall, "dribbleBall": dribbleBall,
}
