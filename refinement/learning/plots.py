"""Figures of the training report: MAE over n_i (Fig. 4.5), MAE over episodes (Fig. 4.6) for every domain; and
the pictures of learned models the domain's simulator declares it can draw (its SimulatorEntry's model_pictures):
the predicted duration over an angle for one situation (Fig. 4.7) and where a success classifier predicts failure
(Fig. 4.8). Drawn headless (Agg) to a PNG file or buffer: the training run writes them atomically beside its
report and embeds the same bytes in the HTML one."""

from __future__ import annotations

import io
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import BinaryIO

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import FormatStrFormatter  # noqa: E402
import numpy as np  # noqa: E402

from tailor.refinement.models.action_models import ActionModel, CollisionModel  # noqa: E402
from tailor.refinement.models.features import feature_space  # noqa: E402
from tailor.refinement.refine_plots import tidy_polar  # noqa: E402
from tailor.sims import registry  # noqa: E402
from tailor.sims.protocol import UNDECLARED, DurationCurve, SimulatorEntry, SuccessRegion  # noqa: E402

ANGLE_SAMPLES = 361
REGION_SAMPLES = 121  # grid points per side of Fig. 4.8's square of starts

Target = Path | BinaryIO  # a file name or a writable binary buffer

CAPTIONS = {
    "mae_vs_n_i.png": "Validation MAE against the examples kept per episode, n_i (Fig. 4.5)",
    "mae_vs_episodes.png": "Test MAE against the number of training episodes, model tree and gradient boosting "
                           "(Fig. 4.6)",
}
SPACES_FILE = "feature_spaces.png"
CAPTIONS[SPACES_FILE] = ("Held-out MAE on each feature space relative to gradient boosting on the raw parameters "
                         "(Fig. 4.3)")
CURVE_SUFFIX = "_polar.png"  # Fig. 4.7's file: <label>_polar.png
CURVE_CAPTION = "Predicted duration over {meaning} in one situation (Fig. 4.7)"
REGION_SUFFIX = ".success_region.png"  # Fig. 4.8's file: <action>.success_region.png
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


def _parameters(names: tuple[str, ...], values: Mapping[str, float], rows: int) -> np.ndarray:
    """(rows, len(names)) action parameters: each name's value in `values`, 0 where it has none."""
    return np.tile(np.array([float(values.get(name, 0.0)) for name in names]), (rows, 1))


def curve_params(curve: DurationCurve, names: tuple[str, ...], angles: np.ndarray) -> np.ndarray:
    """The parameters (in the order `names`) of Fig. 4.7's situation with `curve.varied` at each of `angles`."""
    params = _parameters(names, curve.situation, len(angles))
    params[:, names.index(curve.varied)] = angles
    return params


def plot_duration_curve(curve: DurationCurve, models: Mapping[str, ActionModel], path: Target) -> None:
    """Predicted duration over the swept angle for one situation, Cartesian and polar (Fig. 4.7), the polar radius
    from near the shortest prediction (a variation small beside the durations themselves still shows); each
    panel names its curves."""
    angles = np.linspace(-np.pi, np.pi, ANGLE_SAMPLES)
    fig = plt.figure(figsize=(10.0, 5.2))
    cartesian = fig.add_subplot(1, 2, 1)
    polar = fig.add_subplot(1, 2, 2, projection="polar")
    largest, smallest = 0.0, np.inf
    for action, model in models.items():
        predicted = model.predict_duration(curve_params(curve, _parameters_of(model), angles))
        largest = max(largest, float(np.nanmax(predicted)))
        smallest = min(smallest, float(np.nanmin(predicted)))
        cartesian.plot(np.degrees(angles), predicted, label=action)
        polar.plot(angles, predicted, label=action)
    tidy_polar(polar, largest, smallest)
    polar.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=min(len(models), 4), fontsize="small",
                 frameon=False)
    cartesian.set(xlabel=f"{curve.label} (deg)", ylabel="predicted duration (s)", xticks=range(-180, 181, 90),
                  title=curve.description)
    cartesian.grid(True, alpha=0.3)
    cartesian.legend()
    polar.set_title(f"predicted duration (s) over {curve.label} (Fig. 4.7)", fontsize="medium", pad=14)
    _save(fig, path)


def region_params(region: SuccessRegion, names: tuple[str, ...], turn: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, y, params): starts on a grid round the goal at the origin (parameters in the order `names`), the
    heading turned by `turn` from the direction toward the goal (0: facing it)."""
    axis = np.linspace(-region.half_size, region.half_size, REGION_SAMPLES)
    x, y = np.meshgrid(axis, axis)
    params = _parameters(names, region.situation, x.size)
    ix, iy = names.index(region.x), names.index(region.y)
    params[:, ix], params[:, iy] = x.ravel(), y.ravel()
    params[:, names.index(region.heading)] = np.arctan2(-params[:, iy], -params[:, ix]) + turn
    return x, y, params


def plot_success_region(region: SuccessRegion, model: CollisionModel, path: Target,
                        entry: SimulatorEntry | None = None) -> None:
    """Where the classifier predicts that its action fails (e.g. bumps an object lying at its goal), over starts
    round the goal (Fig. 4.8), one panel per turn of the start heading; axes in the units `entry` declares."""
    names = _parameters_of(model)
    units = {q: (entry.quantity(q) if entry is not None else UNDECLARED).unit for q in (region.x, region.y)}
    fig, axes = plt.subplots(1, len(region.turns), figsize=(5.0 * len(region.turns), 4.8), squeeze=False)
    for ax, (turn, label) in zip(axes[0], region.turns):
        x, y, params = region_params(region, names, turn)
        success = model.predict_success(params).reshape(x.shape)
        ax.contourf(x, y, success.astype(float), levels=[-0.5, 0.5, 1.5], colors=["#d62728", "#2ca02c"], alpha=0.45)
        ax.plot(0.0, 0.0, "ko", ms=4)
        if region.goal_heading:
            heading = float(region.situation.get(region.goal_heading, 0.0))
            ax.annotate("", xy=(0.6 * np.cos(heading), 0.6 * np.sin(heading)), xytext=(0.0, 0.0),
                        arrowprops={"arrowstyle": "->", "lw": 2})
        ax.set(aspect="equal", xlabel=_axis_label(f"start {region.x}", units[region.x]),
               ylabel=_axis_label(f"start {region.y}", units[region.y]), title=label)
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles = [Patch(color="#d62728", alpha=0.45, label="predicted failure"),
               Patch(color="#2ca02c", alpha=0.45, label="predicted success"),
               Line2D([], [], color="black", marker="o", ms=4, lw=2 if region.goal_heading else 0, label=region.goal)]
    fig.legend(handles=handles, loc="lower center", ncol=3, frameon=False)
    fig.suptitle(f"{region.description.format(action=model.action)} (Fig. 4.8)", fontsize="medium")
    fig.tight_layout(rect=(0.0, 0.06, 1.0, 1.0))
    _save(fig, path, layout=False)


def _axis_label(name: str, unit: str) -> str:
    return f"{name} ({unit})" if unit else name


def _parameters_of(model) -> tuple[str, ...]:
    """The action parameters a model's features read: its own space's (generated) or the registered one's."""
    space = getattr(model, "space", None)
    return tuple(space.parameters if space is not None else feature_space(model.feature_space).parameters)


def _reads(model, parameters: frozenset[str]) -> bool:
    """Whether a model reads every action parameter a picture sets."""
    return parameters <= set(_parameters_of(model))


def plot_feature_spaces(reports: Mapping[str, dict], path: Target) -> None:
    """Fig. 4.3 for every action: held-out MAE on each feature space, as bars relative to gradient boosting on
    the raw parameters (the dashed line at 1)."""
    from tailor.refinement.learning.report import SPACE_LABELS, space_mae

    rows = {a: r["space_comparison"] for a, r in reports.items() if r.get("space_comparison")}
    fig, ax = plt.subplots(figsize=(max(6.0, 1.6 * len(rows) + 2.0), 4.0))
    width = 0.8 / len(SPACE_LABELS)
    for k, label in enumerate(SPACE_LABELS):
        xs, ys = [], []
        for i, comparison in enumerate(rows.values()):
            mae = space_mae(comparison)
            if label in mae and comparison["mae_hgb_raw"] > 0:
                xs.append(i + (k - 1.5) * width)
                ys.append(mae[label] / comparison["mae_hgb_raw"])
        ax.bar(xs, ys, width, label=label, color=f"C{k}")
    ax.axhline(1.0, color="0.3", linestyle="--", lw=1, label="gradient boosting, raw")
    ax.set_xticks(range(len(rows)), list(rows))
    ax.set(ylabel="held-out MAE / HGB on raw parameters", yscale="log",
           title="Feature spaces (Fig. 4.3): the model tree on each,\nrelative to gradient boosting on the raw "
                 "parameters")
    ax.grid(True, axis="y", which="both", alpha=0.3)
    for axis in (ax.yaxis.set_major_formatter, ax.yaxis.set_minor_formatter):  # 0.6, not 6 x 10^-1
        axis(FormatStrFormatter("%g"))
    ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False)
    ax.title.set_fontsize("medium")
    _save(fig, path)


def caption(name: str, simulator: str = "") -> str:
    """What the training figure of file `name` shows (a picture `simulator` declares, in its own words)."""
    if name.endswith(REGION_SUFFIX):
        return REGION_CAPTION.format(action=name.removesuffix(REGION_SUFFIX))
    if name.endswith(CURVE_SUFFIX):
        label = name.removesuffix(CURVE_SUFFIX)
        curve = next((c for c in _pictures(simulator, DurationCurve) if c.label == label), None)
        return CURVE_CAPTION.format(meaning=(curve.meaning if curve is not None and curve.meaning else label))
    return CAPTIONS.get(name, name)


def _entry(simulator: str) -> SimulatorEntry | None:
    return registry.simulators().get(simulator) if simulator else None


def _pictures(simulator: str, kind: type) -> list:
    entry = _entry(simulator)
    return [p for p in (entry.model_pictures if entry is not None else ()) if isinstance(p, kind)]


def training_plots(simulator: str, models: Mapping[str, ActionModel],
                   classifiers: Mapping[str, CollisionModel]) -> dict[str, Callable[[Target], None]]:
    """File name -> writer of each figure of a training run: the learning curves, and each picture the simulator
    declares for the models and classifiers whose feature spaces read the parameters it sets."""
    reports = {action: model.report for action, model in models.items()}
    plots: dict[str, Callable[[Target], None]] = {
        "mae_vs_n_i.png": lambda p: plot_mae_vs_n_i(reports, p),
        "mae_vs_episodes.png": lambda p: plot_mae_vs_episodes(reports, p),
    }
    if any(r.get("space_comparison") for r in reports.values()):
        plots[SPACES_FILE] = lambda p: plot_feature_spaces(reports, p)
    for curve in _pictures(simulator, DurationCurve):
        drawn = {action: m for action, m in models.items() if _reads(m, curve.parameters)}
        if drawn:
            plots[curve.label + CURVE_SUFFIX] = lambda p, c=curve, d=drawn: plot_duration_curve(c, d, p)
    entry = _entry(simulator)
    for region in _pictures(simulator, SuccessRegion):
        for action, classifier in classifiers.items():
            if _reads(classifier, region.parameters):
                plots[action + REGION_SUFFIX] = lambda p, r=region, c=classifier: plot_success_region(r, c, p, entry)
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
