"""The time-energy front (`tailor evaluate DOMAIN --pareto W1,W2,... --plot F.png`): measured mean time against
measured mean energy for greedy and each energy weight, the non-dominated points joined and marked."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tailor.outputs import write_atomically

DPI = 110
FONT = 8  # pt, the points' labels
# where a label may sit beside its point (offset in pt), tried in turn until it overlaps no label or point placed
OFFSETS = ((7, 4), (7, -11), (-7, 4), (-7, -11), (7, 15), (7, -22), (-7, 15), (-7, -22), (7, 26), (7, -33))


def draw_pareto(path, report: dict, units: dict[str, str]) -> Path:
    """One point per run kind (greedy, each weight W of `duration + W * energy`), energy (x) against time (y),
    both the means over the same situations; the front's points ringed and joined."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    points = [("greedy (h=1)", report["greedy"])] + [(f"W={e['weight']:g}", e) for e in report["pareto"]]
    points = [(label, p) for label, p in points if p["energy"] is not None and p["duration"] is not None]
    fig, ax = plt.subplots(figsize=(6.8, 4.8))
    for label, p in points:
        greedy = label.startswith("greedy")
        ax.plot(p["energy"], p["duration"], "s" if greedy else "o", color="tab:orange" if greedy else "tab:blue",
                markersize=7, zorder=3)
    on_front = sorted((p["energy"], p["duration"]) for _, p in points if p.get("front"))
    ax.plot([], [], "s", color="tab:orange", label="greedy (h=1), duration")
    ax.plot([], [], "o", color="tab:blue", label="refined (h=2), duration + W * energy")
    xs, ys = zip(*on_front) if on_front else ((), ())
    ax.plot(xs, ys, color="tab:red", alpha=0.7, zorder=4, marker="o", markersize=14, markerfacecolor="none",
            label="front (non-dominated)")
    ax.margins(0.12)
    ax.autoscale_view()
    _label(ax, points)
    ax.set_xlabel(f"measured mean energy ({units.get('energy', '?')})")
    ax.set_ylabel(f"measured mean time ({units.get('duration', 's')})")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    ax.set_title(f"{report['domain']}: refined for duration + W * energy over {report['episodes']} '"
                 f"{report['comparison']}' situations", fontsize=9)
    fig.tight_layout()
    write_atomically(Path(path), lambda tmp: fig.savefig(tmp, dpi=DPI, format="png"))
    plt.close(fig)
    return Path(path)


def _label(ax, points: list[tuple[str, dict]]) -> None:
    """Each point's label beside it, at the first of OFFSETS where its box (estimated from the text's length)
    overlaps no label placed before and no point: points close together (two weights choosing alike) stay
    legible."""
    scale = DPI / 72.0
    height, width = FONT * 1.3 * scale, FONT * 0.62 * scale  # a label's line height, a character's width (px)
    pixels = ax.transData.transform(np.array([[p["energy"], p["duration"]] for _, p in points], dtype=float))
    radius = 7 * scale  # a marker's half size (px)
    boxes = [(x - radius, y - radius, x + radius, y + radius) for x, y in pixels]

    def clear(box) -> bool:
        return not any(box[0] < b[2] and b[0] < box[2] and box[1] < b[3] and b[1] < box[3] for b in boxes)

    for (label, p), (x, y) in zip(points, pixels):
        wide = width * len(label)
        for dx, dy in OFFSETS:
            left = x + dx * scale if dx >= 0 else x + dx * scale - wide
            box = (left, y + dy * scale, left + wide, y + dy * scale + height)
            if clear(box):
                break
        boxes.append(box)
        ax.annotate(label, (p["energy"], p["duration"]), textcoords="offset points", xytext=(dx, dy), fontsize=FONT,
                    ha="left" if dx >= 0 else "right", va="bottom")
