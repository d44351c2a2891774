"""The kitchen domain end to end: its binding instantiates Fig. 5.12's free parameters, places one scene object
per table and cup, its pictures draw the ranges, and `tailor evaluate --situations` switches scenarios."""

from __future__ import annotations

import json

from tailor.planner_bridge import plan_files, resolve_problem
from tailor.refinement.binding import load_domain_binding
from tailor.refinement.instantiate import instantiate
from tailor.refinement.belief import load_belief
from tailor.cli.main import main
from tailor.sims import registry


def _sequence(problem: str):
    domain, path = resolve_problem("kitchen", problem)
    return instantiate(plan_files(domain, path), load_domain_binding(domain.parent), load_belief(path.with_suffix(".toml")))


def test_free_parameters_are_the_spots_at_the_tables_in_fig_5_12_ranges():
    sequence = _sequence("scenario1")
    assert [a.action for a in sequence.actions] == ["navigate", "grip", "navigate", "put"]
    free = {p.id: (p.low, p.high) for p in sequence.free_parameters()}
    assert free == {f"{s}.{q}": r for s in ("p1", "d1")
                    for q, r in (("along", (-0.5, 0.5)), ("dist", (0.4, 0.8)), ("heading", (-1.0, 1.0)))}
    # grip's observed group is the spot it stands at, shared with the navigate that reaches it
    goto, grip = sequence.actions[0], sequence.actions[1]
    assert [p.id for p in goto.params[6:]] == [p.id for p in grip.params[:6]]


def test_every_table_and_cup_is_its_own_scene_object():
    sequence = _sequence("scenario2")
    assert set(sequence.scene) == {"robot", "table table1", "table table2", "cup cup1", "cup cup2"}
    assert len(sequence.actions) == 8
    sim = registry.get("kitchen").create(0)
    sim.reset(dict(sequence.scene))
    assert set(sim.tables) == {"table1", "table2"} and set(sim.cups) == {"cup1", "cup2"}


def test_a_table_placed_outside_its_type_range_is_a_belief_error(tmp_path):
    """Scene values are read within the object's type range ([types.furniture]), as a cup's are."""
    import pytest

    from tailor.errors import EmptyRangeError

    domain, path = resolve_problem("kitchen", "scenario1")
    text = path.with_suffix(".toml").read_text().replace("[objects.table1]\nox = 2.5236", "[objects.table1]\nox = 1e9")
    belief = tmp_path / "scenario1.toml"
    belief.write_text(text)
    with pytest.raises(EmptyRangeError, match=r"table1.ox = 1e\+09 read for \(table table1\) lies outside its "
                                              r"range \[-1, 11\] from \[types.furniture\]"):
        instantiate(plan_files(domain, path), load_domain_binding(domain.parent), load_belief(belief))


def test_draw_scene_draws_furniture_and_the_ranges_of_each_spot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Polygon, Wedge

    sequence = _sequence("scenario1")
    values = {p.id: (p.low + p.high) / 2 for p in sequence.free_parameters()}
    fig, ax = plt.subplots()
    registry.get("kitchen").draw_scene(ax, sequence, values)
    green = [p for p in ax.patches if isinstance(p, Polygon) and p.get_alpha() == 0.25]
    assert len(green) == 2  # the square areas of p1 and d1 (the start has no free parameters)
    assert len([p for p in ax.patches if isinstance(p, Wedge)]) == 2  # their heading sectors
    plt.close(fig)


def test_evaluate_situations_option(capsys):
    assert main(["evaluate", "kitchen", "--situations", "nowhere"]) == 2
    assert "not a situation generator of simulator 'kitchen' (known: scenario1, scenario2)" in capsys.readouterr().err
    assert main(["evaluate", "kitchen", "--situations", "scenario2", "--episodes", "1", "--oracle-episodes", "0",
                 "--horizon-episodes", "0", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["comparison"] == "scenario2" and report["problems"] == ["scenario2"]
    assert [row["action"] for row in report["per_action"]] == ["navigate", "grip", "navigate", "put"] * 2
    assert report["episodes"] == 1 and report["refined_mean"] < report["greedy_mean"]


def test_refine_plot_draws_the_scene_under_both_executions(tmp_path, monkeypatch):
    from dataclasses import replace

    entry = registry.get("kitchen")
    calls = []

    def spy(ax, sequence, values):
        calls.append(sorted(k for k in values if k.startswith("p1.") and k[3:] in ("along", "dist", "heading")))
        entry.draw_scene(ax, sequence, values)

    real_get = registry.get
    monkeypatch.setattr(registry, "get", lambda name: replace(entry, draw_scene=spy) if name == "kitchen" else real_get(name))
    picture = tmp_path / "F.png"
    assert main(["refine", "kitchen", "scenario1", "--plot", str(picture)]) == 0
    assert picture.stat().st_size > 0
    assert calls == [["p1.along", "p1.dist", "p1.heading"]] * 2  # greedy and refined panels
