"""Fig. 6.6: instances of subgoal assertion drawn side by side: the plain execution (dashed) and the one with
assertion + refinement (solid), the asserted subgoals, and the scene objects where the situation placed them."""

from __future__ import annotations

from pathlib import Path

import numpy as np


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
