"""Points the paths pass through (auto_features._via_points): where the durations depend on where in the plane a
move goes (a wall with a door in a fixed scene), the door is found from the data alone and the length and turns
through it make the model far more accurate; in an open field no point is offered. (These tests fail where the
family is switched off.)"""

from __future__ import annotations

import numpy as np
from tailor.refinement.learning.feature_selection import select_features
from tailor.refinement.models.auto_features import VIA, candidate_columns, generate
from tailor.refinement.models.expression_space import ExpressionSpace
from tailor.refinement.models.expressions import from_json
from tailor.refinement.models.features import first_examples
from tailor.sims.episode import Episode
from tailor.sims.protocol import ActionSpec, Quantity, SimulatorEntry

UNITS = {"x": Quantity("m"), "y": Quantity("m"), "phi": Quantity("rad", angle=True), "v": Quantity("m/s")}
PLANAR = ActionSpec("drive", "toy", ("x", "y", "phi", "v"), ("xg", "yg", "phig", "vg"), ("x", "y", "phi", "v"),
                    ("x", "y", "phi", "v"))
DOOR = (0.0, 1.0)  # m: the gap in a wall along x = 0 that every move from one side to the other passes through
# every move starts west of the wall (x < 0); its goal is anywhere, east of the wall for about half of them


def quantity(name: str) -> Quantity:
    return UNITS.get(name, Quantity())


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2 * np.pi) - np.pi


def _rows(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x, y, xg, yg = rng.uniform(-4, -0.5, n), *rng.uniform(-4, 4, (3, n))
    phi, phig = rng.uniform(-np.pi, np.pi, (2, n))
    return np.column_stack([x, y, phi, np.zeros(n), xg, yg, phig, np.zeros(n)])


def _durations(rows: np.ndarray, wall: bool, seed: int) -> np.ndarray:
    """1 m/s along the path, 1 rad/s turning toward its first leg and from its last one to the goal heading;
    with the wall, a move between its sides goes through the door."""
    x, y, phi, _, xg, yg, phig, _ = rows.T
    through = (np.sign(x) != np.sign(xg)) if wall else np.zeros(len(x), bool)
    px, py = np.where(through, DOOR[0], xg), np.where(through, DOOR[1], yg)
    length = np.hypot(px - x, py - y) + np.hypot(xg - px, yg - py)
    first = np.arctan2(py - y, px - x)
    last = np.where(through, np.arctan2(yg - py, xg - px), first)
    turns = np.abs(_wrap(first - phi)) + np.abs(_wrap(phig - last))
    return length + turns + np.random.default_rng(seed).normal(0, 0.02, len(x))


def _episodes(n: int, seed: int, wall: bool = True) -> list[Episode]:
    rows = _rows(n, seed)
    t = _durations(rows, wall, seed)
    return [Episode("drive", rows[k], np.array([0.0]), rows[k:k + 1, :4], ("x", "y", "phi", "v"), "success",
                    float(t[k]), k) for k in range(n)]


def _via(candidates) -> list:
    return [c for c in candidates if c.family == VIA]


def test_the_door_is_found_from_the_data():
    params, durations = first_examples(_episodes(1500, 0))
    via = _via(generate(PLANAR, quantity, params, durations))
    assert [c.name for c in via][:3] == ["via0_length", "via0_to", "via0_at"]
    first = via[0].expression.args[0].args  # hypot(px - x, py - y) + ...: the point's constants
    point = (first[0].args[0].value, first[1].args[0].value)
    assert np.hypot(point[0] - DOOR[0], point[1] - DOOR[1]) < 0.3, point
    for c in via:  # each reads back from a model file, and its bounds enclose its values
        assert from_json(c.expression.to_json(), PLANAR.parameters) == c.expression
    space = ExpressionSpace(PLANAR.parameters, tuple(c.name for c in via), tuple(c.expression for c in via))
    rng = np.random.default_rng(3)
    centre = _rows(5, 4)
    low, high = centre - 0.2, centre + 0.2
    f_low, f_high = space.bounds(low, high)
    for k in range(5):
        values = space.compute(rng.uniform(low[k], high[k], (300, len(PLANAR.parameters))))
        assert np.all(f_low[k] <= values + 1e-9) and np.all(values <= f_high[k] + 1e-9)


def test_an_open_field_gets_no_point():
    """Durations that depend on no place: the rule, decided from the data, offers nothing."""
    params, durations = first_examples(_episodes(1500, 1, wall=False))
    assert not _via(generate(PLANAR, quantity, params, durations))


def test_the_length_and_turns_through_the_door_make_the_model():
    """Selected, they predict the durations far better than the straight move's features can (without the
    family the cross-validated error is about eight times larger)."""
    episodes = _episodes(1500, 2)
    entry = SimulatorEntry("toy", {"drive": PLANAR}, create=lambda seed, noise=None: None, units=UNITS)
    selection = select_features(PLANAR, entry, episodes, seed=0, others={})
    chosen = [step["feature"] for step in selection.report["steps"][1:]]
    assert any(name.startswith("via") for name in chosen), chosen
    assert selection.report["generated_sets"]["forward"] < 0.15, selection.report["generated_sets"]  # s; 0.43 without
    params, _ = first_examples(episodes[:50])
    assert np.all(np.isfinite(candidate_columns(_via(generate(PLANAR, quantity, *first_examples(episodes))),
                                                PLANAR.parameters, params)))
