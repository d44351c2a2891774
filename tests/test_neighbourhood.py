"""Robust subgoals: the optimizers minimize the worst predicted cost within a neighbourhood of each choice.

Constructed models with a known narrow dip, checked against brute force of the same worst case; the binding
key and the command-line option reject bad shares in one line.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from rule_models import RuleModel, identity, rule
from tailor.errors import ArgumentValueError
from tailor.refinement.models.model_tree import ModelTree
from tailor.refinement.optimizers import FreeParameter, Objective, Term, optimize
from tailor.refinement.optimizers.objective import neighbourhood_offsets

INF = np.inf
FREE_X = (FreeParameter("x", 0.0, 1.0),)
# x in [0, 1]: a broad valley down to 5 s at 0.3, and a dip 0.02 wide at 0.8 down to 3 s
DIP = RuleModel([rule([-INF], [0.3], [-10.0], 8.0), rule([0.3], [0.79], [10.0], 2.0),
                 rule([0.79], [0.81], [0.0], 3.0), rule([0.81], [INF], [10.0], 2.0)])


def test_without_a_neighbourhood_every_optimizer_takes_the_dip():
    for method in ("analytic", "ga", "sample"):
        result = optimize(Objective(FREE_X, (Term(DIP, identity),)), method=method, seed=1)
        assert 0.79 <= result.values[0] <= 0.81 and result.cost == pytest.approx(3.0), method


@pytest.mark.parametrize("method", ["analytic", "ga", "sample"])
def test_with_a_neighbourhood_wider_than_the_dip_the_valley_wins(method):
    objective = Objective(FREE_X, (Term(DIP, identity),), neighbourhood=(0.05,))
    result = optimize(objective, method=method, seed=1)
    x = result.values[0]
    # the worst case within 0.05 of 0.3 is 5.5 s (either side of the valley), anywhere near the dip 10 s
    assert abs(x - 0.3) < 0.01, method
    assert result.cost == pytest.approx(float(objective.robust_cost(np.array([[x]]))[0]))
    assert result.cost < 5.5 + 0.1 and "neighbourhood" in result.note


def test_the_worst_case_is_taken_over_the_stencil_within_the_ranges():
    objective = Objective(FREE_X, (Term(DIP, identity),), neighbourhood=(0.1,))
    offsets = neighbourhood_offsets(np.array([0.1]))
    np.testing.assert_allclose(sorted(offsets[:, 0]), [-0.1, -0.05, 0.0, 0.05, 0.1])
    # at 0.0 the stencil is clipped to [0, 0.1]: the worst is 8 s at 0 itself, not a value from outside
    assert objective.robust_cost(np.array([[0.0]]))[0] == pytest.approx(8.0)
    assert objective.robust_cost(np.array([[0.8]]))[0] == pytest.approx(max(DIP.predict(np.array([[0.9]]))[0], 7.0))
    assert objective.robust_cost(np.array([[0.8]]))[0] > objective.cost(np.array([[0.8]]))[0]
    plain = Objective(FREE_X, (Term(DIP, identity),))
    np.testing.assert_array_equal(plain.robust_cost(np.array([[0.2], [0.8]])), plain.cost(np.array([[0.2], [0.8]])))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_analytic_worst_case_is_as_good_as_brute_force_finds(seed):
    """Two free parameters, a fitted model tree with steps: the analytic candidates (every box's cheapest
    corner, that corner moved the radius inward, its middle) reach the worst-case minimum of a 201 x 201
    grid within 1%."""
    rng = np.random.default_rng(seed)
    X = rng.uniform(0, 1, size=(2000, 2))
    y = 3 + 2 * (X[:, 0] > 0.4) - 1.5 * X[:, 1] + 1.2 * (X[:, 1] > 0.7) + 0.5 * X[:, 0] + 1.0 * (
        np.abs(X[:, 0] - 0.2) < 0.03)
    tree = ModelTree(min_samples_leaf=20).fit(X, y)
    free = (FreeParameter("a", 0.0, 1.0), FreeParameter("b", 0.0, 1.0))
    objective = Objective(free, (Term(tree, identity),), neighbourhood=(0.04, 0.04))
    result = optimize(objective, method="analytic")
    assert result.method == "analytic"
    axes = np.linspace(0, 1, 201)
    grid = np.stack(np.meshgrid(axes, axes, indexing="ij"), axis=-1).reshape(-1, 2)
    best = objective.robust_cost(grid).min()
    assert result.cost <= best * 1.01
    assert result.cost == pytest.approx(float(objective.robust_cost(np.array([result.values]))[0]))


def test_refine_checks_the_share():
    from tailor.refinement.refine import refine
    from test_refine import SCORE, _sequence

    with pytest.raises(ArgumentValueError, match="neighbourhood must be a share"):
        refine(_sequence("score_plan.json", SCORE), {}, neighbourhood=0.5)


def test_a_bad_share_in_the_binding_is_one_line(tmp_path):
    import shutil

    from tailor.errors import BindingError
    from tailor.planner_bridge import resolve_domain_dir
    from tailor.refinement.binding import load_domain_binding

    domain = tmp_path / "soccer"
    shutil.copytree(resolve_domain_dir("soccer"), domain, ignore=shutil.ignore_patterns("models", "training"))
    binding = domain / "actions.toml"
    binding.write_text(binding.read_text().replace("neighbourhood = 0.02", "neighbourhood = 0.7"))
    with pytest.raises(BindingError, match=r"\[refinement\] neighbourhood must be a share .* not 0.7") as error:
        load_domain_binding(domain)
    assert "\n" not in str(error.value) and str(binding) in str(error.value)


def test_the_refine_command_rejects_a_bad_share(capsys):
    from tailor.cli.main import main

    with pytest.raises(SystemExit) as exit_:
        main(["refine", "soccer", "score", "--neighbourhood", "0.6"])
    assert exit_.value.code != 0
    err = capsys.readouterr().err
    assert "--neighbourhood" in err and "[0, 0.5)" in err and "Traceback" not in err


def test_refine_minimizes_the_worst_case_around_the_soccer_subgoal(capsys):
    """The bundled soccer binding's neighbourhood (2% of each range): the window's cost is the worst predicted
    total within it, at least the total at the chosen values; without it the cost is that total."""
    from tailor.cli.main import main

    runs = {}
    for share in (None, "0"):
        extra = [] if share is None else ["--neighbourhood", share]
        assert main(["refine", "soccer", "score", "--risk", "0", "--json", *extra]) == 0
        runs[share] = json.loads(capsys.readouterr().out)
    robust, plain = runs[None]["refined"], runs["0"]["refined"]
    assert (robust["neighbourhood"], plain["neighbourhood"], runs[None]["greedy"]["neighbourhood"]) == (0.02, 0.0, 0.0)
    assert plain["optimization"][0]["cost"] == pytest.approx(plain["predicted_total"], abs=1e-3)
    assert robust["optimization"][0]["cost"] >= robust["predicted_total"] - 1e-3
    assert "neighbourhood" in robust["optimization"][0]["note"]
    assert plain["predicted_total"] <= robust["predicted_total"] + 1e-3  # the point optimum is predicted faster


def test_the_api_takes_the_neighbourhood_and_checks_it():
    import tailor
    from tailor.errors import ArgumentTypeError

    default, plain = tailor.refine("soccer", "score"), tailor.refine("soccer", "score", neighbourhood=0.0)
    assert (default.refined.neighbourhood, plain.refined.neighbourhood) == (0.02, 0.0)  # the binding's, else given
    assert default.to_json()["neighbourhood"] == 0.02 and plain.to_json()["risk"] == 1.0
    with pytest.raises(ArgumentValueError, match="neighbourhood must be a share"):
        tailor.refine("soccer", "score", neighbourhood=0.9)
    with pytest.raises(ArgumentTypeError, match="neighbourhood must be a number or None"):
        tailor.refine("soccer", "score", neighbourhood="0.1")
