"""Figures of the training report: MAE over n_i (Fig. 4.5), MAE over episodes (Fig. 4.6) for every domain;
for models in the pose feature space, the predicted duration over the angle of approach for one situation
(Fig. 4.7) and where a success classifier predicts failure (Fig. 4.8). Drawn headless (Agg) to a PNG file or
buffer: the training run writes them atomically beside its report and embeds the same bytes in the HTML one."""

from __future__ import annotations

import io
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import BinaryIO

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from tailor.refinement.models.action_models import ActionModel, CollisionModel  # noqa: E402
from tailor.refinement.models.features import POSE_PARAMETERS, feature_space  # noqa: E402
from tailor.refinement.refine_plots import tidy_polar  # noqa: E402

# the situation of Fig. 4.7: goal 1.5 m straight ahead, robot standing, arriving at rest
SITUATION_DIST = 1.5  # m
SITUATION_V = 0.0  # m/s
SITUATION_VG = 0.0  # m/s
ANGLE_SAMPLES = 361

Target = Path | BinaryIO  # a file name or a writable binary buffer

CAPTIONS = {
    "mae_vs_n_i.png": "Validation MAE against the examples kept per episode, n_i (Fig. 4.5)",
    "mae_vs_episodes.png": "Test MAE against the number of training episodes, model tree and gradient boosting "
                           "(Fig. 4.6)",
    "angle_at_polar.png": "Predicted duration over the angle of approach in one situation (Fig. 4.7)",
}
REGION_CAPTION = "Where the success classifier of {action} predicts failure, over start positions (Fig. 4.8)"


def plot_mae_vs_n_i(reports: Mapping[str, dict], path: Target) -> None:
    """Validation MAE of models trained on half the episodes, against examples per episode (Fig. 4.5), at the
    default leaf size; hollow where that tree would be too large to store, a star at the chosen n_i and leaf."""
    from tailor.refinement.learning.duration_protocol import MAX_LEAVES

    fig, ax = plt.subplots(figsize=(8.4, 4.0))
    for index, (action, report) in enumerate(reports.items()):
        curve, color = report["n_i_curve"], f"C{index}"
        n_i, mae = [r["n_i"] for r in curve], [r["mae"] for r in curve]
        ax.plot(n_i, mae, color=color, label=f"{action} (n_i={report['n_i']}, leaf {report['min_samples_leaf']})")
        large = [(r.get("projected_leaves") or 0) > MAX_LEAVES for r in curve]
        ax.scatter(n_i, mae, marker="o", edgecolors=color, facecolors=["none" if big else color for big in large])
        chosen = [r for r in report.get("leaf_curve", []) if r["min_samples_leaf"] == report["min_samples_leaf"]]
        if chosen:
            ax.scatter([report["n_i"]], [chosen[0]["mae"]], marker="*", s=160, color=color, edgecolors="black",
                       zorder=3)
    ax.set(xscale="log", xlabel="examples per episode n_i", ylabel="MAE on validation episodes (s)",
           title="Accuracy against intermediate examples (Fig. 4.5)")
    n_i = sorted({r["n_i"] for report in reports.values() for r in report["n_i_curve"]})
    ax.set_xticks(n_i, [str(v) for v in n_i])
    ax.minorticks_off()
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize="small", title=f"hollow: > {MAX_LEAVES} leaves\nat leaf size 10; star: chosen",
              title_fontsize="small", loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False)
    _save(fig, path)


def plot_mae_vs_episodes(reports: Mapping[str, dict], path: Target) -> None:
    """Test MAE against the number of training episodes, model tree and gradient boosting (Fig. 4.6); the
    legend beside the axes (colour: action, line: learner), where it hides no point."""
    from matplotlib.lines import Line2D
    from matplotlib.ticker import LogLocator, ScalarFormatter

    fig, ax = plt.subplots(figsize=(8.0, 4.0))
    handles = []
    for index, (action, report) in enumerate(reports.items()):
        curve = report["episodes_curve"]
        color = f"C{index}"
        episodes = [r["episodes"] for r in curve]
        ax.plot(episodes, [r["mae"] for r in curve], marker="o", color=color)
        ax.plot(episodes, [r["mae_hgb"] for r in curve], marker="x", linestyle="--", color=color)
        handles.append(Line2D([], [], color=color, lw=3, label=action))
    handles += [Line2D([], [], color="0.3", marker="o", label="model tree"),
                Line2D([], [], color="0.3", marker="x", linestyle="--", label="gradient boosting")]
    ax.set(xscale="log", xlabel="training episodes", ylabel="MAE on test episodes (s)",
           title="Accuracy against experience (Fig. 4.6)")
    ax.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
    ax.xaxis.set_major_formatter(ScalarFormatter())
    ax.xaxis.set_minor_formatter(plt.NullFormatter())
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(handles=handles, fontsize="small", loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False)
    _save(fig, path)


def situation_params(angle_at: np.ndarray) -> np.ndarray:
    """Action parameters with dist 1.5 m, angle_to 0, v 0 and the given angles of approach (rad)."""
    params = np.zeros((len(angle_at), 8))
    params[:, 4] = SITUATION_DIST  # goal straight ahead of a robot at the origin facing +x
    params[:, 3] = SITUATION_V
    params[:, 6] = angle_at  # phig; the bearing to the goal is 0, so angle_at = phig
    params[:, 7] = SITUATION_VG
    return params


def plot_angle_at(models: Mapping[str, ActionModel], path: Target) -> None:
    """Predicted duration over angle_at for one situation, Cartesian and polar (Fig. 4.7)."""
    angle_at = np.linspace(-np.pi, np.pi, ANGLE_SAMPLES)
    params = situation_params(angle_at)
    fig = plt.figure(figsize=(10.0, 4.6))
    cartesian = fig.add_subplot(1, 2, 1)
    polar = fig.add_subplot(1, 2, 2, projection="polar")
    largest = 0.0
    for action, model in models.items():
        predicted = model.predict_duration(params)
        largest = max(largest, float(np.nanmax(predicted)))
        cartesian.plot(np.degrees(angle_at), predicted, label=action)
        polar.plot(angle_at, predicted, label=action)
    tidy_polar(polar, largest)
    cartesian.set(xlabel="angle_at (deg)", ylabel="predicted duration (s)", xticks=range(-180, 181, 90),
                  title=f"dist {SITUATION_DIST} m, angle_to 0, v {SITUATION_V} m/s, vg {SITUATION_VG} m/s")
    cartesian.grid(True, alpha=0.3)
    cartesian.legend()
    polar.set_title("predicted duration (s) over angle_at (Fig. 4.7)", fontsize="medium", pad=14)
    _save(fig, path)


REGION_HALF_SIZE = 3.0  # m, the start positions of Fig. 4.8's picture: a square this far round the goal
REGION_SAMPLES = 121  # per side
REGION_VG = 0.15  # m/s, mid-range of the collision experience (0 to 0.3 m/s)


def region_params(start_heading: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, y, params): starts on a grid round the goal (the goal at the origin, heading +x), standing,
    with heading `start_heading` relative to the direction toward the goal (0: facing it)."""
    axis = np.linspace(-REGION_HALF_SIZE, REGION_HALF_SIZE, REGION_SAMPLES)
    x, y = np.meshgrid(axis, axis)
    params = np.zeros((x.size, 8))
    params[:, 0], params[:, 1] = x.ravel(), y.ravel()
    params[:, 2] = np.arctan2(-params[:, 1], -params[:, 0]) + start_heading
    params[:, 7] = REGION_VG
    return x, y, params


def plot_collision_region(model: CollisionModel, path: Target) -> None:
    """Where the classifier predicts that its action fails (e.g. bumps an object lying at its goal), over start
    positions round the goal pose (Fig. 4.8): facing the goal, and turned 135 degrees from it (not 180: there
    the sign of angle_at flips with the last bit of the heading, which would speckle the picture)."""
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.8))
    for ax, (heading, label) in zip(axes, ((0.0, "facing the goal"), (0.75 * np.pi, "turned 135 deg from the goal"))):
        x, y, params = region_params(heading)
        success = model.predict_success(params).reshape(x.shape)
        ax.contourf(x, y, success.astype(float), levels=[-0.5, 0.5, 1.5], colors=["#d62728", "#2ca02c"], alpha=0.45)
        ax.plot(0.0, 0.0, "ko", ms=4)
        ax.annotate("", xy=(0.6, 0.0), xytext=(0.0, 0.0), arrowprops={"arrowstyle": "->", "lw": 2})
        ax.set(aspect="equal", xlabel="start x (m)", ylabel="start y (m)", title=f"robot standing, {label}")
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles = [Patch(color="#d62728", alpha=0.45, label="predicted failure"),
               Patch(color="#2ca02c", alpha=0.45, label="predicted success"),
               Line2D([], [], color="black", marker="o", ms=4, lw=2, label="goal pose (heading +x)")]
    fig.legend(handles=handles, loc="lower center", ncol=3, frameon=False)
    fig.suptitle(f"{model.action} to the goal pose, arriving at {REGION_VG} m/s, from a standing start at each point "
                 "(Fig. 4.8)", fontsize="medium")
    fig.tight_layout(rect=(0.0, 0.06, 1.0, 1.0))
    _save(fig, path, layout=False)


POSE_SPACES = ("pose", "pose_delta")  # the duration models' feature spaces Fig. 4.7 is drawn in (goal heading)


def _posed(feature_set: str) -> bool:
    """Whether Figs. 4.7 and 4.8 apply to a model: its feature space reads a start and a goal pose."""
    return feature_space(feature_set).parameters == POSE_PARAMETERS


def caption(name: str) -> str:
    """What the training figure of file `name` shows."""
    if name.endswith(".success_region.png"):
        return REGION_CAPTION.format(action=name.removesuffix(".success_region.png"))
    return CAPTIONS.get(name, name)


def training_plots(simulator: str, models: Mapping[str, ActionModel],
                   classifiers: Mapping[str, CollisionModel]) -> dict[str, Callable[[Target], None]]:
    """File name -> writer of each figure of a training run (those that apply to its models' feature spaces)."""
    reports = {action: model.report for action, model in models.items()}
    plots: dict[str, Callable[[Target], None]] = {
        "mae_vs_n_i.png": lambda p: plot_mae_vs_n_i(reports, p),
        "mae_vs_episodes.png": lambda p: plot_mae_vs_episodes(reports, p),
    }
    # every duration model that reads a start and a goal pose, whatever features it derives from them (a robot's
    # own space that adds the path its controller plans)
    posed = {action: m for action, m in models.items() if m.feature_set in POSE_SPACES or _posed(m.feature_set)}
    if posed:
        plots["angle_at_polar.png"] = lambda p: plot_angle_at(posed, p)
    for action, classifier in classifiers.items():
        if _posed(classifier.feature_set):
            plots[f"{action}.success_region.png"] = lambda p, c=classifier: plot_collision_region(c, p)
    return plots



def png_bytes(draw: Callable[[Target], None]) -> bytes:
    """The PNG a figure writer draws, as bytes (to write to a file and to embed in the HTML report)."""
    buffer = io.BytesIO()
    draw(buffer)
    return buffer.getvalue()


def _save(fig: plt.Figure, target: Target, layout: bool = True) -> None:
    try:
        if layout:
            fig.tight_layout()
        fig.savefig(target, dpi=110, format="png")
    finally:
        plt.close(fig)
