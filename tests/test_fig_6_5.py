"""Fig. 6.5: the search space of subgoal refinement in subgoal assertion, the predicted durations of both actions
through the asserted subgoal and their sum over the subgoal's position, invalid values (the second action predicted
to fail, Alg. 6) not rendered; drawn by `tailor evaluate soccer --assertion --plot FILE.png`."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tailor.refinement.evaluation.assertion_plots import (asserted_pair, draw_search_space, search_space,
                                                          search_space_figure, search_space_name)
from tailor.refinement.pipeline import prepare, read_task, resolve_task
from tailor.refinement.refine import refine
from tailor.sims import registry


@pytest.fixture(scope="module")
def approach():
    """The approach problem's belief asserts a subgoal; refined (sampling: fast) with it."""
    prepared = prepare(read_task(resolve_task("soccer", "approach")))
    refined = refine(prepared.sequence, prepared.models, 2, "sample", 0, prepared.success_models)
    return prepared, refined


def test_three_series_the_second_and_the_sum_masked_where_failure_is_predicted(approach):
    prepared, refined = approach
    entry = registry.get(prepared.sequence.simulator)
    space = search_space(prepared.sequence, refined.sequence, prepared.models, prepared.success_models, entry,
                         points=41)
    assert space.axes == ("subgoal1.x", "subgoal1.y")  # the ground plane: the subgoal's quantities that are no angle
    (t1, first), (t2, second), (t3, total) = space.series
    assert "start to subgoal" in t1 and "Alg. 6" in t2 and t3 == "sum of both"
    assert first.shape == second.shape == total.shape == (41, 41)
    invalid = ~space.valid
    assert 0.05 < invalid.mean() < 0.95  # a region the classifier predicts to fail, and one it does not
    assert not np.ma.getmaskarray(first).any()  # the first action is not guarded: all of it drawn
    assert np.array_equal(np.ma.getmaskarray(second), invalid) and np.array_equal(np.ma.getmaskarray(total), invalid)
    assert np.allclose(total.filled(0.0), (first + second).filled(0.0))
    # the mask is the classifier's verdict on the second action (subgoal -> ball) at each grid point
    first_action, second_action = (prepared.sequence.actions[k] for k in asserted_pair(prepared.sequence))
    chosen = {p.id: p.value for a in refined.sequence.actions for p in a.params}
    classifier = prepared.success_models[second_action.guard]
    for i, j in [(0, 0), (20, 20), (40, 13), (7, 33), (30, 2)]:
        point = {**chosen, "subgoal1.x": float(space.xs[j]), "subgoal1.y": float(space.ys[i])}
        assert classifier.predict_success(second_action.values(point)[None, :])[0] == space.valid[i, j]
        assert prepared.models["goToPose"].predict_duration(first_action.values(point)[None, :])[0] == \
            pytest.approx(first[i, j])
    # the refined subgoal, marked, lies in the valid region; the start and the ball are marked
    assert space.chosen == (chosen["subgoal1.x"], chosen["subgoal1.y"])
    assert [name for name, _, _ in space.marks] == ["start (pos1)", "goal (pos2)"]


def test_the_figure_leaves_the_invalid_region_blank(approach, tmp_path):
    from matplotlib.collections import QuadMesh

    prepared, refined = approach
    space = search_space(prepared.sequence, refined.sequence, prepared.models, prepared.success_models, points=31)
    fig = search_space_figure(space, "Fig. 6.5")
    panels = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"
              and any(isinstance(c, QuadMesh) for c in ax.collections)]
    assert len(panels) == 3
    masked = [int(np.ma.getmaskarray(next(c for c in ax.collections if isinstance(c, QuadMesh)).get_array()).sum())
              for ax in panels]
    assert masked == [0, int((~space.valid).sum()), int((~space.valid).sum())] and masked[1] > 0
    assert "predicted to fail" in panels[1].get_title() and "predicted to fail" not in panels[0].get_title()
    path = draw_search_space(tmp_path / "fig.png", space)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_no_search_space_without_an_asserted_subgoal(approach):
    prepared, refined = approach
    assert asserted_pair(prepared.instantiated) is None
    assert search_space(prepared.instantiated, refined.sequence, prepared.models, prepared.success_models) is None


def test_evaluate_assertion_plot_writes_fig_6_5_beside_fig_6_6(tmp_path, capsys):
    from tailor.cli.main import main

    plot = tmp_path / "assertion.png"
    assert main(["evaluate", "soccer", "--assertion", "--episodes", "3", "--plot", str(plot), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["plot"] == str(plot) and plot.is_file()
    assert data["plot_search_space"] == str(search_space_name(plot)) == str(tmp_path / "assertion_search_space.png")
    assert search_space_name(plot).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert data["plot_search_space_situation"] in data["plot_situations"]
