"""Action instantiation (Algorithm 3) and the ActionSequence it builds."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from tailor.planner_bridge.abstract_plan import AbstractPlan, CausalLink, Step
from tailor.refinement.action_sequence import ActionSequence, ExecutableAction, Parameter
from tailor.refinement.belief import load_belief, parse_belief
from tailor.refinement.binding import load_domain_binding, parse_binding
from tailor.errors import BeliefError, BindingError, EmptyRangeError, TailorError
from tailor.refinement.instantiate import instantiate

ROOT = Path(__file__).resolve().parents[1]
SOCCER = ROOT / "domains" / "soccer"
FIXTURES = Path(__file__).parent / "fixtures" / "binding"
PI = math.pi


def plan_fixture(name: str) -> AbstractPlan:
    return AbstractPlan.from_json(json.loads((FIXTURES / f"{name}_plan.json").read_text()))


def soccer(problem: str) -> ActionSequence:
    return instantiate(plan_fixture(problem), load_domain_binding(SOCCER),
                       load_belief(SOCCER / "problems" / f"{problem}.toml"))


def table(action: ExecutableAction) -> dict[str, object]:
    """name -> value if bound, (low, high) if free."""
    return {p.name: p.value if not p.free else (p.low, p.high) for p in action.params}


# ---- Fig. 5.6 / Algorithm 3 -------------------------------------------------------------------------

def test_score_matches_the_comment_under_algorithm_3():
    seq = soccer("score")
    assert [(a.step, a.pddl, a.action) for a in seq.actions] == [
        (1, "(approachball pos1 pos2)", "goToPose"), (2, "(dribbleball pos2 pos3)", "dribbleBall")]
    # goToPose(x=0,y=1,phi=0,v=0, xg=3,yg=1,phig=[-pi,pi],vg=[0,0.3])
    assert table(seq.actions[0]) == {"x": 0.0, "y": 1.0, "phi": 0.0, "v": 0.0,
                                     "xg": 3.0, "yg": 1.0, "phig": (-PI, PI), "vg": (0.0, 0.3)}
    # dribbleBall(x=3,y=1,phi=[-pi,pi],v=[0,0.3], xg=1,yg=3,phig=2.6,vg=0)
    assert table(seq.actions[1]) == {"x": 3.0, "y": 1.0, "phi": (-PI, PI), "v": (0.0, 0.3),
                                     "xg": 1.0, "yg": 3.0, "phig": 2.6, "vg": 0.0}
    assert dict(seq.scene) == {"robot": (0.0, 1.0, 0.0, 0.0), "ball": (3.0, 1.0)}
    assert (seq.domain, seq.problem, seq.simulator) == ("soccer", "score", "soccer")


def test_score_golden_json():
    golden = json.loads((FIXTURES / "score_sequence.json").read_text())
    assert soccer("score").to_json() == golden


def test_goal_pose_of_approach_is_start_pose_of_dribble_one_id():
    seq = soccer("score")
    approach, dribble = seq.actions
    assert [p.id for p in approach.params[4:]] == [p.id for p in dribble.params[:4]] == [
        "pos2.x", "pos2.y", "pos2.phi", "pos2.v"]
    assert [p.id for p in approach.params[:4]] == ["pos1.x", "pos1.y", "pos1.phi", "pos1.v"]
    assert [(p.id, p.low, p.high) for p in seq.free_parameters()] == [
        ("pos2.phi", -PI, PI), ("pos2.v", 0.0, 0.3)]


def test_bound_values_carry_their_composed_range():
    approach, dribble = soccer("score").actions
    # pos3.v is read (final, from step 0) and bounded by atball (from step 2): value 0 in [0, 0.3]
    assert dribble.params[7] == Parameter("pos3.v", "vg", 0.0, 0.0, 0.3)
    assert approach.params[0] == Parameter("pos1.x", "x", 0.0, -4.0, 4.0)  # field default


def test_waypoint_chain_shares_ids_and_frees_heading_and_speed():
    seq = soccer("waypoints")
    assert [a.action for a in seq.actions] == ["goToPose"] * 4
    for before, after in zip(seq.actions, seq.actions[1:]):
        assert [p.id for p in before.params[4:]] == [p.id for p in after.params[:4]]
    assert [p.id for p in seq.free_parameters()] == [
        "w1.phi", "w1.v", "w2.phi", "w2.v", "w3.phi", "w3.v"]
    assert all((p.low, p.high) in [(-PI, PI), (0.0, 0.6)] for p in seq.free_parameters())
    assert table(seq.actions[0]) == {"x": -3.0, "y": -1.0, "phi": 0.0, "v": 0.0,
                                     "xg": -2.0, "yg": 0.5, "phig": (-PI, PI), "vg": (0.0, 0.6)}
    assert table(seq.actions[3]) == {"x": 1.0, "y": 0.5, "phi": (-PI, PI), "v": (0.0, 0.6),
                                     "xg": 2.5, "yg": -0.5, "phig": -0.588, "vg": 0.0}
    assert dict(seq.scene) == {"robot": (-3.0, -1.0, 0.0, 0.0)}


# ---- ActionSequence ---------------------------------------------------------------------------------

def test_json_round_trip_is_exact():
    for problem in ("score", "waypoints"):
        seq = soccer(problem)
        text = json.dumps(seq.to_json())
        again = ActionSequence.from_json(json.loads(text))
        assert again == seq
        assert json.dumps(again.to_json()) == text


def test_from_json_rejects_other_schema_and_malformed():
    data = soccer("score").to_json()
    with pytest.raises(TailorError, match="schema 2"):
        ActionSequence.from_json({**data, "schema": 2})
    del data["actions"][0]["params"][0]["low"]
    with pytest.raises(TailorError, match="malformed action sequence JSON"):
        ActionSequence.from_json(data)


def test_values_take_free_parameters_from_the_assignment():
    approach, dribble = soccer("score").actions
    assignment = {"pos2.phi": 1.25, "pos2.v": 0.2}
    np.testing.assert_array_equal(approach.values(assignment), [0, 1, 0, 0, 3, 1, 1.25, 0.2])
    np.testing.assert_array_equal(dribble.values(assignment), [3, 1, 1.25, 0.2, 1, 3, 2.6, 0])
    with pytest.raises(TailorError,
                       match=r"no value for free parameter 'pos2.phi' \(phig of goToPose, step 1\)"):
        approach.values({"pos2.v": 0.2})


def test_bind_sets_every_use_of_a_shared_parameter():
    seq = soccer("score").bind({"pos2.phi": -0.5, "pos2.v": 0.3 + 1e-12})
    assert seq.free_parameters() == ()
    approach, dribble = seq.actions
    assert approach.params[6] == Parameter("pos2.phi", "phig", -0.5, -PI, PI)
    assert dribble.params[2] == Parameter("pos2.phi", "phi", -0.5, -PI, PI)
    assert approach.params[7].value == dribble.params[3].value == 0.3  # clipped from rounding noise
    np.testing.assert_array_equal(dribble.values(), [3, 1, -0.5, 0.3, 1, 3, 2.6, 0])


def test_bind_partial_and_errors():
    seq = soccer("waypoints")
    part = seq.bind({"w1.phi": 0.1, "w1.v": 0.5}, partial=True)
    assert [p.id for p in part.free_parameters()] == ["w2.phi", "w2.v", "w3.phi", "w3.v"]
    with pytest.raises(TailorError, match=r"no value for free parameter\(s\) w2.phi, w2.v, w3.phi, w3.v"):
        seq.bind({"w1.phi": 0.1, "w1.v": 0.5})
    with pytest.raises(TailorError, match="cannot bind 'w9.phi': not a free parameter"):
        seq.bind({"w9.phi": 0.0}, partial=True)
    with pytest.raises(TailorError, match="cannot bind 'p0.x': not a free parameter"):
        seq.bind({"p0.x": 0.0}, partial=True)
    with pytest.raises(EmptyRangeError, match=r"value 1.5 for 'w1.v' lies outside its range \[0, 0.6\]"):
        seq.bind({"w1.v": 1.5}, partial=True)
    with pytest.raises(EmptyRangeError, match="value nan for 'w1.v' is not a finite number"):
        seq.bind({"w1.v": float("nan")}, partial=True)


# ---- the general case -------------------------------------------------------------------------------

TOY = """
schema = 2
simulator = "soccer"

[actions.move]
executable = "goToPose"
observed = 0
internal = 2

[predicates.at]
read = ["x", "y", "phi", "v"]
scene = "robot"

[predicates.slow]
v = [0.0, 0.4]

[predicates.calm]
v = [0.2, 0.6]
phi = [0.5, 0.5]

[predicates.spot]
read = ["x", "y"]
args = [1]

[predicates.pose]
read = ["x", "y", "phi", "v"]

[predicates.moving]
v = [0.2, 0.6]

[types.place]
x = [-2.0, 2.0]
y = [-1.0, 1.0]

[types.room]
phi = ["-pi", "pi"]

[types.default]
x = [-9.0, 9.0]
y = [-9.0, 9.0]
phi = [-3.0, 3.0]
v = [0.0, 2.0]
"""

BELIEF = {"objects": {"a": {"x": 0.5, "y": -0.5, "phi": 0.0, "v": 0.0}, "b": {"x": 1.0, "y": 0.25},
                      "c": {"x": 3.0, "y": 4.0, "phi": 9.0, "v": 0.0}}}


def toy(links, args=("a", "x", "b"), binding_text=TOY, belief=BELIEF, **kwargs) -> ActionSequence:
    import tomllib

    plan = AbstractPlan("toy", "p", "hand", (Step(1, "move", args),), tuple(links), ())
    binding = parse_binding(tomllib.loads(binding_text), "toy.toml")
    return instantiate(plan, binding, parse_belief(belief, "toy_belief.toml"), **kwargs)


def test_object_without_links_is_free_in_type_defaults_and_unbound_predicates_are_ignored():
    seq = toy([CausalLink(0, ("at", "a"), 1), CausalLink(0, ("near", "a", "b"), 1)],
              object_types={"a": "place", "b": ("place", "room")})
    assert table(seq.actions[0]) == {"x": 0.5, "y": -0.5, "phi": 0.0, "v": 0.0, "xg": (-2.0, 2.0),
                                     "yg": (-1.0, 1.0), "phig": (-PI, PI), "vg": (0.0, 2.0)}


def test_type_chain_defaults_and_fallback_to_default_type():
    links = [CausalLink(0, ("at", "a"), 1)]
    # several named types and no object_types: only [types.default] applies
    assert table(toy(links).actions[0])["xg"] == (-9.0, 9.0)
    # parent chain: room gives phi, place gives x, default gives v
    got = table(toy(links, object_types={"b": ["room", "place"]}).actions[0])
    assert (got["xg"], got["phig"], got["vg"]) == ((-2.0, 2.0), (-PI, PI), (0.0, 2.0))


def test_ranges_intersect_degenerate_range_binds_and_read_on_second_argument():
    links = [CausalLink(0, ("at", "a"), 1), CausalLink(1, ("slow", "b"), "goal"),
             CausalLink(1, ("calm", "b"), "goal"), CausalLink(0, ("spot", "a", "b"), 1)]
    seq = toy(links)
    got = table(seq.actions[0])
    assert (got["xg"], got["yg"], got["phig"], got["vg"]) == (1.0, 0.25, 0.5, (0.2, 0.4))
    assert [p.id for p in seq.free_parameters()] == ["b.v"]


def test_several_read_predicates_compose():
    # b is read by `spot` (x, y, from step 0) and by `pose` (x, y, phi, v) -- needs b.phi and b.v too
    belief = {"objects": {**BELIEF["objects"], "b": {"x": 1.0, "y": 0.25, "phi": 0.3, "v": 0.1}}}
    links = [CausalLink(0, ("at", "a"), 1), CausalLink(0, ("spot", "a", "b"), 1),
             CausalLink(0, ("pose", "b"), 1)]
    got = table(toy(links, belief=belief).actions[0])
    assert (got["xg"], got["yg"], got["phig"], got["vg"]) == (1.0, 0.25, 0.3, 0.1)


def test_read_only_from_facts_of_the_initial_state():
    # (at b) produced by step 1 reads nothing; b stays free
    got = table(toy([CausalLink(0, ("at", "a"), 1), CausalLink(1, ("at", "b"), "goal")]).actions[0])
    assert got["xg"] == (-9.0, 9.0) and got["vg"] == (0.0, 2.0)


def test_scene_from_initial_state_facts():
    seq = toy([CausalLink(0, ("at", "a"), 1)], initial_state=[("at", "a"), ("spot", "a", "b")])
    assert dict(seq.scene) == {"robot": (0.5, -0.5, 0.0, 0.0)}
    with pytest.raises(BindingError, match=r"toy.toml: scene object 'robot' placed twice in the initial "
                                           r"state: \(at a\) and \(at c\)"):
        toy([CausalLink(0, ("at", "a"), 1)], initial_state=[("at", "c")])


def test_empty_intersection_is_an_empty_range_error():
    text = TOY + "\n[predicates.fast]\nv = [0.5, 1.0]\n"
    links = [CausalLink(0, ("at", "a"), 1), CausalLink(1, ("slow", "b"), "goal"),
             CausalLink(1, ("fast", "b"), "goal")]
    with pytest.raises(EmptyRangeError, match=r"^toy.toml: b.v: the ranges \(slow b\) \[0, 0.4\], "
                                              r"\(fast b\) \[0.5, 1\] do not intersect$"):
        toy(links, binding_text=text)


def test_read_value_outside_its_range_is_an_empty_range_error():
    # c.x = 3 is outside [types.place] x = [-2, 2]
    with pytest.raises(EmptyRangeError, match=r"^toy_belief.toml: c.x = 3 read for \(at c\) lies outside its "
                                              r"range \[-2, 2\] from \[types.place\] \[-2, 2\]$"):
        toy([CausalLink(0, ("at", "c"), 1)], args=("c", "x", "b"), object_types={"c": "place"})
    with pytest.raises(EmptyRangeError,
                       match=r"a.v = 0 read for \(at a\) lies outside its range \[0.2, 0.6\]"):
        toy([CausalLink(0, ("at", "a"), 1), CausalLink(0, ("moving", "a"), 1)])


def test_no_range_anywhere_is_a_binding_error():
    text = TOY.replace('[types.default]\nx = [-9.0, 9.0]\n', '[types.default]\n')
    with pytest.raises(BindingError, match=r"toy.toml: no range for b.x: no predicate on its causal links "
                                           r"bounds "
                                           r"'x' and none of \[types.room\], \[types.default\] defines it"):
        toy([CausalLink(0, ("at", "a"), 1)], binding_text=text, object_types={"a": "place", "b": "room"})


def test_missing_belief_value_names_object_and_quantity():
    belief = {"objects": {"a": {"x": 0.5, "y": -0.5, "v": 0.0}}}
    with pytest.raises(BeliefError, match=r"^toy_belief.toml: object 'a' has no value for 'phi' "
                                          r"\(needed by \(at a\) in the initial state\)$"):
        toy([CausalLink(0, ("at", "a"), 1)], belief=belief)
    with pytest.raises(BeliefError, match=r"object 'b' has no \[objects.b\] table \(needed by \(spot a b\)"):
        toy([CausalLink(0, ("spot", "a", "b"), 1)], belief={"objects": {}})


def test_plan_action_not_bound_names_it():
    plan = AbstractPlan("soccer", "x", "hand", (Step(1, "kick", ("pos1",)),), (), ())
    with pytest.raises(BindingError, match=r"actions.toml: plan step 1 \(kick pos1\): PDDL action 'kick' "
                                           r"is not "
                                           r"bound \(add an \[actions.kick\] table\)$"):
        instantiate(plan, load_domain_binding(SOCCER), load_belief(SOCCER / "problems" / "score.toml"))


def test_argument_index_out_of_range():
    with pytest.raises(BindingError, match=r"toy.toml: \[actions.move\] internal = 2 is out of range for "
                                           r"step 1 "
                                           r"\(move a b\) with 2 argument\(s\)"):
        toy([], args=("a", "b"))
    text = TOY.replace("args = [1]", "args = [3]")
    with pytest.raises(BindingError,
                       match=r"\[predicates.spot\] args index 3 is out of range for \(spot a b\)"):
        toy([CausalLink(0, ("spot", "a", "b"), 1)], binding_text=text)
