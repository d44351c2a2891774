"""The kitchen domain end to end: its binding instantiates Fig. 5.12's free parameters, places one scene object
per table and cup, its pictures draw the ranges, and `tailor evaluate --situations` switches scenarios."""

from __future__ import annotations

import json
import shutil

import pytest

from tailor.planner_bridge import plan_files, resolve_problem
from tailor.refinement import refine_plots
from tailor.refinement.api import dispatch, refine
from tailor.refinement.binding import load_domain_binding
from tailor.refinement.instantiate import instantiate
from tailor.refinement.belief import load_belief
from tailor.cli.main import main
from tailor.sims import registry


def _sequence(problem: str):
    domain, path = resolve_problem("kitchen", problem)
    return instantiate(plan_files(domain, path), load_domain_binding(domain.parent), load_belief(path.with_suffix(".toml")))


def test_free_parameters_are_the_spots_at_the_tables_in_fig_5_12_ranges_and_the_door_way_point():
    sequence = _sequence("scenario1")
    assert [a.action for a in sequence.actions] == ["navigate", "grip", "navigate", "navigate", "put"]
    free = {p.id: (p.low, p.high) for p in sequence.free_parameters()}
    tables = {f"{s}.{q}": r for s in ("p1", "d1")
              for q, r in (("along", (-0.5, 0.5)), ("dist", (0.4, 0.8)), ("heading", (-1.0, 1.0)))}
    door = {"w1.along": (-0.2, 0.2), "w1.heading": (-0.6, 0.6), "w1.v": (0.0, 0.6)}
    cruise = {f"{s}.cruise": (0.3, 0.6) for s in ("p1", "w1", "d1")}  # of each navigate, at the spot it goes to
    assert free == {**tables, **door, **cruise}
    # the base stops at the tables (v bound to 0) and passes the door on the divider's line (dist bound to 0)
    bound = {p.id: p.value for a in sequence.actions for p in a.params if not p.free}
    assert bound["p1.v"] == bound["d1.v"] == bound["start.v"] == bound["w1.dist"] == 0.0
    # grip's observed group is the spot it stands at, shared with the navigate that reaches it (navigate also
    # reads the spot's speed); the navigate leaving the door starts from the door spot the crossing passes
    goto, grip, cross, leave = sequence.actions[:4]
    assert [p.id for p in goto.params[7:13]] == [p.id for p in grip.params[:6]]
    assert [p.id for p in cross.params[7:14]] == [p.id for p in leave.params[:7]] == [
        f"w1.{q}" for q in ("ox", "oy", "ophi", "along", "dist", "heading", "v")]
    assert [a.params[14].id for a in (goto, cross, leave)] == ["p1.cruise", "w1.cruise", "d1.cruise"]


def test_every_table_and_cup_is_its_own_scene_object():
    sequence = _sequence("scenario2")
    assert set(sequence.scene) == {"robot", "table table1", "table table2", "cup cup1", "cup cup2"}
    assert len(sequence.actions) == 11
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
    door = [line for line in ax.lines if line.get_label() == "spot's along range"]
    assert len(door) == 1 and door[0].get_xdata() == pytest.approx([5.0, 5.0])  # w1's segment across the door
    assert sorted(door[0].get_ydata()) == pytest.approx([2.8, 3.2])
    assert len([p for p in ax.patches if isinstance(p, Wedge)]) == 3  # their and the door's heading sectors
    plt.close(fig)


def test_evaluate_situations_option(capsys):
    assert main(["evaluate", "kitchen", "--situations", "nowhere"]) == 2
    assert "not a situation generator of simulator 'kitchen' (known: scenario1, scenario2)" in capsys.readouterr().err
    assert main(["evaluate", "kitchen", "--situations", "scenario2", "--episodes", "1", "--oracle-episodes", "0",
                 "--horizon-episodes", "0", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["comparison"] == "scenario2" and report["problems"] == ["scenario2"]
    assert [row["action"] for row in report["per_action"]] == (["navigate", "grip", "navigate", "navigate", "put"]
                                                                + ["navigate"] + ["navigate", "grip", "navigate",
                                                                                   "navigate", "put"])
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


def test_the_door_is_passed_at_speed_and_that_is_faster_than_stopping_there(tmp_path):
    """Sec. 5.5's free way-point speed: refinement passes the door without stopping, and in the simulator the
    same plan refined with the door's speed held at 0 (the binding's v range [0, 0]) is slower."""
    stopping = tmp_path / "kitchen"
    shutil.copytree(resolve_problem("kitchen", "scenario1")[0].parent, stopping)
    binding = stopping / "actions.toml"
    text = binding.read_text()
    assert text.count("v = [0.0, 0.6]") == 1  # the door's
    binding.write_text(text.replace("v = [0.0, 0.6]", "v = [0.0, 0.0]"))
    free = refine("kitchen", "scenario1", seed=3)
    held = refine(stopping, "scenario1", seed=3, models=stopping / "models")
    assert free.chosen["w1.v"] > 0.3 and "w1.v" not in held.chosen
    # stopping costs the braking to rest and the speeding up again (about 0.5 s net of the straighter route)
    assert free.predicted_total < held.predicted_total - 0.4
    runs = [dispatch(r, seed=3) for r in (free, held)]
    assert all(run.succeeded for run in runs)
    assert runs[0].duration < runs[1].duration - 0.3


def test_refine_plot_draws_fig_5_9_at_the_door(tmp_path):
    """`tailor refine kitchen scenario1 --plot F.png` also writes F_waypoint.png: the cross and the navigate
    after it over the door's heading and speed (Fig. 5.9)."""
    sequence = _sequence("scenario1")
    step, angle, speed = refine_plots.waypoint_pair(sequence, registry.get("kitchen"))
    assert (step, angle.id, speed.id) == (2, "w1.heading", "w1.v")
    picture = tmp_path / "F.png"
    assert main(["refine", "kitchen", "scenario1", "--plot", str(picture)]) == 0
    assert (tmp_path / "F_waypoint.png").stat().st_size > 0


def test_an_objective_that_weighs_energy_slows_the_base_below_its_top_speed():
    """Ch. 8.1 on the kitchen's cruise speed: duration-only refinement drives every navigate at the top speed;
    weighing energy governs the base below it, and both the predicted and the simulated energy fall by far more
    than the time grows (driving governed, the base no longer follows its noisy command)."""
    fast = refine("kitchen", "scenario1", seed=0)
    frugal = refine("kitchen", "scenario1", seed=0, objective="duration + 0.03*energy")
    cruise = [k for k in fast.chosen if k.endswith(".cruise")]
    assert cruise == ["p1.cruise", "w1.cruise", "d1.cruise"]
    assert all(fast.chosen[k] > 0.59 for k in cruise) and all(frugal.chosen[k] < 0.55 for k in cruise)
    energy = [r.refined.measure_total("energy") for r in (fast, frugal)]
    assert energy[1] < 0.6 * energy[0]
    runs = [dispatch(r, seed=0) for r in (fast, frugal)]
    assert all(run.succeeded for run in runs)
    spent = [sum(r.measures["energy"] for r in run.results) for run in runs]
    assert spent[1] < 0.6 * spent[0] and runs[1].duration < 1.1 * runs[0].duration
