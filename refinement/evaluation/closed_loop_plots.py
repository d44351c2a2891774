"""The learning curve of learning in operation (`tailor evaluate DOMAIN --learning-curve --plot F.png`): per
executed task, the models' relative error on its actions before they ran, and refined vs greedy time."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tailor.outputs import write_atomically


def _moving(values, window: int) -> np.ndarray:
    values = np.asarray(values, dtype=float)
    out = np.full(len(values), np.nan)
    for k in range(len(values)):
        chunk = values[max(0, k - window + 1):k + 1]
        chunk = chunk[np.isfinite(chunk)]
        if len(chunk):
            out[k] = chunk.mean()
    return out


def draw_learning_curve(path, rows: list[dict], errors, report: dict, window: int) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tasks = np.arange(1, len(rows) + 1)
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7.5, 6.5), sharex=True)
    top.plot(tasks, 100 * np.asarray(errors, dtype=float), ".", color="0.6", markersize=4, label="per task")
    top.plot(tasks, 100 * _moving(errors, window), "-", color="tab:blue", label=f"mean of the last {window} tasks")
    top.set_ylabel("duration error (% of measured)")
    top.set_ylim(bottom=0)
    top.legend(fontsize=8)
    top.grid(alpha=0.3)
    bottom.plot(tasks, _moving([r["greedy"] for r in rows], window), "-", color="tab:orange", label="greedy (h=1)")
    bottom.plot(tasks, _moving([r["refined"] for r in rows], window), "-", color="tab:green", label=f"refined (h={report.get('horizon', 2)})")
    bottom.set_xlabel("tasks executed")
    bottom.set_ylabel(f"task time (s), mean of the last {window}")
    bottom.legend(fontsize=8)
    bottom.grid(alpha=0.3)
    variant = report.get("variant")
    fig.suptitle(f"{report['domain']}: learning in operation{' on variant ' + variant if variant else ''}",
                 fontsize=10)
    fig.tight_layout()
    write_atomically(Path(path), lambda tmp: fig.savefig(tmp, dpi=110, format="png"))
    plt.close(fig)
    return Path(path)
