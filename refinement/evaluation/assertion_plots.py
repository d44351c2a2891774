"""Fig. 6.6: instances of subgoal assertion drawn side by side: the plain execution (dashed) and the one with
assertion + refinement (solid), the asserted subgoals, and the scene objects where the situation placed them.
Fig. 6.5: the search space of subgoal refinement in subgoal assertion, the predicted durations of the two actions
through an asserted subgoal and their sum over two of the subgoal's free parameters, invalid values (the second
action predicted to fail, Alg. 6) not rendered."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tailor.sims.protocol import UNDECLARED

SEARCH_POINTS = 121  # grid points along each axis of Fig. 6.5


@dataclass(frozen=True)
class SearchSpace:
    """Fig. 6.5's numbers: over the grid `xs` x `ys` of two of the subgoal's free parameters (`axes`, the others
    at their refined values), the predicted duration of each action of the pair and their sum (`series`, each
    (len(ys), len(xs))); the second action's and the sum masked where its classifier predicts failure (`valid`
    False: Alg. 6 returns INVALID there). `chosen` is the refined subgoal, `marks` the start and goal where they
    have the axes' quantities."""

    axes: tuple[str, str]
    xs: np.ndarray
    ys: np.ndarray
    series: tuple[tuple[str, np.ma.MaskedArray], ...]
    valid: np.ndarray
    chosen: tuple[float, float]
    marks: tuple[tuple[str, float, float], ...] = ()


def asserted_pair(sequence) -> tuple[int, int] | None:
    """The indices of the first two actions through an asserted subgoal: a guarded action sharing free
    parameters (the subgoal's) with the action before it; None where no subgoal was asserted."""
    for k in range(1, len(sequence.actions)):
        second, first = sequence.actions[k], sequence.actions[k - 1]
        if second.guard and {p.id for p in second.free_parameters()} & {p.id for p in first.free_parameters()}:
            return k - 1, k
    return None


def search_space(asserted, refined, models: Mapping, success_models: Mapping, entry=None,
                 points: int = SEARCH_POINTS) -> SearchSpace | None:
    """Fig. 6.5 for the first asserted subgoal of `asserted` (free parameters as ranges), the other values at
    those of `refined` (the same sequence refined). The axes are the first two of the subgoal's free parameters
    that the simulator `entry` does not declare angles (the ground plane), else its first two. None where no
    subgoal has two free parameters."""
    pair = asserted_pair(asserted)
    if pair is None:
        return None
    first, second = (asserted.actions[k] for k in pair)
    shared = [p for p in first.free_parameters() if p.id in {q.id for q in second.free_parameters()}]
    if len(shared) < 2:
        return None
    quantity = (lambda name: entry.quantity(name)) if entry is not None else (lambda name: UNDECLARED)
    plane = [p for p in shared if not quantity(p.id).angle]
    ax, ay = (plane if len(plane) >= 2 else shared)[:2]
    xs, ys = np.linspace(ax.low, ax.high, points), np.linspace(ay.low, ay.high, points)
    gx, gy = np.meshgrid(xs, ys)  # (len(ys), len(xs))
    chosen = {p.id: p.value for a in refined.actions for p in a.params}
    series, valid = [], None
    for action in (first, second):
        rows = np.repeat(action.values(chosen)[None], gx.size, axis=0)
        for parameter, grid in ((ax, gx), (ay, gy)):
            rows[:, [k for k, p in enumerate(action.params) if p.id == parameter.id]] = grid.reshape(-1, 1)
        predicted = np.asarray(models[action.action].predict_duration(rows), dtype=float).reshape(gx.shape)
        if action.guard:
            valid = np.asarray(success_models[action.guard].predict_success(rows), dtype=bool).reshape(gx.shape)
        series.append(predicted)
    invalid = ~valid
    titles = [f"{a.step} {a.action}: {'start to subgoal' if k == 0 else 'subgoal to goal (Alg. 6)'}"
              for k, a in enumerate((first, second))]
    drawn = ((titles[0], np.ma.masked_array(series[0], mask=np.zeros_like(invalid))),
             (titles[1], np.ma.masked_array(series[1], mask=invalid)),
             ("sum of both", np.ma.masked_array(series[0] + series[1], mask=invalid)))
    return SearchSpace((ax.id, ay.id), xs, ys, drawn, valid, (chosen[ax.id], chosen[ay.id]),
                       _marks(first, second, ax.id, ay.id))


def _marks(first, second, x_id: str, y_id: str) -> tuple[tuple[str, float, float], ...]:
    """The start (bound values of the first action) and the goal (of the second) in the axes' quantities."""
    def suffix(name: str) -> str:  # a parameter id ends in its quantity
        return name.rpartition(".")[2]

    marks = []
    for label, action in (("start", first), ("goal", second)):
        bound = {suffix(p.id): (p.id.rpartition(".")[0], p.value) for p in action.params if not p.free}
        if suffix(x_id) in bound and suffix(y_id) in bound:
            (name, x), (_, y) = bound[suffix(x_id)], bound[suffix(y_id)]
            marks.append((f"{label} ({name})", float(x), float(y)))
    return tuple(marks)


def search_space_name(path) -> Path:
    """Where `tailor evaluate --assertion --plot FILE.png` writes Fig. 6.5: FILE_search_space.png beside FILE."""
    path = Path(path)
    return path.with_name(path.stem + "_search_space" + (path.suffix or ".png"))


def search_space_figure(space: SearchSpace, title: str = "", entry=None):
    """Fig. 6.5 as three panels (first action, second action, their sum), colour for the predicted duration; the
    masked (invalid) cells are not drawn."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from tailor.refinement.refine_plots import axis_label

    quantity = (lambda name: entry.quantity(name)) if entry is not None else (lambda name: UNDECLARED)
    fig, axes = plt.subplots(1, len(space.series), figsize=(5.0 * len(space.series), 4.6), layout="constrained")
    for ax, (label, values) in zip(np.atleast_1d(axes), space.series):
        mesh = ax.pcolormesh(space.xs, space.ys, values, shading="auto", cmap="viridis")
        fig.colorbar(mesh, ax=ax, label="predicted duration (s)", shrink=0.85)
        ax.plot(*space.chosen, "*", color="tab:red", ms=13, mec="black", mew=0.6, label="refined subgoal")
        for (name, x, y), marker in zip(space.marks, ("o", "s")):
            ax.plot([x], [y], marker, color="white", ms=8, mec="black", mew=0.8, label=name)
        ax.set(xlabel=axis_label(space.axes[0], quantity(space.axes[0])),
               ylabel=axis_label(space.axes[1], quantity(space.axes[1])))
        if quantity(space.axes[0]).unit and quantity(space.axes[0]).unit == quantity(space.axes[1]).unit:
            ax.set_aspect("equal")
        blank = "" if values.mask is np.ma.nomask or not np.any(values.mask) else "\n(blank: predicted to fail)"
        ax.set_title(label + blank, fontsize=10)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=3, fontsize=7, frameon=False)
    if title:
        fig.suptitle(title, fontsize=11)
    return fig


def draw_search_space(path: Path, space: SearchSpace, title: str = "", entry=None) -> Path:
    """Write Fig. 6.5 to `path`."""
    from tailor.refinement.refine_plots import _save

    fig = search_space_figure(space, title, entry)
    import matplotlib.pyplot as plt

    _save(fig, Path(path))
    plt.close(fig)
    return Path(path)


def _layer(result, views) -> tuple[str, ...]:
    """The trajectory columns to draw: the first layer of the simulator's first view (a third column in it a
    heading, as the view declares), else the first two columns after the time."""
    if views:
        first = views[0]
        layer = tuple(first) if isinstance(first[0], str) else tuple(first[0])
        if all(result.has_column(c) for c in layer[:2]):
            return layer
    return tuple(result.columns[1:3])


def draw_instances(path: Path, rows: list[dict], views=()) -> Path:
    """One panel per row of `assertion_episode(..., keep=True)`."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from tailor.refinement.refine_plots import _save, subgoal_rows

    fig, axes = plt.subplots(1, max(1, len(rows)), figsize=(5.2 * max(1, len(rows)), 4.4), squeeze=False)
    for ax, row in zip(axes[0], rows):
        for key, style, color, label in (("plain_result", "--", "tab:red", "plain"),
                                         ("with_result", "-", "tab:blue", "with assertion")):
            result = row[key]
            layer = _layer(result, views)
            x, y = result.column(layer[0]), result.column(layer[1])
            outcome = row["plain_outcome" if key == "plain_result" else "with_outcome"]
            ax.plot(x, y, style, color=color, lw=1.5, label=f"{label}: {result.duration:.1f} s, {outcome}")
            if len(layer) > 2 and len(x):
                heading = result.column(layer[2])
                step = max(1, len(x) // 15)
                ax.quiver(x[::step], y[::step], np.cos(heading[::step]), np.sin(heading[::step]), color=color,
                          scale=30, width=0.003, alpha=0.5)
            if key == "with_result" and row["inserted"]:
                marks = subgoal_rows(result)[:-1]
                ax.plot(x[marks], y[marks], "D", color="k", ms=7, label="asserted subgoal")
        for name, values in row["sequence"].scene.items():
            if len(values) >= 2:
                ax.plot([values[0]], [values[1]], "o", ms=8, mfc="none", label=f"{name} at start")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(alpha=0.3)
        verdict = "subgoal asserted" if row["inserted"] else "success predicted: no subgoal"
        ax.set_title(f"situation {row['index']}: {verdict}", fontsize=10)
        ax.legend(loc="best", fontsize=7)
    _save(fig, Path(path))
    plt.close(fig)
    return Path(path)
