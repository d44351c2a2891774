"""Features as data (models.expressions, expression_maths, expression_space): what each operator computes,
hostile or malformed stored expressions refused before anything is computed, and interval bounds that enclose
every value of every operator over every box (checked against dense sampling, hypothesis drawing the trees)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tailor.errors import ModelFileError
from tailor.refinement.models.action_models import ActionModel
from tailor.refinement.models.expression_maths import evaluate, interval, transfer
from tailor.refinement.models.expression_space import ExpressionSpace
from tailor.refinement.models.expressions import (ARITY, CONSTANT_ARGUMENTS, MAX_DEPTH, MAX_NODES, REGION_ARGUMENTS,
                                                  Expr, ExpressionError, const, format_unit, from_json, node, param,
                                                  parse_unit, unit_of, units_of)
from tailor.refinement.models.model_tree import ModelTree

PARAMS = ("x", "v", "xg", "vg", "h")
UNITS = {"x": "m", "v": "m/s", "xg": "m", "vg": "m/s", "h": "rad"}


def space(*expressions) -> ExpressionSpace:
    exprs = tuple(from_json(e, PARAMS) for e in expressions)
    return ExpressionSpace(PARAMS, tuple(f"f{k}" for k in range(len(exprs))), exprs)


def test_operators_compute_what_the_table_says():
    x = np.array([-3 * np.pi, -1.0, 0.0, 2.0, 4.0])
    y = np.array([2.0, 0.0, 0.0, -4.0, 1.0])
    assert np.allclose(evaluate("wrap", [x]), [-np.pi, -1.0, 0.0, 2.0, 4.0 - 2 * np.pi])
    assert np.all(evaluate("wrap", [x]) >= -np.pi) and np.all(evaluate("wrap", [x]) < np.pi)
    assert list(evaluate("sgn", [x])) == [-1, -1, 1, 1, 1]  # sgn(0) = +1, as Table 4.1's
    assert list(evaluate("div", [x, y])) == [-3 * np.pi / 2, 0.0, 0.0, -0.5, 4.0]  # protected: 0 where y == 0
    assert list(evaluate("sqrt", [np.array([-4.0, 4.0])])) == [0.0, 2.0]
    assert np.allclose(evaluate("atan2", [np.array([1.0]), np.array([-1.0])]), [0.75 * np.pi])


def test_transfer_is_the_double_integrator_time():
    vmax, amax = 1.0, 2.0
    # from rest to rest: a triangle below vmax^2 / amax, a trapezoid above
    d = np.array([0.0, 0.2, 0.5, 3.0, -3.0])
    expected = np.where(np.abs(d) <= vmax ** 2 / amax, 2 * np.sqrt(np.abs(d) / amax),
                        np.abs(d) / vmax + vmax / amax)
    assert np.allclose(transfer(d, 0 * d, 0 * d, vmax, amax), expected)
    # already at top speed toward a far goal, arriving at it: cruise only; mirrored, the same
    assert np.isclose(transfer(np.array([4.0]), np.array([1.0]), np.array([1.0]), vmax, amax)[0], 4.0)
    assert np.isclose(transfer(np.array([-4.0]), np.array([-1.0]), np.array([-1.0]), vmax, amax)[0], 4.0)
    # moving away: brake, come back
    assert transfer(np.array([1.0]), np.array([-1.0]), np.array([0.0]), vmax, amax)[0] > \
        transfer(np.array([1.0]), np.array([0.0]), np.array([0.0]), vmax, amax)[0]


def test_formulas_and_units():
    s = space(["hypot", ["sub", "xg", "x"], ["sub", "vg", "v"]], ["div", ["abs", ["sub", "xg", "x"]], "v"],
              ["abs", ["wrap", ["sub", ["atan2", "xg", "x"], "h"]]], ["sub", "x", ["sub", "xg", "x"]],
              ["transfer", ["sub", "xg", "x"], "v", "vg", 1.0, 0.5], ["mul", -2.0, "x"],
              ["dubins", ["sub", "xg", "x"], "x", "h", ["neg", "h"], 0.4], ["dubins_arcs", "x", "v", "h", "h", 0.4],
              ["dubins_inside", "x", "xg", "h", "xg", "x", "h", 0.4, -3.0, 3.0, -2.5, 2.0])
    assert s.formulas == ("hypot(xg - x, vg - v)", "|xg - x| / v", "|wrap(atan2(xg, x) - h)|", "x - (xg - x)",
                          "transfer(xg - x, v, vg; vmax=1, amax=0.5)", "(-2) * x",
                          "dubins(xg - x, x, h, -h; r=0.4)", "dubins_arcs(x, v, h, h; r=0.4)",
                          "dubins_inside(x, xg, h, xg, x, h; r=0.4, region=[-3, 3] x [-2.5, 2])")
    units = s.with_units(UNITS).units
    assert units == ("?", "s", "rad", "m", "s", "m", "m", "?", "m")
    assert format_unit(parse_unit("m/s^2")) == "m/s^2" and format_unit(parse_unit("")) == ""
    assert format_unit(unit_of(from_json(["sqrt", ["mul", "x", "xg"]], PARAMS), units_of(UNITS))) == "m"
    assert format_unit(parse_unit("1/s")) == "1/s"


@pytest.mark.parametrize("data, message", [
    ("os", "not a parameter"),
    ("__import__('os').system('true')", "not a parameter"),
    (["eval", "x"], "unknown operator"),
    (["add", "x"], "takes 2 arguments"),
    (["add", "x", "v", "xg"], "takes 2 arguments"),
    (float("nan"), "not a finite number"),
    (1e300, "not a finite number"),
    (True, "expected a parameter name"),
    (None, "expected a parameter name"),
    ({"op": "add"}, "expected a parameter name"),
    ([], "expected a parameter name"),
    (["transfer", "x", "v", "vg", "x", 1.0], "positive constant"),
    (["transfer", "x", "v", "vg", -1.0, 1.0], "positive constant"),
    (["dubins", "x", "xg", "h", "h", "x"], "positive constant"),
    (["dubins", "x", "xg", "h", "h", 0.0], "positive constant"),
    (["dubins_arcs", "x", "xg", "h", "h", -0.4], "positive constant"),
    (["dubins", "x", "xg", "h", 0.4], "takes 5 arguments"),
    (["dubins", "x", "xg", "h", "h", 0.4, 0.1], "takes 5 arguments"),
    (["dubins", "x", "xg", "h", "phig", 0.4], "not a parameter"),
    (["dubins_inside", "x", "v", "h", "xg", "vg", "h", 0.4, 3.0, -3.0, -2.0, 2.0], "xmin < xmax"),
    (["dubins_inside_arcs", "x", "v", "h", "xg", "vg", "h", 0.4, -3.0, 3.0, 2.0, 2.0], "ymin < ymax"),
    (["dubins_inside", "x", "v", "h", "xg", "vg", "h", 0.4, "x", 3.0, -2.0, 2.0], "argument 8 .* must be a constant"),
    (["dubins_inside", "x", "v", "h", "xg", "vg", "h", -0.4, -3.0, 3.0, -2.0, 2.0], "positive constant"),
    (["dubins_inside", "x", "v", "h", "xg", "vg", "h", 0.4, -3.0, 3.0, -2.0], "takes 11 arguments"),
])
def test_malformed_expressions_are_refused(data, message):
    with pytest.raises(ExpressionError, match=message):
        from_json(data, PARAMS)


def test_deep_and_large_expressions_are_refused_before_they_are_read_whole():
    deep = "x"
    for _ in range(MAX_DEPTH):
        deep = ["neg", deep]
    with pytest.raises(ExpressionError, match="deeper"):
        from_json(deep, PARAMS)
    very_deep = "x"
    for _ in range(100_000):  # a hostile file: refused at MAX_DEPTH, never recursed into
        very_deep = ["abs", very_deep]
    with pytest.raises(ExpressionError, match="deeper"):
        from_json(very_deep, PARAMS)
    wide = "x"
    for _ in range(MAX_NODES):  # within the depth limit: a balanced tree of too many nodes
        wide = ["add", wide, wide] if isinstance(wide, str) or len(json.dumps(wide)) < 4000 else wide
    balanced = ["add", *[["add", *[["add", *[["add", "x", "v"]] * 2]] * 2]] * 2]
    for _ in range(3):
        balanced = ["add", balanced, balanced]
    with pytest.raises(ExpressionError, match="nodes"):
        from_json(balanced, PARAMS)


def _model(expressions: ExpressionSpace) -> ActionModel:
    rng = np.random.default_rng(0)
    X = rng.uniform(-2, 2, (60, len(PARAMS)))
    features = expressions.compute(X)
    tree = ModelTree(min_samples_leaf=10).fit(features, features[:, 0] + 1.0)
    return ActionModel("move", "auto", expressions.names, tree, 1, {"duration_range": [0.0, 10.0]},
                       expressions=expressions)


def _written(model: ActionModel, tmp_path) -> dict:
    """The model's file written as `tailor train` writes it (tmp_path/move.json), read back as JSON."""
    path = tmp_path / "move.json"
    path.write_text(json.dumps(model.to_json()))
    return json.loads(path.read_text())


def test_a_model_file_keeps_its_features_as_expressions(tmp_path):
    s = space(["abs", ["sub", "xg", "x"]], ["mul", "v", ["sgn", ["sub", "xg", "x"]]]).with_units(UNITS)
    model = _model(s)
    data = _written(model, tmp_path)
    assert data["feature_space"] == "auto"
    assert data["expressions"]["features"][0] == {"name": "f0", "expression": ["abs", ["sub", "xg", "x"]],
                                                  "formula": "|xg - x|", "unit": "m"}
    loaded = ActionModel.from_json(data, str(tmp_path / "move.json"))
    X = np.random.default_rng(1).uniform(-2, 2, (20, len(PARAMS)))
    assert np.array_equal(loaded.predict_duration(X), model.predict_duration(X))
    assert loaded.space.bounds is not None and loaded.space.parameters == PARAMS
    low, high = loaded.space.bounds(X - 0.1, X + 0.1)
    assert np.all(low <= loaded.features(X)) and np.all(loaded.features(X) <= high)


def test_a_model_file_keeps_a_path_of_bounded_curvature_and_bounds_it(tmp_path):
    """dubins and dubins_arcs (sims.dubins): stored as data, read back exactly, the same predictions, and the
    certified optimizer's enclosure holding the features of every point of a box."""
    length = ["dubins", ["sub", ["sub", "xg", "x"], ["mul", 0.3, ["cos", "h"]]], ["mul", 0.3, ["sin", "h"]], "h",
              ["neg", "h"], 0.4]
    arcs = ["dubins_arcs", *length[1:]]
    s = space(length, arcs, ["transfer", length, "v", "vg", 1.0, 0.5]).with_units(UNITS)
    assert s.units == ("m", "m", "s")  # (a fitted number takes its place's unit: xg - x - 0.3 cos(h) is metres)
    model = _model(s)
    data = _written(model, tmp_path)
    assert data["expressions"]["features"][0]["expression"] == length
    assert data["expressions"]["features"][1]["formula"].startswith("dubins_arcs(xg - x - 0.3 * cos(h), ")
    loaded = ActionModel.from_json(data, str(tmp_path / "move.json"))
    assert loaded.space.parameters == PARAMS
    rng = np.random.default_rng(4)
    X = rng.uniform(-2, 2, (200, len(PARAMS)))
    assert np.array_equal(loaded.predict_duration(X), model.predict_duration(X))
    assert np.all(loaded.features(X)[:, 1] <= loaded.features(X)[:, 0] + 1e-12)  # the arcs are part of the path
    low, high = loaded.space.bounds(X - 0.05, X + 0.05)
    for k in range(0, 200, 20):
        values = loaded.features(rng.uniform(X[k] - 0.05, X[k] + 0.05, (300, len(PARAMS))))
        assert np.all(low[k] <= values) and np.all(values <= high[k])
    point_low, point_high = loaded.space.bounds(X, X)  # at a point: the path's features themselves
    assert np.allclose(point_low[:, :2], loaded.features(X)[:, :2], atol=1e-7)
    assert np.allclose(point_high[:, :2], loaded.features(X)[:, :2], atol=1e-7)


def test_a_model_file_keeps_a_path_inside_a_region_and_bounds_it(tmp_path):
    """dubins_inside and dubins_inside_arcs (sims.dubins_inside): stored as data with their region, read back
    exactly, the same predictions, the certified optimizer's enclosure holding every point of a box, and at a point
    the features themselves."""
    start = [["sub", "x", ["mul", 0.3, ["cos", "h"]]], ["sub", "v", ["mul", 0.3, ["sin", "h"]]], "h"]
    length = ["dubins_inside", *start, "xg", "vg", ["neg", "h"], 0.4, -2.5, 2.5, -2.0, 2.0]
    arcs = ["dubins_inside_arcs", *length[1:]]
    s = space(length, arcs)
    model = _model(s)
    data = _written(model, tmp_path)
    assert data["expressions"]["features"][0]["expression"] == length
    assert data["expressions"]["features"][0]["formula"].endswith("; r=0.4, region=[-2.5, 2.5] x [-2, 2])")
    loaded = ActionModel.from_json(data, str(tmp_path / "move.json"))
    rng = np.random.default_rng(6)
    X = rng.uniform(-2, 2, (200, len(PARAMS)))
    assert np.array_equal(loaded.predict_duration(X), model.predict_duration(X))
    free = space(["dubins", ["sub", "xg", start[0]], ["sub", "vg", start[1]], "h", ["neg", "h"], 0.4]).compute(X)
    values = loaded.features(X)
    assert np.all(values[:, 0] >= free[:, 0] - 1e-12) and np.any(values[:, 0] > free[:, 0] + 0.1)  # walls: longer
    low, high = loaded.space.bounds(X - 0.05, X + 0.05)
    for k in range(0, 200, 20):
        inside = loaded.features(rng.uniform(X[k] - 0.05, X[k] + 0.05, (300, len(PARAMS))))
        assert np.all(low[k] <= inside) and np.all(inside <= high[k])
    point_low, point_high = loaded.space.bounds(X, X)
    assert np.allclose(point_low, values, atol=1e-7) and np.allclose(point_high, values, atol=1e-7)


@pytest.mark.parametrize("change, message", [
    (lambda d: d["expressions"]["features"][0].update(expression=["system", "x"]), "unknown operator"),
    (lambda d: d["expressions"]["features"][0].update(expression="theta"), "not a parameter"),
    (lambda d: d["expressions"]["features"][0].update(expression=["dubins", "x", "xg", "h", "h", -0.4]),
     "positive constant"),
    (lambda d: d["expressions"]["features"][0].update(expression=["dubins", "x", "xg", "h", 0.4]),
     "takes 5 arguments"),
    (lambda d: d["expressions"]["features"][0].update(
        expression=["dubins_inside", "x", "v", "h", "xg", "vg", "h", 0.4, 1.0, -1.0, -2.0, 2.0]), "xmin < xmax"),
    (lambda d: d["expressions"].update(features=[]), "1 to 32"),
    (lambda d: d["expressions"].update(parameters="x"), "parameter names"),
    (lambda d: d["expressions"]["features"][1].update(name="f0"), "distinct"),
    (lambda d: d["expressions"]["features"][0].update(name="a b; rm"), "not a name"),
    (lambda d: d.update(feature_names=["g0", "g1"]), "do not match"),
    (lambda d: d.update(feature_space="line"), "names its feature space 'auto'"),
    (lambda d: d.pop("expressions"), "without its 'expressions'"),
])
def test_a_hostile_or_malformed_model_file_is_one_line_naming_it(tmp_path, change, message):
    data = _model(space(["abs", ["sub", "xg", "x"]], ["sub", "v", "vg"])).to_json()
    change(data)
    with pytest.raises(ModelFileError, match=message) as caught:
        ActionModel.from_json(json.loads(json.dumps(data)), str(tmp_path / "move.json"))
    assert str(caught.value).startswith(str(tmp_path / "move.json")) and "\n" not in str(caught.value)


def test_parameters_of_another_shape_are_a_model_file_error():
    model = _model(space(["abs", ["sub", "xg", "x"]]))
    with pytest.raises(ModelFileError, match="parameters of shape"):
        model.features(np.zeros((3, 4)))


# --- interval bounds: every operator, every box, checked against dense sampling -----------------------------
LEAVES = st.one_of(st.sampled_from(PARAMS).map(param),
                   st.floats(-3, 3, allow_nan=False).map(lambda v: const(round(v, 3))))


def _grow(children):
    unary = st.tuples(st.sampled_from([op for op, n in ARITY.items() if n == 1]), children).map(
        lambda t: node(t[0], t[1]))
    binary = st.tuples(st.sampled_from([op for op, n in ARITY.items() if n == 2]), children, children).map(
        lambda t: node(t[0], t[1], t[2]))
    moving = st.tuples(children, children, children, st.floats(0.1, 3), st.floats(0.1, 3)).map(
        lambda t: node("transfer", t[0], t[1], t[2], const(t[3]), const(t[4])))
    path = st.tuples(st.sampled_from(["dubins", "dubins_arcs"]), children, children, children, children,
                     st.floats(0.05, 2)).map(lambda t: node(t[0], *t[1:5], const(t[5])))
    inside = st.tuples(st.sampled_from(["dubins_inside", "dubins_inside_arcs"]), st.tuples(*[children] * 6),
                       st.floats(0.05, 2), st.floats(0.5, 6), st.floats(0.5, 6)).map(
        lambda t: node(t[0], *t[1], const(t[2]), const(-t[3]), const(t[3]), const(-t[4]), const(t[4])))
    return st.one_of(unary, binary, moving, path, inside)


EXPRESSIONS = st.recursive(LEAVES, _grow, max_leaves=8)


def _boxes(rng: np.random.Generator, k: int) -> tuple[np.ndarray, np.ndarray]:
    centre = rng.uniform(-4, 4, (k, len(PARAMS)))
    width = rng.choice([0.0, 1e-9, 0.01, 0.5, 3.0, 8.0], (k, len(PARAMS)))
    return centre - width / 2, centre + width / 2


def _samples(low: np.ndarray, high: np.ndarray, rng: np.random.Generator, n: int) -> np.ndarray:
    """n points of the box: its corners, its centre and uniform draws."""
    corners = np.array([[low[j] if (c >> j) & 1 else high[j] for j in range(len(low))]
                        for c in range(2 ** len(low))])
    return np.vstack([corners, (low + high) / 2, rng.uniform(low, high, (n, len(low)))])


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(EXPRESSIONS, st.integers(0, 2 ** 32 - 1))
def test_bounds_enclose_every_value_over_every_box(expression: Expr, seed: int):
    s = ExpressionSpace(PARAMS, ("f",), (expression,))
    rng = np.random.default_rng(seed)
    low, high = _boxes(rng, 4)
    f_low, f_high = s.bounds(low, high)
    assert f_low.shape == f_high.shape == (4, 1)
    for k in range(4):
        values = s.compute(_samples(low[k], high[k], rng, 400))[:, 0]
        finite = values[np.isfinite(values)]
        assert np.all(f_low[k, 0] <= finite) and np.all(finite <= f_high[k, 0]), (expression.formula(), k)


@pytest.mark.parametrize("op", sorted(ARITY))
def test_each_operator_alone_is_enclosed_densely(op: str):
    rng = np.random.default_rng(sum(map(ord, op)))
    n = ARITY[op] - len(CONSTANT_ARGUMENTS.get(op, ()))
    for _ in range(200):
        centre = rng.uniform(-7, 7, n) * rng.choice([1e-3, 1.0, 10.0], n)
        width = rng.choice([0.0, 1e-6, 0.3, 2.0, 7.0], n)
        low, high = centre - width / 2, centre + width / 2
        constants = tuple(float(rng.uniform(0.2, 2)) for _ in CONSTANT_ARGUMENTS.get(op, ()))
        if op in REGION_ARGUMENTS:  # a radius and a region (xmin, xmax, ymin, ymax) about the positions
            a, b = rng.uniform(1.0, 8.0, 2)
            constants = (constants[0], -a, a, -b, b)
        lo, hi = interval(op, [(np.array([a]), np.array([b])) for a, b in zip(low, high)], constants)
        points = _samples(low, high, rng, 300)
        values = evaluate(op, [points[:, j] for j in range(n)], constants)
        assert np.all(lo[0] <= values) and np.all(values <= hi[0]), (op, low, high)


@pytest.mark.parametrize("op", ["transfer", "dubins", "dubins_arcs", "dubins_inside", "dubins_inside_arcs"])
def test_times_and_paths_are_enclosed_exactly_at_a_point(op: str):
    """The certified optimizer splits boxes down to points and refuses an enclosure wider there than 1e-6
    relative (optimizers.certified._check_tight): a generated space whose transfer or path bound stayed wide at a
    point could never be certified."""
    rng = np.random.default_rng(5)
    n = ARITY[op] - len(CONSTANT_ARGUMENTS[op])
    points = rng.uniform(-4, 4, (500, n))
    constants = {"transfer": (0.8, 1.5), "dubins": (0.4,), "dubins_arcs": (0.4,)}.get(op, (0.4, -3.0, 3.0, -2.0, 2.0))
    values = evaluate(op, list(points.T), constants)
    lo, hi = interval(op, [(points[:, j], points[:, j]) for j in range(n)], constants)
    assert np.all(lo <= values) and np.all(values <= hi)
    assert np.all(hi - lo <= 1e-6 * (1.0 + np.abs(values)))


def test_bounds_of_angles_are_tight_where_they_can_be_and_whole_where_not():
    s = space(["wrap", "h"], ["atan2", "x", "xg"], ["sin", "h"])
    low = np.array([[0, 0, 0, 0, 0.1], [-1, 0, -1, 0, 3.0], [1, 0, 1, 0, -10.0]], dtype=float)
    high = np.array([[0, 0, 0, 0, 0.2], [1, 0, 1, 0, 3.5], [2, 0, 2, 0, 10.0]], dtype=float)
    f_low, f_high = s.bounds(low, high)
    assert np.allclose([f_low[0, 0], f_high[0, 0]], [0.1, 0.2])  # within one turn: exact
    assert np.allclose([f_low[1, 0], f_high[1, 0]], [-np.pi, np.pi], atol=1e-9)  # across the seam: all
    assert np.allclose([f_low[1, 1], f_high[1, 1]], [-np.pi, np.pi], atol=1e-9)  # holds the origin: all
    assert f_low[2, 1] > 0.4 and f_high[2, 1] < 1.2  # away from the origin: the corners'
    assert np.allclose([f_low[2, 2], f_high[2, 2]], [-1, 1])


def test_refine_with_a_hostile_model_file_is_one_line_and_exit_12(tmp_path, capsys):
    from tailor.cli.main import main
    from tailor.planner_bridge.bundled import DOMAINS_DIR

    data = json.loads((DOMAINS_DIR / "arm" / "models" / "reach.json").read_text())
    data["feature_space"] = "auto"
    data["expressions"] = {"parameters": ["theta_a", "omega_a", "theta_b", "omega_b", "theta_ga", "omega_ga",
                                          "theta_gb", "omega_gb"],
                           "features": [{"name": "f", "expression": ["__import__", "os"]}]}
    models = tmp_path / "models"
    models.mkdir()
    (models / "reach.json").write_text(json.dumps(data))
    problem = sorted((DOMAINS_DIR / "arm" / "problems").glob("*.pddl"))[0].stem
    assert main(["refine", "arm", problem, "--models", str(models)]) == 12
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "reach.json" in err and "unknown operator '__import__'" in err


def test_a_fitted_number_takes_the_unit_its_place_asks_for():
    """A distance fitted behind a pose is metres where it is subtracted from metres; metres plus radians stays
    unknown."""
    units = units_of(UNITS)
    behind = ["hypot", ["sub", ["sub", "xg", "x"], ["mul", 0.942, ["cos", "h"]]], ["mul", 0.942, ["sin", "h"]]]
    assert format_unit(unit_of(from_json(behind, PARAMS), units)) == "m"
    assert format_unit(unit_of(from_json(["mul", 2.0, "x"], PARAMS), units)) == "m"
    assert format_unit(unit_of(from_json(["add", "x", "h"], PARAMS), units)) == "?"
    assert format_unit(unit_of(from_json(["add", ["mul", 2.0, "x"], "v"], PARAMS), units)) == "m/s"  # 2 in 1/s
