"""The arm simulator (pymunk): a PowerCube-like planar 2-DOF arm drawing letters (Sec. 5.5, App. A.4).

`SIMULATOR` is what the package registers (entry point `tailor.simulators: arm`): the reach action in joint
space (Table 2.1), the simulator factory, the experience scenario and the random letters, its own feature
space, its quantities' and measures' units (joint angles are angles, but within their limits: never a full
circle), and for the closed loop (Ch. 8.1) its disturbance "bump" and its variant "payload"
(sims.arm.disturbances).

Declaring the robot loads no physics: the simulator module (sims.arm.simulator, which imports pymunk) is
imported when a simulator is first created or an episode first runs, so that `tailor domains` and
`tailor plan` stay light; `ArmSim`, `Noise` and `simulate_sequence` still import from here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from tailor.sims.arm.disturbances import DISTURBANCES, VARIANTS
from tailor.sims.arm.features import RAMPS
from tailor.sims.arm.scenarios import SITUATIONS, run_reach, run_stroke_leg, subgoal_episode
from tailor.sims.registry import deferred_names
from tailor.sims.protocol import ActionSpec, Quantity, Scenario, SimulatorEntry

if TYPE_CHECKING:
    from tailor.sims.arm.simulator import ArmSim, Noise

_JOINTS = ("theta_a", "omega_a", "theta_b", "omega_b")
_ANGLE, _SPEED, _METRES = Quantity("rad", angle=True), Quantity("rad/s"), Quantity("m")
UNITS = {"theta_a": _ANGLE, "theta_b": _ANGLE, "omega_a": _SPEED, "omega_b": _SPEED, "tip_x": _METRES,
         "tip_y": _METRES,
         # the measures of a reach besides its duration (sims.arm.simulator: what each one is; a reach has no
         # heading, so no heading_error)
         "energy": Quantity("J"), "error": _METRES}


def _create(seed: int, noise: Noise | None = None, disturbance: str | None = None,
            variant: str | None = None) -> ArmSim:
    # deferred: the simulator module loads pymunk, which declaring the robot must not
    from tailor.sims.arm.simulator import ArmSim, Noise

    return ArmSim(seed, Noise() if noise is None else noise, disturbance, variant)


SIMULATOR = SimulatorEntry(
    name="arm",
    actions={"reach": ActionSpec("reach", "arm", observed=_JOINTS,
                                 internal=("theta_ga", "omega_ga", "theta_gb", "omega_gb"),
                                 observed_quantities=_JOINTS, internal_quantities=_JOINTS)},
    create=_create,
    scenarios={"reach": Scenario("reach", "reach", run_reach, run_reach.__doc__ or ""),
               "stroke": Scenario("stroke", "reach", run_stroke_leg, run_stroke_leg.__doc__ or "")},
    situations=SITUATIONS,
    scene_objects=("arm",),
    subgoal_episode=subgoal_episode,
    views=(("tip_x", "tip_y"), ("theta_a", "theta_b")),
    feature_spaces=(RAMPS,),
    units=UNITS,
    disturbances=DISTURBANCES,
    variants=VARIANTS,
    description="PowerCube-like planar arm (shoulder, elbow), ramp velocity profiles tracked by PID (pymunk)",
)

# names of the simulator module, imported on first use (see above)
__getattr__ = deferred_names(__name__, "simulator", ("ArmSim", "Noise", "simulate_sequence"))


__all__ = ["SIMULATOR", "ArmSim", "Noise", "simulate_sequence"]
