"""Dispatch a fully bound action sequence to the simulator of its actions (the last stage of Algorithm 4)."""

from __future__ import annotations

from tailor.refinement.action_sequence import ActionSequence
from tailor.errors import SimError, TailorError
from tailor.sims import registry
from tailor.sims.episode import ActionCall, SequenceResult


def action_calls(sequence: ActionSequence) -> list[ActionCall]:
    """Each action with its internal (subgoal) parameters; the observed ones come from the simulated world."""
    entry = registry.get(sequence.simulator)
    calls = []
    for action in sequence.actions:
        n_observed = len(entry.action(action.action).observed)
        calls.append(ActionCall(action.action, tuple(float(x) for x in action.values()[n_observed:])))
    return calls


def dispatch(sequence: ActionSequence, seed: int = 0, noise=None) -> SequenceResult:
    """Execute the sequence in a fresh simulator reset to its scene; `noise` None is the simulator's default."""
    if not sequence.actions:
        raise TailorError(f"problem {sequence.problem!r}: the plan has no actions to dispatch")
    if not sequence.simulator:
        raise TailorError(f"problem {sequence.problem!r}: the action sequence names no simulator")
    calls = action_calls(sequence)
    simulator = registry.get(sequence.simulator).create(seed, noise)
    simulator.reset({name: tuple(float(x) for x in values) for name, values in sequence.scene.items()})
    return simulator.run_sequence(calls)


def check_scene(sequence: ActionSequence, binding_file: str | None = None) -> None:
    """Reset a fresh simulator to the sequence's scene before anything is refined or simulated, so that a scene
    object the simulator does not have (a binding's `scene = "goalpost"`) or a belief value outside its world
    fails at once, naming the binding, not after the optimization."""
    if not sequence.actions or not sequence.simulator:
        return
    simulator = registry.get(sequence.simulator).create(0, None)
    try:
        simulator.reset({name: tuple(float(x) for x in values) for name, values in sequence.scene.items()})
    except SimError as exc:
        placed = ", ".join(sorted(sequence.scene)) or "nothing"
        raise SimError(f"simulator {sequence.simulator!r} rejects the scene the binding's `scene` keys place "
                       f"({placed}): {exc.message}", file=binding_file) from None
