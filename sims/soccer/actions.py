"""The soccer actions (Sec. 2.2, App. A.1): pure functions from the belief state and the subgoal to [v, phidot].

Every action has the signature `(x, y, phi, v, xg, yg, phig, vg) -> (v_cmd, phidot_cmd)`: the robot's
dynamic pose (its ball point, heading, signed speed) as believed, and the goal pose. They keep no state, so
the simulator (or a real robot) may call them at any rate.

- goToPose (sims.soccer.goto): an intermediate point behind the goal pose lures the robot in (App. A.1);
  where no detour is needed, a Dubins path. It does not see a ball: the collision classifier of Sec. 4.2.2
  learns when it bumps one lying at its goal.
- approachBall (sims.soccer.approach): a Dubins path round the ball to a pre-pose behind it, then straight in.
- dribbleBall (sims.soccer.dribble): a Dubins path with a tight turning radius and slow arcs, ball in the guide.
- goToPosition (sims.soccer.position): turn and go to a position, no goal heading (App. A.2): the action of
  the other robot kind of a mixed team (Sec. 7.3), sized for its slower dynamics (world.SPARROW).
"""

from __future__ import annotations

from collections.abc import Callable

from tailor.sims.soccer.approach import approachBall
from tailor.sims.soccer.dribble import dribbleBall
from tailor.sims.soccer.goto import goToPose
from tailor.sims.soccer.position import goToPosition

Command = tuple[float, float]
Action = Callable[[float, float, float, float, float, float, float, float], Command]

ACTION_FUNCTIONS: dict[str, Action] = {
    "goToPose": goToPose, "approachBall": approachBall, "dribbleBall": dribbleBall, "goToPosition": goToPosition,
}
HEADING_FREE = frozenset({"goToPosition"})  # actions whose goal heading is ignored (and not judged)
