"""Pictures of subgoal refinement: the executions side by side in each view the simulator declares (Fig. 5.1:
one view from above; Fig. 5.14: two views, one in the plane, one of two configuration quantities), the
predicted time over the first free parameter (Fig. 5.8: a polar plot where the simulator declares that
parameter's quantity an angle and its range spans the full circle), and, at the first way-point whose angle of
approach and speed are both free, the predicted time of the action arriving there, of the one leaving it and
their sum over both (Fig. 5.9)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tailor.sims import registry
from tailor.sims.protocol import UNDECLARED, Quantity, SimulatorEntry

FULL_CIRCLE = 2 * np.pi - 1e-9
LAYER_STYLES = (("-", "tab:blue"), ("--", "tab:orange"), (":", "tab:green"))
LEGEND_DROP = 30  # points from the bottom of a panel to the top of its legend (below the axis label)
LEGEND_SHORT = 24  # characters: up to 6 labels no longer than this fit 3 columns under a panel; others 2


def _save(fig, path: Path) -> None:
    """Write the figure atomically, with the permissions of a new file: a reader never sees half a PNG."""
    from tailor.outputs import write_atomically

    write_atomically(path, lambda tmp: fig.savefig(tmp, dpi=110, bbox_inches="tight", format="png"))


def view_layers(view) -> tuple[tuple[str, ...], ...]:
    """A simulator view as layers: ("x", "y") is one layer; (("x", "y", "phi"), ("bx", "by")) two, the third
    name of a layer a heading drawn as arrows."""
    return (tuple(view),) if isinstance(view[0], str) else tuple(tuple(layer) for layer in view)


def subgoal_rows(result) -> list[int]:
    """Trajectory rows where each action of a dispatched sequence ended (the subgoals it reached)."""
    t = result.column("t")
    ends = [r.start + r.duration for r in result.results]
    return [int(np.argmin(np.abs(t - end))) for end in ends] if len(t) else []


def axis_label(name: str, quantity: Quantity = UNDECLARED) -> str:
    """An axis label of a quantity or column as its simulator declares it: "x (m)"; the bare name where no unit
    is declared."""
    return f"{name} ({quantity.unit})" if quantity.unit else name


def layer_label(layer, entry: SimulatorEntry | None = None) -> str:
    """What a view layer draws, for a legend: the scene object the simulator declares whose name prefixes the
    layer's columns ("box" for box_x, box_y), else its first scene object (the robot, whose own state the
    other columns are); the column names where it declares no scene objects."""
    objects = [name.split(" ")[0] for name in (entry.scene_objects if entry is not None else ())]
    for name in objects:
        if all(column.startswith(name + "_") for column in layer[:2]):
            return name
    return objects[0] if objects else ", ".join(layer[:2])


def _draw(ax, result, layers, title: str, entry: SimulatorEntry | None = None) -> None:
    marks = subgoal_rows(result)
    for k, layer in enumerate(layers):
        if not all(result.has_column(c) for c in layer[:2]):
            continue
        style, color = LAYER_STYLES[k % len(LAYER_STYLES)]
        x, y = result.column(layer[0]), result.column(layer[1])
        if not np.isfinite(x).any():
            continue
        name = layer_label(layer, entry)
        ax.plot(x, y, style, color=color, lw=1.5, label=name)
        ax.plot(x[:1], y[:1], "o", color=color, ms=8, mec="black", mew=0.6, zorder=4,
                label="start" if k == 0 else f"{name} at the start")
        if len(layer) > 2 and result.has_column(layer[2]):
            heading, step = result.column(layer[2]), max(1, len(x) // 25)
            ax.quiver(x[::step], y[::step], np.cos(heading[::step]), np.sin(heading[::step]), color=color,
                      scale=25, width=0.004, alpha=0.6)
            ax.plot([], [], linestyle="none", marker=r"$\rightarrow$", ms=10, color=color, alpha=0.6,
                    label=f"{name} heading ({layer[2]})")  # the arrows' legend entry
        if k == 0 and marks:
            ax.plot(x[marks], y[marks], "x", color="k", ms=8, mew=2, zorder=5, label="subgoals reached")
    across, up = _quantity(entry, layers[0][0]), _quantity(entry, layers[0][1])
    if across.unit == up.unit:  # a plane (x, y in m; two joint angles): one scale; not time against position
        ax.set_aspect("equal", adjustable="box")  # (box: the panels of a row share their limits)
    ax.grid(alpha=0.3)
    ax.set_title(title, fontsize=10)
    ax.set_xlabel(axis_label(layers[0][0], across))
    ax.set_ylabel(axis_label(layers[0][1], up))


def _legend(ax, scene: tuple[str, ...] = ()) -> None:
    """Every series of a panel named once (a scene draws several objects of one kind), the trajectories' before
    the `scene`'s, below the axes where it covers nothing."""
    from matplotlib.transforms import offset_copy

    handles, labels = ax.get_legend_handles_labels()
    unique = dict(zip(labels, handles))
    order = sorted(unique, key=lambda label: label in scene)  # (stable: each group in the order drawn)
    if len(unique) > 1:  # (anchored in points below the axes: clear of the axis label whatever the panel's height)
        below = offset_copy(ax.transAxes, fig=ax.figure, y=-LEGEND_DROP, units="points")
        short = len(order) <= 6 and max(map(len, order)) <= LEGEND_SHORT
        ax.legend([unique[label] for label in order], order, loc="upper center", bbox_to_anchor=(0.5, 0.0),
                  bbox_transform=below, ncol=3 if short else 2, fontsize=8, frameon=False)


def plot_executions(path: Path, views, panels: list[tuple[str, object]], background=None,
                    entry: SimulatorEntry | None = None) -> None:
    """One row per view, one column per (title, SequenceResult), written to `path`; `background(ax, column)`
    draws under the first view's trajectories (the simulator's draw_scene); units and names as `entry`
    declares them."""
    import matplotlib.pyplot as plt

    fig = executions_figure(views, panels, background, entry)
    _save(fig, path)
    plt.close(fig)


def executions_figure(views, panels: list[tuple[str, object]], background=None, entry: SimulatorEntry | None = None):
    """The figure of `plot_executions`: a start marker and the subgoals reached in each panel; the panels of a
    row (the same view of each execution) share their axes; each panel its legend, axes labelled with the units
    `entry` declares."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    views = list(views) or [("t", "t")]
    fig, axes = plt.subplots(len(views), len(panels), figsize=(5.5 * len(panels), 5.2 * len(views)), squeeze=False,
                             sharex="row", sharey="row")
    for row, view in enumerate(views):
        for col, (title, result) in enumerate(panels):
            scene = ()
            if row == 0 and background is not None:
                background(axes[row, col], col)
                scene = tuple(axes[row, col].get_legend_handles_labels()[1])
            _draw(axes[row, col], result, view_layers(view), title if row == 0 else "", entry)
            _legend(axes[row, col], scene)
            if col:
                axes[row, col].set_ylabel("")  # (the first panel's label, and tick labels, say it)
    fig.subplots_adjust(hspace=0.45)
    return fig


MARK_STYLES = {"greedy": ("s", "tab:orange"), "refined": ("*", "tab:green")}  # marker, colour of a chosen value
POLAR_MARGIN = 1.12  # the radius axis reaches this far beyond the largest value: no marker cut at the rim
POLAR_CENTRE = 0.15  # the centre of polar axes lies this share of the radius range below the smallest value
POLAR_HOLE = 0.12  # radius of the hole of polar axes not starting at 0, as a share of their radius range


def polar_limits(smallest: float, largest: float) -> tuple[float, float]:
    """The radius range of polar axes drawing values from `smallest` to `largest`: from a little below the
    smallest (never below 0), so that a variation small beside the values themselves still shows, to a margin
    beyond the largest (markers at the maximum stay whole)."""
    upper = POLAR_MARGIN * largest if largest > 0 else 1.0
    smallest = min(max(smallest, 0.0), largest) if largest > 0 else 0.0
    lower = smallest - POLAR_CENTRE * (upper - smallest)
    digit = 10.0 ** (np.floor(np.log10(upper - smallest)) - 1) if upper > smallest else 1.0
    return max(0.0, float(np.floor(lower / digit) * digit)), upper  # (rounded down: a short tick label)


def tidy_polar(ax, largest: float, smallest: float = 0.0, unit: str = "s") -> None:
    """Readable polar axes: radius from near `smallest` to a margin beyond `largest` (polar_limits); where that
    is not 0, a small hole at the centre, its rim labelled with the value there (no reader takes the centre for
    0); a few radial ticks with their `unit` in a small font at 112.5 deg (between the 90 and 135 deg angle
    labels), angle labels every 45 deg, small and padded so neighbouring panels do not run into each other."""
    from matplotlib.ticker import FixedLocator, FuncFormatter, MaxNLocator

    lower, upper = polar_limits(smallest, largest)
    ax.set_ylim(lower, upper)
    ticks = [t for t in MaxNLocator(nbins=4).tick_values(lower, upper) if lower <= t <= upper]
    if lower > 0:
        ax.set_rorigin(lower - POLAR_HOLE * (upper - lower))
        ticks = [lower] + [t for t in ticks if t > lower + POLAR_CENTRE * (upper - lower)]  # rim and ticks apart
    ax.yaxis.set_major_locator(FixedLocator(ticks))
    ax.yaxis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:.4g} {unit}".strip()))
    ax.set_rlabel_position(112.5)
    ax.tick_params(axis="y", labelsize=7, labelcolor="0.35")
    ax.tick_params(axis="x", labelsize=8, pad=1)
    ax.grid(alpha=0.4)


def on_the_circle(parameter, quantity: Quantity) -> bool:
    """Whether a free parameter is drawn on polar axes: its quantity is an angle and its range the full circle."""
    return quantity.angle and parameter.high - parameter.low >= FULL_CIRCLE


def plot_costs(path: Path, parameter, values: np.ndarray, curves: list[tuple[str, np.ndarray]],
               marks: list[tuple[str, float]], note: str = "", quantity: Quantity = UNDECLARED) -> None:
    """Predicted duration over one free parameter, one panel per curve, written to `path`; `note` under them."""
    import matplotlib.pyplot as plt

    fig = costs_figure(parameter, values, curves, marks, quantity)
    if note:
        fig.supxlabel(note, fontsize=8)
    _save(fig, path)
    plt.close(fig)


def costs_figure(parameter, values: np.ndarray, curves: list[tuple[str, np.ndarray]],
                 marks: list[tuple[str, float]], quantity: Quantity = UNDECLARED):
    """The figure of `plot_costs`: polar where the parameter's `quantity` is an angle and its range spans the
    full circle (Fig. 5.8), Cartesian otherwise (the quantity's unit on the axis); the greedy and refined choices
    marked, each panel with its legend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    polar = on_the_circle(parameter, quantity)
    fig, axes = plt.subplots(1, len(curves), subplot_kw={"projection": "polar"} if polar else {},
                             figsize=(4.6 * len(curves), 5.0), layout="constrained")
    for ax, (title, predicted) in zip(np.atleast_1d(axes), curves):
        ax.plot(values, predicted, color="tab:blue", label="predicted duration (s)")
        if polar:
            tidy_polar(ax, float(np.nanmax(predicted)), float(np.nanmin(predicted)))
        else:
            from matplotlib.ticker import MaxNLocator

            ax.set(xlabel=f"{parameter.id} ({quantity.unit})" if quantity.unit else parameter.id,
                   ylabel="predicted duration (s)")
            ax.xaxis.set_major_locator(MaxNLocator(nbins=5))  # tick labels apart in a narrow panel
            ax.grid(alpha=0.3)
        for label, value in marks:
            k = int(np.argmin(np.abs(values - value)))
            shown = _degrees(value) if polar else f"{value + 0.0:.3g}"  # (a +0.0: never "-0")
            marker, color = MARK_STYLES.get(label, ("o", "tab:red"))
            ax.plot([value], [predicted[k]], marker, color=color, ms=11 if marker == "*" else 8, mec="black",
                    mew=0.6, zorder=4, clip_on=False, linestyle="none",
                    label=f"{label}: {shown}, {predicted[k]:.2f} s")
        ax.set_title(f"{title}\n({parameter.id})" if polar else title, fontsize=10, pad=12)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.08 if polar else -0.14), fontsize=8, frameon=False)
    return fig


def cost_plot_names(path) -> tuple[Path, Path, Path]:
    """The names draw_refinement gives the predicted-time plots beside FILE: FILE_polar.png, FILE_costs.png
    (over one free parameter) and FILE_waypoint.png (Fig. 5.9)."""
    path = Path(path)
    return tuple(path.with_name(path.stem + kind + (path.suffix or ".png"))
                 for kind in ("_polar", "_costs", "_waypoint"))


def is_speed(quantity: Quantity) -> bool:
    """A quantity declared in a unit per second that is not an angle's rate: a speed."""
    return quantity.unit.endswith("/s") and not quantity.angle and not quantity.unit.startswith("rad")


def waypoint_pair(sequence, entry: SimulatorEntry | None) -> tuple[int, object, object] | None:
    """The first way-point of Fig. 5.9 in `sequence`: (index of the action arriving there, the free angle, the
    free speed), where two consecutive actions share a free parameter declared an angle and one declared a speed
    (the angle of approach and the speed at the way-point); None where there is none."""
    actions = sequence.actions
    for k in range(len(actions) - 1):
        shared = {p.id for p in actions[k].free_parameters()} & {p.id for p in actions[k + 1].free_parameters()}
        free = [p for p in actions[k].free_parameters() if p.id in shared]
        angle = next((p for p in free if _quantity(entry, p.id).angle), None)
        speed = next((p for p in free if is_speed(_quantity(entry, p.id))), None)
        if angle is not None and speed is not None:
            return k, angle, speed
    return None


def _degrees(angle: float) -> str:
    return f"{round(float(np.degrees(angle)))}°"  # (an int: never "-0")


def waypoint_figure(angle, speed, grid: tuple[np.ndarray, np.ndarray], panels: list[tuple[str, np.ndarray]],
                    marks: list[tuple[str, float, float]], entry: SimulatorEntry | None = None):
    """Fig. 5.9: one panel per (title, predicted durations over the grid of angle x speed), filled contours with
    a shared colour scale, the greedy and refined choices marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    angles, speeds = grid
    fig, axes = plt.subplots(1, len(panels), figsize=(4.8 * len(panels), 4.6), layout="constrained")
    for ax, (title, predicted) in zip(np.atleast_1d(axes), panels):
        finite = predicted[np.isfinite(predicted)]
        levels = np.linspace(finite.min(), finite.max(), 15) if finite.size and np.ptp(finite) > 0 else 15
        filled = ax.contourf(np.degrees(angles), speeds, predicted.T, levels=levels, cmap="viridis")
        fig.colorbar(filled, ax=ax, label="predicted duration (s)", shrink=0.85)
        best = np.unravel_index(np.nanargmin(predicted), predicted.shape)
        ax.plot(np.degrees(angles[best[0]]), speeds[best[1]], "o", color="white", mec="black", ms=7, clip_on=False,
                zorder=4, label=f"fastest on the grid: {_degrees(angles[best[0]])}, {speeds[best[1]]:.2f}, "
                                f"{predicted[best]:.2f} s")
        for label, a, v in marks:
            marker, color = MARK_STYLES.get(label, ("o", "tab:red"))
            i, j = int(np.argmin(np.abs(angles - a))), int(np.argmin(np.abs(speeds - v)))
            ax.plot(np.degrees(a), v, marker, color=color, ms=11 if marker == "*" else 8, mec="black", mew=0.6,
                    linestyle="none", clip_on=False, zorder=5,
                    label=f"{label}: {_degrees(a)}, {v:.2f}, {predicted[i, j]:.2f} s")
        ax.set(xlabel=f"{angle.id} (°)", ylabel=axis_label(speed.id, _quantity(entry, speed.id)))
        ax.set_title(title, fontsize=10)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), fontsize=8, frameon=False)
    return fig


NO_FREE_PARAMETERS = "no free parameters"  # the one panel of a plan that leaves nothing to choose
PANEL_LABELS = {"greedy": "greedy (h=1)", "zero": "zero baseline: every free parameter set to 0",
                NO_FREE_PARAMETERS: "no free parameters: greedy and refined are the same plan"}


def panel_title(key: str, outcome) -> str:
    """The title of the panel of one execution (greedy, refined, the zero baseline, or the one plan of a sequence
    without free parameters): what it is, then its predicted and simulated time."""
    label = f"refined (h={outcome.refined.horizon})" if key == "refined" else PANEL_LABELS.get(key, key)
    failed = "" if outcome.simulated.succeeded else " (failed)"
    return (f"{label}\npredicted {outcome.refined.predicted_total:.2f} s, simulated {outcome.simulated.duration:.2f} s"
            f"{failed}")


def _quantity(entry: SimulatorEntry | None, name: str) -> Quantity:
    return entry.quantity(name) if entry is not None else UNDECLARED


def draw_refinement(path, prepared, outcomes, views) -> list[Path]:
    """The executions in `outcomes` (greedy, refined, and any other) in each view of the simulator as FILE, the
    predicted time of the first actions over the first free parameter that is a full-circle angle (else the
    first one) as FILE_polar.png (or FILE_costs.png where it is not a full-circle angle), angles as the simulator
    declares them, and Fig. 5.9 at the first way-point with a free angle and speed as FILE_waypoint.png
    (waypoint_pair, draw_waypoint). Returns the files written."""
    path = Path(path)
    if not prepared.sequence.free_parameters():  # nothing to choose: greedy, refined (and zero) are one plan
        outcomes = {NO_FREE_PARAMETERS: outcomes["refined"]}
    panels = [(panel_title(key, o), o.simulated) for key, o in outcomes.items()]
    entry = registry.get(prepared.sequence.simulator) if prepared.sequence.simulator else None
    draw_scene = entry.draw_scene if entry is not None else None
    values_of = {key: {p.id: p.value for a in o.refined.sequence.actions for p in a.params}
                 for key, o in outcomes.items()}
    chosen_values = list(values_of.values())
    background = (None if draw_scene is None
                  else (lambda ax, col: draw_scene(ax, prepared.sequence, chosen_values[col])))
    plot_executions(path, views, panels, background, entry)
    written = [path]
    if "greedy" not in outcomes:  # nothing to choose: no predicted time over a choice
        return written
    chosen, greedy = values_of["refined"], values_of["greedy"]
    if prepared.sequence.actions[0].free_parameters():
        written.append(draw_costs(path, prepared, outcomes["refined"].refined.horizon, chosen, greedy, entry))
    pair = waypoint_pair(prepared.sequence, entry)
    if pair is not None:
        written.append(draw_waypoint(cost_plot_names(path)[2], prepared, pair, chosen, greedy, entry))
    return written


def draw_costs(path: Path, prepared, horizon: int, chosen: dict, greedy: dict, entry: SimulatorEntry | None) -> Path:
    """The predicted time of the first max(2, horizon) actions and their sum over the first action's first free
    parameter that is a full-circle angle (else its first), the others at their refined values, as
    FILE_polar.png or FILE_costs.png beside `path`; returns the file written."""
    free = prepared.sequence.actions[0].free_parameters()
    parameter = next((p for p in free if on_the_circle(p, _quantity(entry, p.id))), free[0])
    window = prepared.sequence.actions[:max(2, horizon)]
    values = np.linspace(parameter.low, parameter.high, 361)
    curves = []
    total = np.zeros_like(values)
    for action in window:
        rows = [action.values({**chosen, parameter.id: float(v)}) for v in values]
        predicted = prepared.models[action.action].predict_duration(np.array(rows))
        total += predicted
        curves.append((f"{action.step} {action.action}", predicted))
    curves.append(("sum over the horizon", total))
    quantity = _quantity(entry, parameter.id)
    polar = on_the_circle(parameter, quantity)
    costs = cost_plot_names(path)[0 if polar else 1]
    others = len({p.id for a in window for p in a.free_parameters()} - {parameter.id})
    note = (f"{parameter.id} varied, the {others} other free parameter{'s' if others != 1 else ''} of these actions at "
            "their refined values: a mark is where a choice of it lies on this slice, not that choice's own "
            "predicted total" if others else "")
    plot_costs(costs, parameter, values, curves, [("greedy", greedy[parameter.id]), ("refined", chosen[parameter.id])],
               note, quantity)
    return costs


def draw_waypoint(path: Path, prepared, pair: tuple[int, object, object], chosen: dict, greedy: dict,
                  entry: SimulatorEntry | None) -> Path:
    """Fig. 5.9 at the way-point `pair` (waypoint_pair): the predicted durations of the action arriving there, of
    the one leaving it and their sum over its free angle and speed, the other free parameters at their refined
    values; written to `path`."""
    import matplotlib.pyplot as plt

    k, angle, speed = pair
    angles = np.linspace(angle.low, angle.high, 61)
    speeds = np.linspace(speed.low, speed.high, 41)
    both = prepared.sequence.actions[k:k + 2]
    panels, total = [], np.zeros((len(angles), len(speeds)))
    for action in both:
        rows = np.array([action.values({**chosen, angle.id: float(a), speed.id: float(v)})
                         for a in angles for v in speeds])
        predicted = prepared.models[action.action].predict_duration(rows).reshape(len(angles), len(speeds))
        total += predicted
        panels.append((f"{action.step} {action.action}: to the way-point" if action is both[0]
                       else f"{action.step} {action.action}: from the way-point", predicted))
    panels.append(("total of both", total))
    marks = [(label, values[angle.id], values[speed.id]) for label, values in (("greedy", greedy), ("refined", chosen))]
    fig = waypoint_figure(angle, speed, (angles, speeds), panels, marks, entry)
    others = len({p.id for a in both for p in a.free_parameters()} - {angle.id, speed.id})
    if others:
        plural = "s" if others != 1 else ""
        fig.supxlabel(f"{angle.id} and {speed.id} varied, the {others} other free parameter{plural} of these actions "
                      "at their refined values: a mark is where a choice of both lies on this slice, not that "
                      "choice's own predicted total", fontsize=8)
    _save(fig, path)
    plt.close(fig)
    return path
