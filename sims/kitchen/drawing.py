"""The kitchen under the trajectories of `tailor refine --plot`: walls, island, tables and cups of the scene, and
at each spot with free parameters the ranges of Fig. 5.12 (green: the square area of positions along and
away from the table's edge, the circular sector of headings at the chosen position) with the chosen pose."""

from __future__ import annotations

import math

from tailor.sims.kitchen import world as W

RANGE_COLOR = "tab:green"
SECTOR_RADIUS = 0.35  # m


def _box(ax, box: W.Box, **style) -> None:
    from matplotlib.patches import Polygon

    ax.add_patch(Polygon(box.corners(), closed=True, **style))


def draw_scene(ax, sequence, values) -> None:
    """Draw the static kitchen of an instantiated action sequence on a matplotlib axis: the ranges of its free
    spot parameters and their chosen `values` (by parameter id)."""
    from matplotlib.patches import Circle, Polygon, Wedge

    for box in [*W.walls(), W.island()]:
        _box(ax, box, color="0.55", zorder=0)
    for name, scene_values in sequence.scene.items():
        kind, _, label = name.partition(" ")
        if kind == "table":
            box = W.table_box(*scene_values)
            _box(ax, box, facecolor="burlywood", edgecolor="saddlebrown", zorder=0)
            ax.text(box.cx, box.cy, label, ha="center", va="center", fontsize=7, zorder=1)
        elif kind == "cup":
            ax.add_patch(Circle(scene_values, W.CUP_RADIUS * 1.5, color="tab:red", zorder=2))
    spots: dict[str, dict] = {}
    for action in sequence.actions:
        for p in action.params:
            obj, _, quantity = p.id.partition(".")
            spots.setdefault(obj, {})[quantity] = p
    for obj, q in spots.items():
        if "tx" in q and q["tx"].value is not None:
            ax.plot([q["tx"].value], [q["ty"].value], "x", color="tab:red", ms=6, zorder=2)
        if not all(k in q for k in ("ox", "oy", "ophi", "along", "dist", "heading")):
            continue
        along, dist, heading = q["along"], q["dist"], q["heading"]
        if along.value is not None or dist.value is not None:
            continue  # a spot without free parameters (the start)
        frame = (q["ox"].value, q["oy"].value, q["ophi"].value)
        corners = [W.spot_pose(*frame, a, d, 0.0)[:2]
                   for a, d in ((along.low, dist.low), (along.high, dist.low), (along.high, dist.high), (along.low, dist.high))]
        ax.add_patch(Polygon(corners, closed=True, color=RANGE_COLOR, alpha=0.25, zorder=1))
        if along.id not in values or dist.id not in values:
            continue
        x, y, _ = W.spot_pose(*frame, values[along.id], values[dist.id], 0.0)
        ax.add_patch(Wedge((x, y), SECTOR_RADIUS, math.degrees(frame[2] + heading.low),
                           math.degrees(frame[2] + heading.high), color=RANGE_COLOR, alpha=0.25, zorder=1))
        phi = frame[2] + values.get(heading.id, 0.0)
        ax.annotate("", xy=(x + SECTOR_RADIUS * math.cos(phi), y + SECTOR_RADIUS * math.sin(phi)), xytext=(x, y),
                    arrowprops={"arrowstyle": "->", "color": "darkgreen"}, zorder=3)
        ax.text(x, y - 0.3, obj, ha="center", fontsize=7, color="darkgreen")
    ax.set_xlim(-0.2, W.ROOM_LENGTH + 0.2)
    ax.set_ylim(-0.2, W.ROOM_WIDTH + 0.2)
