"""Automatic feature generation and selection (Sec. 4.1.1): candidates built from an action's declared
quantities for any robot, invariant where the quantities say so; Table 4.1's generic rows rebuilt from the
structure; forward selection that finds the features a duration depends on; and models learned on generated
features far more accurate than on the raw parameters (these tests fail where the generation is switched off)."""

from __future__ import annotations

import numpy as np
import pytest

from tailor.refinement.learning.duration_protocol import train_duration_model
from tailor.refinement.learning.feature_selection import generic_space, select_features
from tailor.refinement.models.auto_features import candidate_columns, generate, generic_row
from tailor.refinement.models.auto_paths import fit_curvature
from tailor.refinement.models.expression_space import ExpressionSpace
from tailor.refinement.models.expressions import from_json
from tailor.refinement.models.features import raw_space
from tailor.sims.episode import Episode
from tailor.sims.protocol import ActionSpec, Quantity, SimulatorEntry

UNITS = {"x": Quantity("m"), "y": Quantity("m"), "phi": Quantity("rad", angle=True), "v": Quantity("m/s"),
         "q": Quantity("rad", angle=True), "w": Quantity("rad/s"), "pos": Quantity("cm"), "vel": Quantity("cm/s")}
PLANAR = ActionSpec("drive", "toy", ("x", "y", "phi", "v"), ("xg", "yg", "phig", "vg"), ("x", "y", "phi", "v"),
                    ("x", "y", "phi", "v"))
JOINTS = ActionSpec("bend", "toy", ("qa", "wa", "qb", "wb"), ("qga", "wga", "qgb", "wgb"), ("q", "w", "q", "w"),
                    ("q", "w", "q", "w"))
RAIL = ActionSpec("slide", "toy", ("pos", "vel"), ("target", "target_vel"), ("pos", "vel"), ("pos", "vel"))
# a goal that is a point in the start's units, not the start's quantities (paired by unit in order)
POINT = ActionSpec("touch", "toy", ("x", "y", "phi"), ("px", "py"), ("x", "y", "phi"), ("px", "py"))
UNITS.update(px=Quantity("m"), py=Quantity("m"))


def quantity(name: str) -> Quantity:
    return UNITS.get(name, Quantity())


def entry(spec: ActionSpec) -> SimulatorEntry:
    return SimulatorEntry("toy", {spec.name: spec}, create=lambda seed, noise=None: None, units=UNITS)


def names(spec: ActionSpec, params=None, durations=None) -> set[str]:
    return {c.name for c in generate(spec, quantity, params, durations)}


def test_candidates_come_from_the_quantities_not_the_names():
    planar = names(PLANAR)
    assert {"d_x", "dist_x_y", "to_x_y_phi", "at_x_y_phig", "rel_phi_phig", "across_x_y_phi",
            "v_toward_x_y", "vg_toward_x_y"} <= planar
    assert {"d_qa", "abs_d_qb", "max_d_qa_qb", "wa_toward_qa", "wgb_toward_qb"} <= names(JOINTS)
    assert {"d_pos", "vel_toward_pos", "target_vel_toward_pos"} <= names(RAIL)
    assert {"dist_x_y", "to_x_y_phi", "along_x_y_phi"} <= names(POINT)  # px with x, py with y: by unit, in order


def test_the_generic_rows_of_table_4_1():
    assert [c.name for c in generic_row(PLANAR, quantity)] == ["v", "vg", "dist", "angle_to", "angle_at"]
    assert [c.name for c in generic_row(JOINTS, quantity)] == ["dist", "angle1", "angle2", "v", "vg"]
    assert [c.name for c in generic_row(RAIL, quantity)] == ["dist", "v", "vg"]
    assert generic_row(ActionSpec("odd", "toy", ("a",), ("b",), ("a",), ("b",)), quantity) is None


def test_the_planar_row_equals_the_hand_written_one():
    """The pose row generated from the quantities computes what Table 4.1 writes by hand."""
    rng = np.random.default_rng(0)
    p = np.column_stack([rng.uniform(-4, 4, (50, 2)), rng.uniform(-np.pi, np.pi, 50), rng.uniform(0, 1, 50),
                         rng.uniform(-4, 4, (50, 2)), rng.uniform(-np.pi, np.pi, 50), rng.uniform(0, 1, 50)])
    row = generic_space(PLANAR, entry(PLANAR)).compute(p)
    x, y, phi, v, xg, yg, phig, vg = p.T
    bearing = np.arctan2(yg - y, xg - x)
    signed = np.mod(bearing - phi + np.pi, 2 * np.pi) - np.pi
    at = np.where(signed < 0, -1, 1) * (np.mod(phig - bearing + np.pi, 2 * np.pi) - np.pi)
    assert np.allclose(row, np.column_stack([v, vg, np.hypot(xg - x, yg - y), np.abs(signed), at]))


def _rigid(p: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    a, (sx, sy) = rng.uniform(-np.pi, np.pi), rng.uniform(-5, 5, 2)
    out = p.copy()
    for ix, iy, iphi in ((0, 1, 2), (4, 5, 6)):
        out[:, ix] = np.cos(a) * p[:, ix] - np.sin(a) * p[:, iy] + sx
        out[:, iy] = np.sin(a) * p[:, ix] + np.cos(a) * p[:, iy] + sy
        out[:, iphi] = p[:, iphi] + a
    return out


def test_geometric_candidates_are_invariant_to_moving_the_scene():
    rng = np.random.default_rng(1)
    p = np.column_stack([rng.uniform(-4, 4, (80, 2)), rng.uniform(-np.pi, np.pi, 80), rng.uniform(0, 1, 80),
                         rng.uniform(-4, 4, (80, 2)), rng.uniform(-np.pi, np.pi, 80), rng.uniform(0, 1, 80)])
    invariant = [c for c in generate(PLANAR, quantity)
                 if c.name.startswith(("dist_", "to_", "at_", "abs_at_", "turn_", "rel_", "across_", "along_"))]
    assert len(invariant) >= 8
    before = candidate_columns(invariant, PLANAR.parameters, p)
    after = candidate_columns(invariant, PLANAR.parameters, _rigid(p, rng))
    assert np.allclose(before, after, atol=1e-9)


def _rail_episodes(n: int, seed: int, scale: float = 100.0) -> list[Episode]:
    """Synthetic moves on a rail (cm): the duration is the double integrator's least time plus noise."""
    from tailor.refinement.models.expression_maths import transfer

    rng = np.random.default_rng(seed)
    x, xg = rng.uniform(-300, 300, (2, n))
    v, vg = rng.uniform(-50, 50, (2, n))
    t = transfer((xg - x) / scale, v / scale, vg / scale, 1.0, 0.5) + rng.normal(0, 0.02, n)
    return [Episode("slide", np.array([x[k], v[k], xg[k], vg[k]]), np.array([0.0]),
                    np.array([[x[k], v[k]]]), ("pos", "vel"), "success", float(t[k]), k) for k in range(n)]


def test_selection_finds_the_time_of_a_move_and_its_limits():
    episodes = _rail_episodes(600, 0)
    selection = select_features(RAIL, entry(RAIL), episodes, seed=0)
    assert selection.space is not None and selection.report["chosen"] == "auto"
    formulas = [f["formula"] for f in selection.report["selected"]]
    assert formulas[0].startswith("transfer(target - pos, vel, target_vel; vmax=")
    vmax = float(formulas[0].split("vmax=")[1].split(",")[0])
    assert 90 <= vmax <= 110  # 1 m/s in the action's own unit, cm/s, found from the data alone
    assert selection.report["selected"][0]["unit"] == "s"
    assert len(selection.space.names) <= 4


def test_generated_features_beat_the_raw_parameters_by_far():
    """With generation switched off (the raw parameters), this fails: the move's time is no function a model
    tree fits from x, v, xg, vg in 600 episodes."""
    episodes = _rail_episodes(600, 1)
    selection = select_features(RAIL, entry(RAIL), episodes[:450], seed=1)
    auto = train_duration_model("slide", episodes, 1, selection.space, ("pos", "vel"), n_i_candidates=(1,),
                                episode_fractions=(1.0,)).report
    raw = train_duration_model("slide", episodes, 1, raw_space(RAIL.parameters), ("pos", "vel"),
                               n_i_candidates=(1,), episode_fractions=(1.0,)).report
    assert auto["mae"] < 0.25 * raw["mae"]
    assert auto["mae"] < 0.06


def test_a_simulators_own_space_is_one_candidate_set_among_others():
    from tailor.sims.protocol import FeatureSpace

    episodes = _rail_episodes(300, 2)
    useless = FeatureSpace("useless", RAIL.parameters, ("one",), lambda p: p[:, :1] * 0 + 1.0, "everything")
    selection = select_features(RAIL, entry(RAIL), episodes, seed=2, others={"useless": useless})
    assert set(selection.report["candidate_sets"]) == {"generated", "useless"}
    assert selection.space is not None  # the generated set wins
    exact = FeatureSpace("exact", RAIL.parameters, ("t",), lambda p: np.column_stack(
        [np.array([e.duration for e in episodes])[:len(p)]]) if len(p) == len(episodes) else p[:, :1], "nothing")
    chosen = select_features(RAIL, entry(RAIL), episodes, seed=2, others={"exact": exact})
    assert chosen.named == "exact" and chosen.space is None


def test_generation_needs_no_data_and_stays_bounded():
    for spec in (PLANAR, JOINTS, RAIL, POINT):
        candidates = generate(spec, quantity)
        assert 0 < len(candidates) <= 160
        for c in candidates:  # every one reads back from a model file
            assert from_json(c.expression.to_json(), spec.parameters) == c.expression


@pytest.mark.parametrize("spec", [PLANAR, JOINTS])
def test_generated_spaces_bound_themselves(spec):
    candidates = generate(spec, quantity)[:32]
    s = ExpressionSpace(spec.parameters, tuple(c.name for c in candidates), tuple(c.expression for c in candidates))
    rng = np.random.default_rng(3)
    centre = rng.uniform(-3, 3, (5, len(spec.parameters)))
    low, high = centre - 0.2, centre + 0.2
    f_low, f_high = s.bounds(low, high)
    for k in range(5):
        values = s.compute(rng.uniform(low[k], high[k], (500, len(spec.parameters))))
        assert np.all(f_low[k] <= values) and np.all(values <= f_high[k])


@pytest.mark.parametrize("simulator, scenario", [("kitchen", "navigate"), ("kitchen", "grip"), ("arm", "reach"),
                                                 ("soccer", "goToPose")])
def test_the_bundled_robots_get_candidates_from_their_declarations_alone(simulator, scenario):
    from tailor.refinement.models.features import first_examples
    from tailor.sims import registry
    from tailor.sims.experience import gather

    robot = registry.get(simulator)
    episodes = [e for e in gather(simulator, scenario, 40, seed=0, progress=False) if e.succeeded]
    spec = robot.action(episodes[0].action)
    params, durations = first_examples(episodes)
    candidates = generate(spec, robot.quantity, params, durations)
    assert len(candidates) >= 10
    values = candidate_columns(candidates, spec.parameters, params)
    assert np.all(np.isfinite(values))
    for c in candidates:
        assert from_json(c.expression.to_json(), spec.parameters) == c.expression
    names = {c.name for c in candidates}
    if scenario == "navigate":  # a pose with offsets in its frame: the offset point, its composition found
        assert {"offset_dist", "offset_to"} <= names
    if simulator == "arm":  # joint angles that never go round: differences not wrapped; their moves timed
        assert "transfer_max" in names
        assert any(c.expression.formula() == "theta_ga - theta_a" for c in candidates)


# --- a path of bounded curvature (auto_paths, sims.dubins) -------------------------------------------------------
TRUE_RADIUS, TRUE_START_BACK, TRUE_GOAL_BACK = 0.5, 0.2, 0.6  # m: the toy vehicle turns about a point behind


def _drive_episodes(n: int, seed: int) -> list[Episode]:
    """Synthetic drives of a vehicle that cannot turn on the spot: it follows the shortest path of radius
    TRUE_RADIUS between points TRUE_START_BACK behind the start pose and TRUE_GOAL_BACK behind the goal pose, at
    1 m/s on straights and 0.5 m/s on arcs."""
    from tailor.sims import dubins

    rng = np.random.default_rng(seed)
    x, y, xg, yg = rng.uniform(-4, 4, (4, n))
    phi, phig = rng.uniform(-np.pi, np.pi, (2, n))
    v, vg = rng.uniform(0, 1, (2, n))
    start = np.column_stack([x - TRUE_START_BACK * np.cos(phi), y - TRUE_START_BACK * np.sin(phi), phi])
    goal = np.column_stack([xg - TRUE_GOAL_BACK * np.cos(phig), yg - TRUE_GOAL_BACK * np.sin(phig), phig])
    length, arcs = dubins.shortest(start, goal, TRUE_RADIUS)
    t = (length - arcs) / 1.0 + arcs / 0.5 + rng.normal(0, 0.02, n)
    rows = np.column_stack([x, y, phi, v, xg, yg, phig, vg])
    return [Episode("drive", rows[k], np.array([0.0]), rows[k:k + 1, :4], ("x", "y", "phi", "v"), "success",
                    float(t[k]), k) for k in range(n)]


def test_a_path_of_bounded_curvature_is_offered_where_start_and_goal_are_poses():
    from tailor.refinement.models.features import first_examples

    params, durations = first_examples(_drive_episodes(300, 0))
    offered = names(PLANAR, params, durations)
    assert {"dubins_x_y_phi_phig", "dubins_arcs_x_y_phi_phig", "dubins_transfer_x_y_phi_phig"} <= offered
    assert not any(n.startswith("dubins_inside") for n in offered)  # no walls: no region
    assert not any(n.startswith("dubins") for n in names(PLANAR))  # its constants need data
    x, y, phi, _, xg, yg, phig, _ = params.T  # a robot that turns on the spot: the turns at the ends, no path
    bearing = np.arctan2(yg - y, xg - x)
    turns = np.abs(np.angle(np.exp(1j * (bearing - phi)))) + np.abs(np.angle(np.exp(1j * (phig - bearing))))
    assert not any(n.startswith("dubins") for n in names(PLANAR, params, np.hypot(xg - x, yg - y) + turns / 2))
    rng = np.random.default_rng(1)
    for spec in (JOINTS, RAIL, POINT):  # no plane, or no heading at the goal: no path
        rows = rng.uniform(-3, 3, (200, len(spec.parameters)))
        assert not any(n.startswith("dubins") for n in names(spec, rows, rng.uniform(1, 5, 200))), spec.name


def test_the_turning_radius_and_the_points_it_turns_about_are_found_from_the_data():
    episodes = _drive_episodes(800, 2)
    selection = select_features(PLANAR, entry(PLANAR), episodes, seed=0)
    first = selection.report["steps"][1]
    assert first["feature"].startswith("dubins"), first
    params, durations = _first(episodes)
    x, y, phi, _, xg, yg, phig, _ = params.T
    fit = fit_curvature(xg - x, yg - y, phi, phig, durations)
    assert fit.radius == pytest.approx(TRUE_RADIUS, rel=0.1)
    assert fit.start_back == pytest.approx(TRUE_START_BACK, abs=0.05)
    assert fit.goal_back == pytest.approx(TRUE_GOAL_BACK, abs=0.05)
    candidates = {c.name: c for c in generate(PLANAR, quantity, params, durations)}
    assert candidates["dubins_x_y_phi_phig"].expression.formula().endswith(f"phi, phig; r={fit.radius:g})")
    assert selection.report["generated_sets"]["forward"] < 0.1  # seconds, of durations of 3 to 20 s
    # invariant to moving the scene, and enclosed by its bounds
    path = [candidates[n] for n in ("dubins_x_y_phi_phig", "dubins_arcs_x_y_phi_phig")]
    p = params[:100]
    rng = np.random.default_rng(3)
    assert np.allclose(candidate_columns(path, PLANAR.parameters, p),
                       candidate_columns(path, PLANAR.parameters, _rigid(p, rng)), atol=1e-6)


def test_the_families_discovered_in_workers_are_those_discovered_here():
    """generate's discovery (transfer limits, approach lengths, paths, via points) runs in workers with jobs > 1:
    the same candidates, in the same order, with the same constants."""
    params, durations = _first(_walled_episodes(300, 5))
    here = generate(PLANAR, quantity, params, durations)
    there = generate(PLANAR, quantity, params, durations, jobs=2)
    assert [(c.name, c.expression.formula()) for c in there] == [(c.name, c.expression.formula()) for c in here]
    assert any(c.name.startswith("dubins_inside") for c in here) and any(c.name.startswith("transfer") for c in here)


def _first(episodes: list[Episode]) -> tuple[np.ndarray, np.ndarray]:
    from tailor.refinement.models.features import first_examples

    return first_examples(episodes)


# --- a path inside the region the positions occupy (auto_paths.fit_region, sims.dubins_inside) --------------------
WALLS = (-3.7, 3.7, -2.7, 2.7)  # m: the toy vehicle's workspace; its starts and goals lie 0.7 m inside


def _walled_episodes(n: int, seed: int) -> list[Episode]:
    """Drives as _drive_episodes' of a vehicle that plans the shortest path staying inside WALLS."""
    from tailor.sims import dubins_inside

    rng = np.random.default_rng(seed)
    x, xg = rng.uniform(-3, 3, (2, n))
    y, yg = rng.uniform(-2, 2, (2, n))
    phi, phig = rng.uniform(-np.pi, np.pi, (2, n))
    v, vg = rng.uniform(0, 1, (2, n))
    start = np.column_stack([x - TRUE_START_BACK * np.cos(phi), y - TRUE_START_BACK * np.sin(phi), phi])
    goal = np.column_stack([xg - TRUE_GOAL_BACK * np.cos(phig), yg - TRUE_GOAL_BACK * np.sin(phig), phig])
    length, arcs = dubins_inside.shortest_inside(start, goal, TRUE_RADIUS, WALLS)
    t = (length - arcs) / 1.0 + arcs / 0.5 + rng.normal(0, 0.02, n)
    rows = np.column_stack([x, y, phi, v, xg, yg, phig, vg])
    return [Episode("drive", rows[k], np.array([0.0]), rows[k:k + 1, :4], ("x", "y", "phi", "v"), "success",
                    float(t[k]), k) for k in range(n)]


def test_a_workspace_with_walls_is_found_from_the_region_the_positions_occupy():
    """Near the walls the vehicle drives a longer word than the free shortest one; the path inside the region the
    positions occupy, widened by a discovered margin, is offered and chosen, and predicts the durations to their
    noise, where the free path cannot (it fails with the region switched off)."""
    episodes = _walled_episodes(600, 4)
    params, durations = _first(episodes)
    candidates = {c.name: c for c in generate(PLANAR, quantity, params, durations)}
    inside = candidates["dubins_inside_x_y_phi_phig"].expression
    assert inside.op == "dubins_inside"
    region = [a.value for a in inside.args[7:]]
    assert region == pytest.approx(list(WALLS), abs=0.05)
    assert inside.args[6].value == pytest.approx(TRUE_RADIUS, rel=0.05)
    selection = select_features(PLANAR, entry(PLANAR), episodes, seed=0)
    assert selection.report["steps"][1]["feature"] == "dubins_inside_x_y_phi_phig"
    assert selection.report["generated_sets"]["forward"] < 0.04  # seconds (noise 0.02 s), of durations of 3 to 20 s
    space = selection.space  # stored as data and enclosed over boxes
    assert ExpressionSpace.from_json(space.to_json(), PLANAR.parameters).formulas == space.formulas
    low, high = space.bounds(params[:50] - 0.01, params[:50] + 0.01)
    values = space.compute(params[:50])
    assert np.all(low <= values) and np.all(values <= high)


# --- a pose with offsets against a point (one group's frame composed, the other taken as it is) ------------------
UNITS.update(ox=Quantity("m"), oy=Quantity("m"), along=Quantity("m"), dist=Quantity("m"),
             ophi=Quantity("rad", angle=True), heading=Quantity("rad", angle=True))
SPOT = ("ox", "oy", "ophi", "along", "dist", "heading")
REACH_FROM_SPOT = ActionSpec("reach", "toy", SPOT, ("px", "py"), SPOT, ("px", "py"))


def test_a_pose_with_offsets_is_composed_against_a_point():
    """The base stands `along` ahead of its frame and `dist` to its right (a convention not declared), turned by
    ophi + heading; the duration depends on the point as seen from the base. The composition is found from the
    durations, and the distance and angle to the point from the offset pose are candidates (with the offsets as
    zeros, or the frame alone, they could not be)."""
    rng = np.random.default_rng(0)
    n = 600
    ox, oy, ophi = rng.uniform(-3, 3, n), rng.uniform(-3, 3, n), rng.uniform(-np.pi, np.pi, n)
    along, dist, heading = rng.uniform(-0.5, 0.5, n), rng.uniform(0.4, 0.8, n), rng.uniform(-1, 1, n)
    c, s = np.cos(ophi), np.sin(ophi)
    bx, by = ox + along * c + dist * s, oy + along * s - dist * c
    reach = rng.uniform(0.3, 1.2, n)
    px, py = ox + reach * c + rng.uniform(-0.3, 0.3, n) * s, oy + reach * s
    distance = np.hypot(px - bx, py - by)
    to = np.abs((np.arctan2(py - by, px - bx) - ophi - heading + np.pi) % (2 * np.pi) - np.pi)
    durations = 2.0 * distance + 1.5 * to + rng.normal(0, 0.02, n)
    params = np.column_stack([ox, oy, ophi, along, dist, heading, px, py])
    candidates = {c.name: c for c in generate(REACH_FROM_SPOT, quantity, params, durations)}
    assert {"offset_dist", "offset_to", "offset_along", "offset_across"} <= set(candidates)
    values = candidate_columns([candidates["offset_dist"], candidates["offset_to"]], REACH_FROM_SPOT.parameters,
                               params)
    assert np.allclose(values, np.column_stack([distance, to]), atol=1e-9)
    # no heading in the point's group: no angle at it
    assert "offset_abs_at" not in candidates and "offset_turn" not in candidates
