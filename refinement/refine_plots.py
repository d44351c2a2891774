"""Pictures of subgoal refinement: greedy vs refined trajectories (Fig. 5.1) and predicted time over the
free angle of approach as polar plots (Fig. 5.8)."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np

FIELD_X = (-4.0, 4.0)  # m, the soccer field of sims.soccer
FIELD_Y = (-3.0, 3.0)


def _save(fig, path: Path) -> None:
    """Write the figure atomically: a reader never sees half a PNG."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=path.suffix or ".png", dir=path.parent)
    os.close(fd)
    try:
        fig.savefig(tmp, dpi=110, bbox_inches="tight")
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def _draw_trajectory(ax, trajectory: np.ndarray, title: str, goals: list[tuple[float, float, float]]) -> None:
    t, x, y, phi = trajectory[:, 0], trajectory[:, 1], trajectory[:, 2], trajectory[:, 3]
    ax.plot(x, y, "-", color="tab:blue", lw=1.5, label="robot (ball point)")
    step = max(1, len(t) // 25)
    ax.quiver(x[::step], y[::step], np.cos(phi[::step]), np.sin(phi[::step]), color="tab:blue",
              scale=25, width=0.004, alpha=0.6)
    if trajectory.shape[1] >= 7 and np.isfinite(trajectory[:, 5]).any():
        ax.plot(trajectory[:, 5], trajectory[:, 6], "--", color="tab:orange", lw=1.2, label="ball")
        ax.plot(trajectory[0, 5], trajectory[0, 6], "o", color="tab:orange", ms=7)
    for gx, gy, gphi in goals:
        ax.plot(gx, gy, "x", color="k", ms=8)
        if np.isfinite(gphi):
            ax.arrow(gx, gy, 0.35 * np.cos(gphi), 0.35 * np.sin(gphi), head_width=0.08, color="k")
    ax.set_xlim(*FIELD_X)
    ax.set_ylim(*FIELD_Y)
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.set_title(title, fontsize=10)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")


def plot_trajectories(path: Path, panels: list[tuple[str, np.ndarray, list[tuple[float, float, float]]]]) -> None:
    """Side-by-side trajectories, one panel per (title, trajectory (n, 7), subgoals [(x, y, phi)])."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(panels), figsize=(6.0 * len(panels), 4.8))
    for ax, (title, trajectory, goals) in zip(np.atleast_1d(axes), panels):
        _draw_trajectory(ax, trajectory, title, goals)
    np.atleast_1d(axes)[0].legend(loc="lower left", fontsize=8)
    _save(fig, path)
    plt.close(fig)


def plot_polar_costs(path: Path, angles: np.ndarray, curves: list[tuple[str, np.ndarray]],
                     marks: list[tuple[str, float]]) -> None:
    """Predicted duration over the free angle of approach, one polar plot per curve (Fig. 5.8)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(curves), subplot_kw={"projection": "polar"}, figsize=(4.2 * len(curves), 4.2))
    for ax, (title, values) in zip(np.atleast_1d(axes), curves):
        ax.plot(angles, values, color="tab:blue")
        ax.set_rlabel_position(202.5)  # radial labels off the 0°/180° axis labels
        for label, angle in marks:
            k = int(np.argmin(np.abs(np.angle(np.exp(1j * (angles - angle))))))
            ax.plot([angle], [values[k]], "o", ms=6, label=f"{label}: {np.degrees(angle):.0f}°, {values[k]:.2f} s")
        ax.set_title(title, fontsize=10)
        ax.legend(loc="lower center", bbox_to_anchor=(0.5, -0.32), fontsize=8)
    _save(fig, path)
    plt.close(fig)


def _subgoals(sequence) -> list[tuple[float, float, float]]:
    goals = []
    for action in sequence.actions:
        values = action.values()
        goals.append((float(values[4]), float(values[5]), float(values[6])))
    return goals


def draw_refinement(path, prepared, outcomes) -> None:
    """Fig. 5.1 for this problem (greedy and refined trajectories) and, where the first subgoal has a free
    heading, Fig. 5.8 (predicted time of the first actions over that angle) as FILE_polar.png."""
    path = Path(path)
    panels = []
    for key, label in (("greedy", "greedy (h=1)"), ("refined", f"refined (h={outcomes['refined'].refined.horizon})")):
        o = outcomes[key]
        title = f"{label}: predicted {o.refined.predicted_total:.2f} s, simulated {o.simulated.duration:.2f} s"
        if not o.simulated.succeeded:
            title += " (failed)"
        panels.append((title, o.simulated.trajectory, _subgoals(o.refined.sequence)))
    plot_trajectories(path, panels)

    refined = outcomes["refined"].refined
    first = prepared.sequence.actions[0]
    angle = next((p for p in first.free_parameters() if p.name.startswith("phi")), None)
    if angle is None:
        return
    window = prepared.sequence.actions[:max(2, refined.horizon)]
    chosen = {p.id: p.value for a in refined.sequence.actions for p in a.params}
    greedy = {p.id: p.value for a in outcomes["greedy"].refined.sequence.actions for p in a.params}
    angles = np.linspace(angle.low, angle.high, 361)
    curves = []
    total = np.zeros_like(angles)
    for action in window:
        rows = []
        for value in angles:
            assignment = dict(chosen)
            assignment[angle.id] = float(value)
            rows.append(action.values(assignment))
        predicted = prepared.models[action.action].predict_duration(np.array(rows))
        total += predicted
        curves.append((f"{action.step} {action.action}", predicted))
    curves.append(("sum over the horizon", total))
    plot_polar_costs(path.with_name(path.stem + "_polar" + (path.suffix or ".png")), angles, curves,
                     [("greedy", greedy[angle.id]), ("refined", chosen[angle.id])])
