"""The picture of `tailor execute --plot`: the executed run as the robot logged it, one colour per action, a
failed action dashed red, and where the loop re-refined or replanned."""

from __future__ import annotations

from pathlib import Path

from tailor.outputs import write_atomically


def _pairs(view) -> list[tuple[str, str]]:
    """The (x, y) column pairs of a simulator's view: a pair, or layers whose first two columns are x, y."""
    if view and isinstance(view[0], str):
        return [tuple(view[:2])]
    return [tuple(layer[:2]) for layer in view]


def draw_run(events, domain: str, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from tailor.sims import registry

    executed = [e for e in events if e.kind == "executed" and e.log is not None]
    entry = registry.get(executed[0].simulator) if executed else None
    views = list(entry.views) if entry is not None else []
    pairs = [p for p in (_pairs(views[0]) if views else []) if executed and all(c in executed[0].log.columns
                                                                                   for c in p)]
    if not pairs and executed:
        pairs = [tuple(executed[0].log.columns[:2])]
    fig, ax = plt.subplots(figsize=(7, 5.5))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    note = None
    for k, event in enumerate(events):
        if event.kind in ("re-refined", "replanned"):
            note = event.kind
            continue
        if event.kind != "executed" or event.log is None:
            continue
        log = event.log
        for j, (cx, cy) in enumerate(pairs[:1]):
            x, y = log.column(cx), log.column(cy)
            failed = event.outcome != "success"
            ax.plot(x, y, "--" if failed else "-", color="tab:red" if failed else colours[k % len(colours)],
                    label=f"{event.pddl}: {event.measured:.2f} s ({event.outcome})")
            if note is not None and len(x):
                ax.plot(x[0], y[0], "o" if note == "re-refined" else "s", color="black", markersize=7,
                        fillstyle="none", label=note)
            if failed and len(x):
                ax.plot(x[-1], y[-1], "x", color="tab:red", markersize=9)
        note = None
    if pairs:  # each axis its own quantity's unit, as the simulator declares it
        from tailor.refinement.refine_plots import axis_label
        from tailor.sims.protocol import UNDECLARED

        for name, set_label in zip(pairs[0], (ax.set_xlabel, ax.set_ylabel)):
            set_label(axis_label(name, entry.quantity(name) if entry is not None else UNDECLARED))
        ax.set_aspect("equal", adjustable="datalim")
    handles, labels = ax.get_legend_handles_labels()
    unique = dict(zip(labels, handles))
    ax.legend(unique.values(), unique.keys(), fontsize=8, loc="best")
    end = next((e for e in reversed(events) if e.kind == "finished"), None)
    ax.set_title(f"tailor execute {domain}: {end.outcome if end else 'stopped'}", fontsize=10)
    ax.grid(alpha=0.3)
    write_atomically(path, lambda tmp: fig.savefig(tmp, dpi=110, format="png"))
    plt.close(fig)
    return path
