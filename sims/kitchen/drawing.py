"""The kitchen under the trajectories of `tailor refine --plot`: walls, island, tables and cups of the scene, and
at each spot with free parameters the ranges of Fig. 5.12 (green: the square area of positions along and
away from the table's edge, or at a door spot the segment across the door, the circular sector of headings at
the chosen position) with the chosen pose, and at a way-point the speed chosen to pass it.
Names stand where no marker is: a table's behind it (beyond the wall it stands against; cups and put locations
lie on it, the robot works before it), a spot's diagonally beyond the far corner of its square (the heading
sector and arrow point toward the table, the chosen position lies inside the square), on the side away from the
other spots at the same table edge."""

from __future__ import annotations

import math

from tailor.sims.kitchen import world as W

RANGE_COLOR = "tab:green"
SECTOR_RADIUS = 0.35  # m
LABEL_GAP = 3.0  # points between a name and the edge it stands beside
SPOT_LABEL_GAP = 10.0  # points from a square's corner to a spot's name: clear of a subgoal marker at the corner
LABEL_BOX = {"boxstyle": "round,pad=0.15", "facecolor": "white", "edgecolor": "none", "alpha": 0.8}
MARGIN = 0.7  # m of the axes beyond the outer walls: room for the tables' names behind them


def _box(ax, box: W.Box, **style) -> None:
    from matplotlib.patches import Polygon

    ax.add_patch(Polygon(box.corners(), closed=True, **style))


def _name(ax, text: str, x: float, y: float, direction: float, rotation: float = 0.0, gap: float = LABEL_GAP,
          **style) -> None:
    """`text` beside the point (x, y), `gap` points from it toward angle `direction` (rad) and wholly on that
    side of it, on a white ground (a route may pass under it)."""
    dx, dy = math.cos(direction), math.sin(direction)
    ha = "left" if dx > 0.38 else "right" if dx < -0.38 else "center"  # (0.38: diagonals take a corner's side)
    va = "bottom" if dy > 0.38 else "top" if dy < -0.38 else "center"
    ax.annotate(text, (x, y), xytext=(gap * dx, gap * dy), textcoords="offset points", ha=ha, va=va,
                rotation=rotation, fontsize=7, bbox=LABEL_BOX, zorder=3, **style)


def _side(frame: tuple[float, float, float], frames: list[tuple[float, float, float]]) -> float:
    """+1 or -1: the direction along the table edge of `frame` away from the other spots' `frames` facing the same
    way (the spots at that edge; +1, along the positive `along`, where there are none)."""
    ox, oy, ophi = frame
    toward = sum(-(x - ox) * math.sin(ophi) + (y - oy) * math.cos(ophi)
                 for x, y, phi in frames if (x, y) != (ox, oy) and abs(W.wrap(phi - ophi)) < 1e-6)
    return -1.0 if toward > 0 else 1.0


def _along(phi: float) -> float:
    """The reading angle (deg, in (-90, 90]) of a name written along an edge facing `phi`."""
    angle = (math.degrees(phi) + 90.0) % 180.0
    return angle - 180.0 if angle > 90.0 else angle


def draw_scene(ax, sequence, values) -> None:
    """Draw the static kitchen of an instantiated action sequence on a matplotlib axis: the ranges of its free
    spot parameters and their chosen `values` (by parameter id)."""
    from matplotlib.patches import Circle, Polygon, Wedge

    for box in [*W.walls(), W.island()]:
        _box(ax, box, color="0.55", zorder=0, label="wall, island")
    for name, scene_values in sequence.scene.items():
        kind, _, label = name.partition(" ")
        if kind == "table":
            box = W.table_box(*scene_values)
            _box(ax, box, facecolor="burlywood", edgecolor="saddlebrown", zorder=0, label="table")
            back = scene_values[2]  # the robot faces the table at phi: its back lies that way
            reach = box.hx + W.WALL_THICKNESS
            _name(ax, label, box.cx + reach * math.cos(back), box.cy + reach * math.sin(back), back, _along(back))
        elif kind == "cup":
            ax.add_patch(Circle(scene_values, W.CUP_RADIUS * 1.5, color="tab:red", zorder=2, label="cup"))
    spots: dict[str, dict] = {}
    for action in sequence.actions:
        for p in action.params:
            obj, _, quantity = p.id.partition(".")
            spots.setdefault(obj, {})[quantity] = p
    frames = [(q["ox"].value, q["oy"].value, q["ophi"].value) for q in spots.values()
              if all(k in q for k in ("ox", "oy", "ophi"))]
    for obj, q in spots.items():
        if "tx" in q and q["tx"].value is not None:
            ax.plot([q["tx"].value], [q["ty"].value], "x", color="tab:red", ms=6, zorder=2, label="put location")
        if not all(k in q for k in ("ox", "oy", "ophi", "along", "dist", "heading")):
            continue
        along, dist, heading = q["along"], q["dist"], q["heading"]
        if along.value is not None and dist.value is not None:
            continue  # a spot without a free position (the start)
        frame = (q["ox"].value, q["oy"].value, q["ophi"].value)
        corners = [W.spot_pose(*frame, a, d, 0.0)[:2]
                   for a, d in ((along.low, dist.low), (along.high, dist.low), (along.high, dist.high), (along.low, dist.high))]
        if along.value is None and dist.value is None:
            ax.add_patch(Polygon(corners, closed=True, color=RANGE_COLOR, alpha=0.25, zorder=1,
                                 label=f"spot's {along.id.partition('.')[2]}, {dist.id.partition('.')[2]} range"))
        else:  # one free offset (a door spot: across the door): its range is a segment
            free = along if along.value is None else dist
            ax.plot(*zip(corners[0], corners[2]), color=RANGE_COLOR, alpha=0.5, lw=5, solid_capstyle="butt", zorder=1,
                    label=f"spot's {free.id.partition('.')[2]} range")
        at = {p.id: values.get(p.id, p.value) for p in (along, dist, heading)}
        if at[along.id] is None or at[dist.id] is None:
            continue
        side = _side(frame, frames)
        corner = W.spot_pose(*frame, along.high if side > 0 else along.low, dist.high, 0.0)[:2]
        outward = frame[2] + math.pi - side * math.pi / 4  # away from the table and beyond the square's side
        x, y, _ = W.spot_pose(*frame, at[along.id], at[dist.id], 0.0)
        speed = q.get("v")
        label = obj
        if speed is not None and speed.value is None and speed.id in values:  # a way-point passed at a free speed
            label = f"{obj}: {values[speed.id]:.2f} m/s"
        _name(ax, label, *corner, outward, gap=SPOT_LABEL_GAP, color="darkgreen")
        ax.add_patch(Wedge((x, y), SECTOR_RADIUS, math.degrees(frame[2] + heading.low),
                           math.degrees(frame[2] + heading.high), color=RANGE_COLOR, alpha=0.25, zorder=1,
                           label=f"spot's {heading.id.partition('.')[2]} range"))
        phi = frame[2] + (at[heading.id] or 0.0)
        ax.annotate("", xy=(x + SECTOR_RADIUS * math.cos(phi), y + SECTOR_RADIUS * math.sin(phi)), xytext=(x, y),
                    arrowprops={"arrowstyle": "->", "color": "darkgreen"}, zorder=3)
        ax.plot([], [], linestyle="none", marker=r"$\rightarrow$", ms=10, color="darkgreen",
                label=f"chosen {heading.id.partition('.')[2]}")  # the arrows' legend entry
    ax.set_xlim(-MARGIN, W.ROOM_LENGTH + MARGIN)
    ax.set_ylim(-MARGIN, W.ROOM_WIDTH + MARGIN)
