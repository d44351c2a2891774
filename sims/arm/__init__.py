"""The arm simulator (pymunk): a PowerCube-like planar 2-DOF arm drawing letters (Sec. 5.5, App. A.4).

`SIMULATOR` is what the package registers (entry point `tailor.simulators: arm`): the reach action in joint
space (Table 2.1), the simulator factory, the experience scenario and the random letters.
"""

from tailor.sims.arm.features import RAMPS
from tailor.sims.arm.scenarios import SITUATIONS, run_reach, run_stroke_leg, subgoal_episode
from tailor.sims.arm.simulator import ArmSim, Noise, simulate_sequence
from tailor.sims.protocol import ActionSpec, Scenario, SimulatorEntry

_JOINTS = ("theta_a", "omega_a", "theta_b", "omega_b")


def _create(seed: int, noise: Noise | None = None) -> ArmSim:
    return ArmSim(seed, Noise() if noise is None else noise)


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
    description="PowerCube-like planar arm (shoulder, elbow), ramp velocity profiles tracked by PID (pymunk)",
)

__all__ = ["SIMULATOR", "ArmSim", "Noise", "simulate_sequence"]
