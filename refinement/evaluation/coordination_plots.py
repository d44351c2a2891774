"""Pictures of the coordination experiments (Ch. 7), drawn from a `tailor coordinate` report:
Fig. 7.9 (who goes as noise grows), Fig. 7.10 / 7.11 (the failure tree and where it predicts confusion) and
Fig. 7.12 (success over communication quality and field of view, one heat map per strategy)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from tailor.outputs import write_error  # noqa: E402
from tailor.refinement.learning.plots import _save  # noqa: E402  (atomic: a temp file renamed into place)
from tailor.sims import registry  # noqa: E402

FILES = ("q4_noise.png", "q5_failure_example.png", "q6_communication_fov.png")


def plot_noise(report: dict, path: Path) -> None:
    """Fig. 7.9: stacked shares of decisions where 0, 1, 2, ... robots intend to go, per added noise."""
    rows = report["dynamic"]["noise"]
    shares = np.array([r["going_shares"] for r in rows])
    labels = [f"{r['sigma']:.2f}" for r in rows]
    fig, ax = plt.subplots(figsize=(6.5, 4))
    bottom = np.zeros(len(rows))
    # nobody going is grey, exactly one (success) green, more than one from orange to red
    colors = [(0.6, 0.6, 0.6, 1.0), (0.2, 0.6, 0.2, 1.0)]
    colors += list(plt.cm.autumn_r(np.linspace(0.4, 1.0, max(1, shares.shape[1] - 2))))
    for k in range(shares.shape[1]):
        ax.bar(labels, 100 * shares[:, k], bottom=100 * bottom, color=colors[k], label=f"{k} go")
        bottom += shares[:, k]
    ax.set_xlabel("noise added to teammate estimates, sigma (m; rad on headings)")
    ax.set_ylabel("decisions (%)")
    ax.set_title("Q4: how many robots intend to go (shared belief)")
    ax.legend(loc="lower left", fontsize=8)
    _save(fig, path)


def position_labels(simulator: str) -> tuple[str, str]:
    """The axis labels of the plane of a team robot's position (the first two quantities of its state) with the
    units `simulator` declares: ("x (m)", "y (m)"); ("x", "y") where it has no team scene."""
    from tailor.refinement.refine_plots import axis_label

    entry = registry.simulators().get(simulator)
    scene = entry.team if entry is not None else None
    if scene is None:
        return ("x", "y")
    return tuple(axis_label(name, entry.quantity(name)) for name in scene.state[:2])


def heading_column(simulator: str) -> int | None:
    """The column of a team robot's state that `simulator` declares an angle (its heading, drawn as an arrow),
    None where it declares none (or has no team scene)."""
    entry = registry.simulators().get(simulator)
    scene = entry.team if entry is not None else None
    if scene is None:
        return None
    return next((k for k, quantity in enumerate(scene.state) if entry.quantity(quantity).angle), None)


def plot_failure_example(report: dict, bounds: tuple[float, float, float, float], path: Path) -> None:
    """Fig. 7.11: robots standing still (at the first two columns of their state, the heading where the
    simulator declares one); for each target position the robot chosen (solid green) or, where the failure
    tree predicts confusion, both robots that might go (dashed red). Beside it, Fig. 7.10's tree as regions
    over the time gap and the quickest time, with the rules. Axes in the units the simulator declares; a legend
    names every kind of line and mark."""
    from matplotlib.lines import Line2D

    ex, tree = report["example"], report["dynamic"]["failure_tree"]
    robots, targets = np.array(ex["robots"]), np.array(ex["targets"])
    fig, (ax, text) = plt.subplots(1, 2, figsize=(12, 5), gridspec_kw={"width_ratios": [3, 2]})
    x0, x1, y0, y1 = bounds
    ax.add_patch(plt.Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, color="0.5"))
    step = max(1, len(targets) // 40)
    for k in range(0, len(targets), step):
        tx, ty = targets[k]
        if ex["predicted_failure"][k]:
            for r in (ex["chosen"][k], ex["runner_up"][k]):
                ax.plot([robots[r, 0], tx], [robots[r, 1], ty], "--", color="tab:red", lw=0.8)
        else:
            r = ex["chosen"][k]
            ax.plot([robots[r, 0], tx], [robots[r, 1], ty], "-", color="tab:green", lw=0.8)
    ax.plot(targets[:, 0], targets[:, 1], ".", color="k", ms=2)
    heading = heading_column(report.get("simulator", ""))
    for n, state in enumerate(robots):
        x, y = state[:2]
        if heading is not None:
            ax.arrow(x, y, 0.4 * np.cos(state[heading]), 0.4 * np.sin(state[heading]), width=0.05, color="tab:blue")
        else:
            ax.plot([x], [y], "o", color="tab:blue")
        ax.annotate(f"{n} ({ex['kinds'][n]})", (x, y), textcoords="offset points", xytext=(6, -12), fontsize=8)
    ax.set_aspect("equal")
    ax.set_xlim(x0 - 0.3, x1 + 0.3)
    ax.set_ylim(y0 - 0.3, y1 + 0.3)
    xlabel, ylabel = position_labels(report.get("simulator", ""))
    ax.set(xlabel=xlabel, ylabel=ylabel)
    ax.set_title("Q5: who goes (green) and predicted confusion (red)")
    robot = (Line2D([], [], color="tab:blue", marker=r"$\rightarrow$", ms=12, linestyle="none",
                    label="robot (standing; arrow: its heading)") if heading is not None
             else Line2D([], [], color="tab:blue", marker="o", linestyle="none", label="robot (standing)"))
    ax.legend(handles=[robot, Line2D([], [], color="k", marker=".", ms=5, linestyle="none", label="target position"),
                       Line2D([], [], color="tab:green", lw=0.8, label="the robot chosen to go"),
                       Line2D([], [], color="tab:red", lw=0.8, linestyle="--",
                              label="predicted confusion: both robots that might go")],
              loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2, fontsize=8, frameon=False)
    text.axis("off")
    lines = ["Decision tree predicting coordination", "success (Fig. 7.10):", ""]
    if tree is not None:
        lines += tree["rules"] + ["", f"accuracy {100 * tree['accuracy']:.1f}% on {tree['test_ticks']} decisions",
                                  f"failures predicted {100 * (tree['failures_predicted'] or 0):.1f}%"]
    text.text(0.0, 1.0, "\n".join(lines), va="top", family="monospace", fontsize=9)
    _save(fig, path)


def plot_communication_fov(report: dict, path: Path) -> None:
    """Fig. 7.12: coordination success (exactly one robot goes) over communication quality x field of view."""
    grid = report["dynamic"]["communication_fov"]
    names = list(grid["success"])
    fig, axes = plt.subplots(1, len(names), figsize=(4.2 * len(names), 4), squeeze=False)
    for ax, name in zip(axes[0], names):
        values = 100 * np.array(grid["success"][name])
        ax.imshow(values, origin="lower", vmin=0, vmax=100, cmap="viridis", aspect="auto")
        ax.set_xticks(range(len(grid["field_of_view"])), [f"{f:.0f}" for f in grid["field_of_view"]])
        ax.set_yticks(range(len(grid["communication"])), [f"{100 * q:.0f}" for q in grid["communication"]])
        ax.set_xlabel("field of view (degrees)")
        ax.set_ylabel("communication quality (%)")
        ax.set_title(name)
        for (a, b), v in np.ndenumerate(values):
            ax.text(b, a, f"{v:.0f}", ha="center", va="center", fontsize=8, color="w" if v < 60 else "k")
    fig.suptitle("Q6: coordination success (%: exactly one robot intends to go)")
    _save(fig, path)


def draw_all(report: dict, bounds: tuple[float, float, float, float], folder) -> list[Path]:
    """Every picture into `folder`; returns the paths written."""
    folder = Path(folder)
    paths = [folder / name for name in FILES]
    try:
        folder.mkdir(parents=True, exist_ok=True)
        plot_noise(report, paths[0])
        plot_failure_example(report, bounds, paths[1])
        plot_communication_fov(report, paths[2])
    except OSError as exc:
        raise write_error(exc.filename or folder, exc) from None
    return paths
