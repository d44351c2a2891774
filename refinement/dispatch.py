"""Dispatch a fully bound action sequence to the simulator of its actions (the last stage of Algorithm 4)."""

from __future__ import annotations

from tailor.sims import ACTIONS
from tailor.sims.episode import ActionCall, SequenceResult

from tailor.refinement.action_sequence import ActionSequence
from tailor.refinement.errors import TailorError


def _soccer(robot, ball, calls, seed, noise):
    from tailor.sims.soccer import simulate_sequence

    return simulate_sequence(robot=robot, ball=ball, calls=calls, seed=seed, noise=noise)


SIMULATORS = {"soccer": _soccer}


def dispatch(sequence: ActionSequence, seed: int = 0, noise=None) -> SequenceResult:
    """Execute the sequence in its simulator; observed parameters come from the simulated world."""
    if not sequence.actions:
        raise TailorError(f"problem {sequence.problem!r}: the plan has no actions to dispatch")
    simulators = {ACTIONS[a.action].simulator for a in sequence.actions}
    if len(simulators) != 1:
        raise TailorError(f"problem {sequence.problem!r}: actions of several simulators: {sorted(simulators)}")
    (name,) = simulators
    if name not in SIMULATORS:
        raise TailorError(f"problem {sequence.problem!r}: no simulator {name!r}")
    if "robot" not in sequence.scene:
        raise TailorError(f"problem {sequence.problem!r}: the belief state places no robot")
    spec = ACTIONS[sequence.actions[0].action]
    n_observed = len(spec.observed)
    calls = [ActionCall(a.action, tuple(float(x) for x in a.values()[n_observed:])) for a in sequence.actions]
    robot = tuple(float(x) for x in sequence.scene["robot"])
    ball = sequence.scene.get("ball")
    ball = tuple(float(x) for x in ball) if ball is not None else None
    return SIMULATORS[name](robot, ball, calls, seed, noise)
