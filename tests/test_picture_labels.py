"""Issue 32, "Pictures": labels and units from the simulator's declared quantities, shared axes where panels
compare, complete legends, no text over markers, the polar radius from near the minimum, and panel titles that
say what each execution is. Each test draws the figure the command draws (through `draw_refinement`, the
training and coordination plot functions, `draw_run`) from synthetic trajectories and stub models, so nothing
is simulated or trained."""

from __future__ import annotations

import functools
import math
from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib.lines import Line2D
from matplotlib.patches import Circle
from matplotlib.transforms import Bbox

from tailor.planner_bridge import plan_files, resolve_problem
from tailor.refinement import refine_plots
from tailor.refinement.belief import load_belief
from tailor.refinement.binding import load_domain_binding
from tailor.refinement.instantiate import instantiate
from tailor.sims import registry
from tailor.sims.episode import ActionResult, SequenceResult
from tailor.sims.kitchen import world as W


@functools.cache
def _sequence(domain: str, problem: str):
    domain_file, path = resolve_problem(domain, problem)
    return instantiate(plan_files(domain_file, path), load_domain_binding(domain_file.parent),
                       load_belief(path.with_suffix(".toml")))


def _run(columns: tuple[str, ...], waypoints: list[dict[str, float]], actions: list[str]) -> SequenceResult:
    """A trajectory at 10 Hz through `waypoints` (column -> value), one straight segment of 1 s per action
    (an action that stays puts the same waypoint twice), every action a success."""
    rows, results = [], []
    for k, action in enumerate(actions):
        a, b = waypoints[k], waypoints[k + 1]
        for s in np.linspace(0.0, 1.0, 11)[(1 if k else 0):]:
            rows.append([k + s] + [a.get(c, 0.0) + s * (b.get(c, 0.0) - a.get(c, 0.0)) for c in columns[1:]])
        results.append(ActionResult(action, "success", 1.0, float(k)))
    return SequenceResult(tuple(results), np.array(rows), columns)


def _outcome(bound, simulated: SequenceResult, horizon: int, predicted: float):
    return SimpleNamespace(refined=SimpleNamespace(sequence=bound, horizon=horizon, predicted_total=predicted),
                           simulated=simulated)


class _Stub:
    """A duration model predicting `base + swing * cos(parameter)` of one of its action's parameters."""

    def __init__(self, index: int, base: float = 2.35, swing: float = 0.25):
        self.index, self.base, self.swing = index, base, swing

    def predict_duration(self, rows):
        return self.base + self.swing * np.cos(np.asarray(rows)[:, self.index])


def _draw(monkeypatch, tmp_path, sequence, outcomes, models=None):
    """The figures `draw_refinement` draws (executions, then the predicted time over a free parameter)."""
    figures = []

    def keep(fig, path):
        fig.canvas.draw()
        figures.append(fig)

    monkeypatch.setattr(refine_plots, "_save", keep)
    prepared = SimpleNamespace(sequence=sequence, models=models or {})
    entry = registry.get(sequence.simulator)
    refine_plots.draw_refinement(tmp_path / "F.png", prepared, outcomes, entry.views)
    return figures


def _soccer(monkeypatch, tmp_path):
    sequence = _sequence("soccer", "score")
    free = {p.id: p for p in sequence.free_parameters()}
    greedy = sequence.bind({"pos2.phi": 0.0, "pos2.v": 0.0})
    refined = sequence.bind({"pos2.phi": 1.2, "pos2.v": 0.2})
    columns = ("t", "x", "y", "phi", "v", "ball_x", "ball_y")
    start, ball, goal = {"x": 0.0, "y": 1.0}, {"ball_x": 3.0, "ball_y": 1.0}, {"ball_x": 1.1, "ball_y": 2.9}
    straight = _run(columns, [{**start, **ball}, {"x": 2.9, "y": 1.0, **ball}, {"x": 1.0, "y": 2.9, **goal}],
                    ["goToPose", "dribbleBall"])
    curved = _run(columns, [{**start, **ball}, {"x": 2.5, "y": 0.2, "phi": 1.2, **ball},
                            {"x": 1.0, "y": 2.9, **goal}], ["goToPose", "dribbleBall"])
    models = {a.action: _Stub([p.id for p in a.params].index("pos2.phi")) for a in sequence.actions}
    assert free["pos2.phi"].high - free["pos2.phi"].low > 6.28  # a full circle: the polar plot
    outcomes = {"greedy": _outcome(greedy, straight, 1, 5.0), "refined": _outcome(refined, curved, 2, 4.8)}
    return _draw(monkeypatch, tmp_path, sequence, outcomes, models)


def _arm(monkeypatch, tmp_path, zero: bool = True):
    sequence = _sequence("arm", "letter-f")
    values = {p.id: 0.5 for p in sequence.free_parameters()}
    columns = ("t", "theta_a", "omega_a", "theta_b", "omega_b", "tip_x", "tip_y")
    points = [{"theta_a": -1.3 + 0.1 * k, "theta_b": 2.1 - 0.1 * k, "tip_x": 0.4 + 0.02 * k * (k % 2),
               "tip_y": -0.15 + 0.05 * k} for k in range(len(sequence.actions) + 1)]
    wide = [{**p, "tip_x": p["tip_x"] + 0.1, "theta_b": p["theta_b"] - 0.3} for p in points]
    actions = [a.action for a in sequence.actions]
    outcomes = {"greedy": _outcome(sequence.bind(values), _run(columns, points, actions), 1, 4.7),
                "refined": _outcome(sequence.bind(values), _run(columns, wide, actions), 2, 3.9)}
    if zero:
        bound = sequence.bind({p.id: 0.0 for p in sequence.free_parameters()})
        outcomes = {"zero": _outcome(bound, _run(columns, points, actions), 0, 5.5), **outcomes}
    models = {"reach": _Stub(1)}
    return _draw(monkeypatch, tmp_path, sequence, outcomes, models)


def _kitchen(monkeypatch, tmp_path, problem: str, choose):
    """The executions of a kitchen problem where every spot's free parameters take `choose(parameter)`, the
    robot driving straight from spot to spot (the subgoals reached at the chosen positions)."""
    sequence = _sequence("kitchen", problem)
    values = {p.id: choose(p) for p in sequence.free_parameters()}
    bound = sequence.bind(values)
    columns = ("t", "x", "y", "phi")
    robot = sequence.scene["robot"]
    points = [{"x": robot[0], "y": robot[1], "phi": robot[2]}]
    for action in bound.actions:
        spot = {p.id.partition(".")[2]: p.value for p in action.params[len(action.params) // 2:]}
        if action.action == "navigate":
            x, y, phi = W.spot_pose(spot["ox"], spot["oy"], spot["ophi"], spot["along"], spot["dist"],
                                    spot["heading"])
            points.append({"x": x, "y": y, "phi": phi})
        else:
            points.append(points[-1])
    run = _run(columns, points, [a.action for a in sequence.actions])
    models = {a: _Stub(0, 10.0, 1.0) for a in ("navigate", "grip", "put")}
    outcomes = {"greedy": _outcome(bound, run, 1, 40.0), "refined": _outcome(bound, run, 2, 35.0)}
    return _draw(monkeypatch, tmp_path, sequence, outcomes, models)


def _series(ax) -> set[str]:
    return {label for label in ax.get_legend_handles_labels()[1] if not label.startswith("_")}


def _legend(ax) -> list[str]:
    legend = ax.get_legend()
    return [t.get_text() for t in legend.get_texts()] if legend is not None else []


# --- labels and units -------------------------------------------------------------------------------------------
def test_execution_axes_carry_the_units_the_simulator_declares(monkeypatch, tmp_path):
    """Raw column names without units ("x", "tip_x") were the axis labels."""
    soccer = _soccer(monkeypatch, tmp_path)[0]
    assert {(ax.get_xlabel(), ax.get_ylabel()) for ax in soccer.axes[:1]} == {("x (m)", "y (m)")}
    assert all(ax.get_xlabel() == "x (m)" for ax in soccer.axes[:2])
    arm = _arm(monkeypatch, tmp_path)[0]
    tip, joints = arm.axes[0], arm.axes[3]  # the first panel of each row (3 executions: zero, greedy, refined)
    assert (tip.get_xlabel(), tip.get_ylabel()) == ("tip_x (m)", "tip_y (m)")
    assert (joints.get_xlabel(), joints.get_ylabel()) == ("theta_a (rad)", "theta_b (rad)")


def test_execution_legends_name_what_is_drawn_not_its_columns(monkeypatch, tmp_path):
    """The legend said "x, y" and "ball_x, ball_y": it names the declared scene objects, the robot and the ball,
    and the heading arrows."""
    fig = _soccer(monkeypatch, tmp_path)[0]
    for ax in fig.axes:
        legend = _legend(ax)
        assert {"robot", "ball", "robot heading (phi)", "start", "subgoals reached"} <= set(legend)
        assert not {"x, y", "ball_x, ball_y"} & set(legend)


def test_a_polar_radius_carries_its_unit(monkeypatch, tmp_path):
    polar = _soccer(monkeypatch, tmp_path)[1]
    for ax in polar.axes:
        labels = [t.get_text() for t in ax.get_yticklabels() if t.get_text()]
        assert labels and all(label.endswith(" s") for label in labels)


def test_coordination_positions_carry_their_units(monkeypatch):
    from tailor.refinement.evaluation import coordination_plots

    figures = []
    monkeypatch.setattr(coordination_plots, "_save", lambda fig, path: figures.append(fig))
    scene = registry.get("soccer").team
    rng = np.random.default_rng(0)
    targets = rng.uniform([scene.bounds[0], scene.bounds[2]], [scene.bounds[1], scene.bounds[3]], (12, 2))
    report = {"simulator": "soccer", "dynamic": {"failure_tree": None},
              "example": {"robots": [[-2.0, 0.5, 0.3, 0.0], [1.5, -1.0, 2.0, 0.0]], "targets": targets.tolist(),
                          "kinds": list(scene.kinds)[:1] * 2, "predicted_failure": [k % 3 == 0 for k in range(12)],
                          "chosen": [k % 2 for k in range(12)], "runner_up": [(k + 1) % 2 for k in range(12)]}}
    coordination_plots.plot_failure_example(report, scene.bounds, None)
    ax = figures[0].axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("x (m)", "y (m)")
    assert len(_legend(ax)) == 4  # the robots, the targets, who goes, predicted confusion


def test_the_executed_run_labels_each_axis_with_its_own_unit(monkeypatch, tmp_path):
    import matplotlib.pyplot as plt

    from tailor.cli import execute_plot

    figures = []
    real = plt.subplots
    monkeypatch.setattr(plt, "subplots", lambda *a, **k: figures.append(real(*a, **k)) or figures[-1])
    columns = ("x", "y", "phi", "v", "ball_x", "ball_y")
    log = SimpleNamespace(columns=columns, column=lambda name: np.linspace(0.0, 1.0 + columns.index(name), 5))
    events = [SimpleNamespace(kind="executed", log=log, simulator="soccer", outcome="success",
                              pddl="(gotopose pos1 pos2)", measured=3.2),
              SimpleNamespace(kind="finished", log=None, outcome="success")]
    execute_plot.draw_run(events, "soccer", tmp_path / "E.png")
    ax = figures[0][1]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("x (m)", "y (m)")


# --- shared axes and complete legends ---------------------------------------------------------------------------
@pytest.mark.parametrize("draw", [_soccer, _arm])
def test_the_panels_of_one_view_share_their_axes(draw, monkeypatch, tmp_path):
    """Greedy and refined executions of different extents were drawn on different scales."""
    fig = draw(monkeypatch, tmp_path)[0]
    rows = {}
    for ax in fig.axes:
        rows.setdefault(round(ax.get_subplotspec().rowspan.start), []).append(ax)
    for axes in rows.values():
        assert len(axes) > 1
        assert all(np.allclose(ax.get_xlim(), axes[0].get_xlim()) for ax in axes)
        assert all(np.allclose(ax.get_ylim(), axes[0].get_ylim()) for ax in axes)


@pytest.mark.parametrize("draw", [_soccer, _arm])
def test_every_panel_with_several_series_names_them_all(draw, monkeypatch, tmp_path):
    """Only the first panel of each row had a legend."""
    fig = draw(monkeypatch, tmp_path)[0]
    for ax in fig.axes:
        series = _series(ax)
        assert len(series) > 1 and set(_legend(ax)) == series


def test_the_kitchen_legend_names_its_scene(monkeypatch, tmp_path):
    fig = _kitchen(monkeypatch, tmp_path, "scenario1", lambda p: (p.low + p.high) / 2)[0]
    for ax in fig.axes:
        legend = set(_legend(ax))
        assert legend == _series(ax)
        assert {"robot", "table", "cup", "put location", "spot's along, dist range", "spot's heading range",
                "chosen heading"} <= legend


def test_the_training_polar_panel_names_its_curves(monkeypatch):
    from tailor.refinement.learning import plots

    figures = []
    monkeypatch.setattr(plots, "_save", lambda fig, target, layout=True: figures.append(fig))
    curve = next(p for p in registry.get("soccer").model_pictures if isinstance(p, plots.DurationCurve))
    names = ("x", "y", "phi", "v", "xg", "yg", "phig", "vg")
    models = {action: SimpleNamespace(space=SimpleNamespace(parameters=names),
                                      predict_duration=_Stub(names.index("phig"), base, 0.25).predict_duration)
              for action, base in (("approachBall", 2.35), ("goToPose", 2.6))}
    plots.plot_duration_curve(curve, models, None)
    cartesian, polar = figures[0].axes
    assert set(_legend(cartesian)) == set(_legend(polar)) == set(models)
    assert polar.get_ylim()[0] > 0.8 * 2.1  # and the radius from near the shortest prediction (2.1 s)


# --- polar radius ------------------------------------------------------------------------------------------------
def test_the_polar_radius_starts_near_the_minimum(monkeypatch, tmp_path):
    """A 2.1-2.6 s variation drawn from a radius of 0 looked like a circle."""
    polar = _soccer(monkeypatch, tmp_path)[1]
    for ax in polar.axes:
        values = np.concatenate([line.get_ydata() for line in ax.get_lines() if len(line.get_ydata()) > 2])
        low, high = float(values.min()), float(values.max())
        lower, upper = ax.get_ylim()
        assert low - 0.25 * (upper - low) <= lower <= low  # near the minimum, nothing cut
        assert (high - low) / (upper - lower) > 0.5  # the variation fills most of the radius
        labels = [t.get_text() for t in ax.get_yticklabels() if t.get_text()]
        assert labels[0] == f"{lower:.4g} s"  # the rim of the hole says where the radius starts


def test_polar_limits_keep_zero_where_the_values_start_near_it():
    assert refine_plots.polar_limits(0.2, 10.0)[0] == 0.0
    lower, upper = refine_plots.polar_limits(2.1, 2.6)
    assert 1.9 < lower < 2.1 and upper >= 2.6


# --- titles ------------------------------------------------------------------------------------------------------
def test_the_zero_baseline_panel_says_what_it_is(monkeypatch, tmp_path):
    """The arm's first panel was titled "free parameters 0", which reads as "there are none"."""
    fig = _arm(monkeypatch, tmp_path)[0]
    titles = [ax.get_title() for ax in fig.axes[:3]]
    assert not any("free parameters 0" in t for t in titles)
    assert titles[0].startswith("zero baseline: every free parameter set to 0\npredicted 5.50 s")
    assert titles[1].startswith("greedy (h=1)\n") and titles[2].startswith("refined (h=2)\n")


def test_a_plan_without_free_parameters_is_one_panel_saying_so(monkeypatch, tmp_path):
    """With nothing to choose, greedy and refined are one plan: one panel, titled so."""
    sequence = _sequence("soccer", "score").bind({"pos2.phi": 0.0, "pos2.v": 0.0})
    assert not sequence.free_parameters()
    columns = ("t", "x", "y", "phi", "v", "ball_x", "ball_y")
    run = _run(columns, [{"x": 0.0, "y": 1.0}, {"x": 2.9, "y": 1.0}, {"x": 1.0, "y": 2.9}],
               ["goToPose", "dribbleBall"])
    outcomes = {"greedy": _outcome(sequence, run, 1, 5.0), "refined": _outcome(sequence, run, 2, 5.0)}
    figures = _draw(monkeypatch, tmp_path, sequence, outcomes)
    assert len(figures) == 1 and len(figures[0].axes) == 1
    assert figures[0].axes[0].get_title().startswith("no free parameters: greedy and refined are the same plan\n")


# --- no text over markers ----------------------------------------------------------------------------------------
def _renderer(fig):
    """The figure drawn again (a closed figure has lost its Agg canvas), and its renderer."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    if not isinstance(fig.canvas, FigureCanvasAgg):
        FigureCanvasAgg(fig)
    fig.canvas.draw()
    return fig.canvas.get_renderer()


def _marker_boxes(fig, ax) -> list[Bbox]:
    """Where each marker of the panel is drawn (its full size, in pixels), and each cup."""
    renderer = _renderer(fig)
    boxes = []
    for line in ax.get_lines():
        if not isinstance(line, Line2D) or line.get_marker() in (None, "None", "", " "):
            continue
        half = (line.get_markersize() + line.get_markeredgewidth()) * fig.dpi / 72.0 / 2.0
        points = np.column_stack([line.get_xdata(), line.get_ydata()]).astype(float)
        for x, y in ax.transData.transform(points[np.isfinite(points).all(axis=1)]):
            boxes.append(Bbox.from_extents(x - half, y - half, x + half, y + half))
    boxes += [p.get_window_extent(renderer) for p in ax.patches if isinstance(p, Circle)]
    return boxes


def _text_boxes(fig, ax) -> list[tuple[str, Bbox]]:
    renderer = _renderer(fig)
    out = []
    for text in ax.texts:
        if not text.get_text():
            continue
        box = text.get_window_extent(renderer)
        if text.get_bbox_patch() is not None:
            box = Bbox.union([box, text.get_bbox_patch().get_window_extent(renderer)])
        out.append((text.get_text(), box))
    return out


CHOICES = {
    "middle": lambda p: (p.low + p.high) / 2,
    "low": lambda p: p.low,
    "high": lambda p: p.high,
    "near the table, at one side": lambda p: {"dist": p.low, "along": p.high}.get(p.id.partition(".")[2],
                                                                                   min(max(0.0, p.low), p.high)),
    "far, at the other side": lambda p: {"dist": p.high, "along": p.low}.get(p.id.partition(".")[2], min(1.0, p.high)),
}


@pytest.mark.parametrize("problem", ["scenario1", "scenario2"])
@pytest.mark.parametrize("choice", list(CHOICES))
def test_no_kitchen_name_covers_a_marker(problem, choice, monkeypatch, tmp_path):
    """Table names were written across cups and put locations, spot names across the subgoals reached."""
    fig = _kitchen(monkeypatch, tmp_path, problem, CHOICES[choice])[0]
    for ax in fig.axes:
        texts, markers = _text_boxes(fig, ax), _marker_boxes(fig, ax)
        assert {"table1", "table2", "p1", "d1"} <= {name for name, _ in texts}
        covered = [name for name, box in texts if any(box.overlaps(m) for m in markers)]
        assert covered == []


def test_the_kitchen_names_stay_inside_the_panel(monkeypatch, tmp_path):
    fig = _kitchen(monkeypatch, tmp_path, "scenario1", CHOICES["middle"])[0]
    for ax in fig.axes:
        frame = ax.get_window_extent(_renderer(fig))
        for name, box in _text_boxes(fig, ax):
            assert frame.x0 <= box.x0 and box.x1 <= frame.x1 and frame.y0 <= box.y0 and box.y1 <= frame.y1, name


def test_spot_names_stand_apart_at_a_shared_table_edge():
    """Two spots at one table edge (scenario2's p1 and p2) are named on opposite sides."""
    from tailor.sims.kitchen.drawing import _side

    here, there = (2.0, 5.3, math.pi / 2), (2.25, 5.3, math.pi / 2)
    assert _side(here, [here, there]) == -_side(there, [here, there])
    assert _side(here, [here]) == 1.0
