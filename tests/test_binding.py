"""The action library binding: the soccer file, a new domain bound without Python, and every error path."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from tailor.planner_bridge.abstract_plan import AbstractPlan, CausalLink, Step
from tailor.refinement.belief import belief_path_for, load_belief
from tailor.refinement.binding import load_binding, load_domain_binding
from tailor.errors import BindingError
from tailor.refinement.instantiate import instantiate

SOCCER = Path(__file__).resolve().parents[1] / "domains" / "soccer"


def test_soccer_binding():
    b = load_domain_binding(SOCCER)
    assert b.file == str(SOCCER / "actions.toml") and b.domain == "soccer" and b.simulator == "soccer"
    assert b.quantities == ("x", "y", "phi", "v") and b.entry.name == "soccer"
    assert b.action("gotopose").spec.internal == ("xg", "yg", "phig", "vg")
    assert {n: (a.executable, dict(a.args)) for n, a in b.actions.items()} == {
        "approachball": ("goToPose", {"observed": 0, "internal": 1}),
        "dribbleball": ("dribbleBall", {"observed": 0, "internal": 1}),
        "gotopose": ("goToPose", {"observed": 0, "internal": 1}),
    }
    # approaching the ball is goToPose with its success classifier (Ch. 6), subgoals no faster than trained
    assert b.action("approachball").success_model == "goToPose"
    assert dict(b.action("approachball").subgoal) == {"v": (0.0, 0.6)}
    assert b.action("dribbleball").success_model is None
    assert {n: (p.read, dict(p.ranges), p.scene, p.args) for n, p in b.predicates.items()} == {
        "robot": (("x", "y", "phi", "v"), {}, "robot", None),
        "ball": (("x", "y"), {}, "ball", None),
        "atball": ((), {"v": (0.0, 0.3)}, None, None),
        "final": (("x", "y", "phi", "v"), {}, None, None),
        "waypoint": (("x", "y"), {"v": (0.0, 0.6)}, None, None),
    }
    assert {n: dict(t) for n, t in b.types.items()} == {
        "pos": {"x": (-4.0, 4.0), "y": (-3.0, 3.0), "phi": (-math.pi, math.pi), "v": (0.0, 1.0)}}
    assert b.predicate("NEXT") is None and b.action("GoToPose").executable == "goToPose"


# A different PDDL domain bound to goToPose by data alone: a delivery robot driving between places.
DELIVERY_DOMAIN = """(define (domain delivery)
  (:requirements :strips :typing)
  (:types dock - place place - object)
  (:predicates (parked ?p - place) (road ?a ?b - place) (loading ?d - dock))
  (:action drive :parameters (?to ?from - place)
    :precondition (and (parked ?from) (road ?from ?to))
    :effect (and (parked ?to) (not (parked ?from)))))"""
DELIVERY_PROBLEM = """(define (problem deliver) (:domain delivery)
  (:objects home mid - place bay - dock)
  (:init (parked home) (road home mid) (road mid bay) (loading bay))
  (:goal (parked bay)))"""
DELIVERY_BINDING = """
schema = 2
domain = "delivery"
simulator = "soccer"
[actions.drive]
executable = "goToPose"
observed = 1   # ?from
internal = 0   # ?to
[predicates.parked]
read = ["x", "y", "phi", "v"]
scene = "robot"
[predicates.loading]
read = ["x", "y", "phi"]
v = [0.0, 0.0]
[types.place]
x = [-5.0, 5.0]
y = [-5.0, 5.0]
phi = ["-pi", "pi"]
v = [0.0, 0.8]
[types.dock]
x = [0.0, 5.0]
"""
DELIVERY_BELIEF = """
[objects.home]
x = -4.0
y = 0.0
phi = 0.0
v = 0.0
[objects.mid]
x = 0.0
y = 2.0
[objects.bay]
x = 4.0
y = 1.0
phi = 1.5
"""


def test_a_new_domain_is_bound_to_gotopose_without_python(tmp_path):
    from unified_planning.io import PDDLReader

    (tmp_path / "domain.pddl").write_text(DELIVERY_DOMAIN)
    (tmp_path / "problems").mkdir()
    problem_file = tmp_path / "problems" / "deliver.pddl"
    problem_file.write_text(DELIVERY_PROBLEM)
    (tmp_path / "actions.toml").write_text(DELIVERY_BINDING)
    belief_path_for(problem_file).write_text(DELIVERY_BELIEF)

    problem = PDDLReader().parse_problem(str(tmp_path / "domain.pddl"), str(problem_file))
    types = {}
    for o in problem.all_objects:  # the object's type and its ancestors
        t, chain = o.type, []
        while t is not None:
            chain.append(t.name)
            t = t.father
        types[o.name] = chain
    assert types == {"home": ["place"], "mid": ["place"], "bay": ["dock", "place"]}
    belief = load_belief(belief_path_for(problem_file), objects=types)
    steps = (Step(1, "drive", ("mid", "home")), Step(2, "drive", ("bay", "mid")))
    links = (CausalLink(0, ("parked", "home"), 1), CausalLink(0, ("road", "home", "mid"), 1),
             CausalLink(1, ("parked", "mid"), 2), CausalLink(0, ("road", "mid", "bay"), 2),
             CausalLink(2, ("parked", "bay"), "goal"), CausalLink(0, ("loading", "bay"), "goal"))
    plan = AbstractPlan("delivery", "deliver", "hand", steps, links, ((1, 2),))
    seq = instantiate(plan, load_domain_binding(tmp_path), belief, object_types=types)
    rows = [[(p.id, p.name, p.value, p.low, p.high) for p in a.params] for a in seq.actions]
    pi = math.pi
    assert rows == [
        [("home.x", "x", -4.0, -5.0, 5.0), ("home.y", "y", 0.0, -5.0, 5.0), ("home.phi", "phi", 0.0, -pi, pi),
         ("home.v", "v", 0.0, 0.0, 0.8), ("mid.x", "xg", None, -5.0, 5.0), ("mid.y", "yg", None, -5.0, 5.0),
         ("mid.phi", "phig", None, -pi, pi), ("mid.v", "vg", None, 0.0, 0.8)],
        [("mid.x", "x", None, -5.0, 5.0), ("mid.y", "y", None, -5.0, 5.0), ("mid.phi", "phi", None, -pi, pi),
         ("mid.v", "v", None, 0.0, 0.8), ("bay.x", "xg", 4.0, 0.0, 5.0), ("bay.y", "yg", 1.0, -5.0, 5.0),
         ("bay.phi", "phig", 1.5, -pi, pi), ("bay.v", "vg", 0.0, 0.0, 0.0)],
    ]
    assert [a.action for a in seq.actions] == ["goToPose", "goToPose"]
    assert dict(seq.scene) == {"robot": (-4.0, 0.0, 0.0, 0.0)}


VALID_ACTION = '[actions.go]\nexecutable = "goToPose"\nobserved = 0\ninternal = 1\n'
SOCCER_SIM = 'simulator = "soccer"\n'  # top-level key every binding needs; prepended to each BAD_BINDINGS text

BAD_BINDINGS = [
    ('[actions.go]\nobserved = 0\ninternal = 1\n', r"\[actions.go\] missing 'executable': the action of simulator "
                                                    r"'soccer' it runs \(known: "),
    ('[actions.go]\nexecutable = "fly"\nobserved = 0\ninternal = 1\n',
     r"\[actions.go\] executable = 'fly' is not an executable action of simulator 'soccer' "
     r"\(known: goToPose, approachBall, dribbleBall, goToPosition\)"),
    (VALID_ACTION + "observd = 0\n",
     r"\[actions.go\]: unknown key 'observd' \(expected one of executable, internal, observed, subgoal, "
     r"success_margin, success_model\)"),
    ('[actions.go]\nexecutable = "goToPose"\nobserved = 0\n',
     r"\[actions.go\] missing 'internal': the PDDL argument index that supplies goToPose's internal "
     r"parameters xg, yg, phig, vg"),
    ('[actions.go]\nexecutable = "goToPose"\nobserved = -1\ninternal = 1\n',
     r"\[actions.go\] observed must be a PDDL argument index \(an integer >= 0\), not -1"),
    ('[actions.go]\nexecutable = "goToPose"\nobserved = true\ninternal = 1\n',
     r"\[actions.go\] observed must be a PDDL argument index \(an integer >= 0\), not True"),
    ("actions = 3\n", r"'actions' must be a table of tables \(\[actions.NAME\]\)"),
    ("[actions]\ngo = 3\n", r"\[actions.go\] must be a table"),
    ("foo = 1\n",
     r"top level: unknown key 'foo' \(expected one of actions, domain, evaluation, objective, predicates, refinement, "
     r"schema, simulator, training, types\)"),
    ("schema = 1\n", r"unsupported schema 1 \(expected 2: a binding names its simulator\)"),
    ("schema = 3\n", r"unsupported schema 3 \(expected 2: a binding names its simulator\)"),
    ("training = 3\n", r"'training' must be a table \(\[training\]\)"),
    ("evaluation = \"score\"\n", r"'evaluation' must be a table \(\[evaluation\]\)"),
    ("domain = 3\n", r"'domain' must be a string"),
    ("[predicates.at]\nspeed = [0, 1]\n",
     r"\[predicates.at\]: unknown key 'speed' \(expected one of args, lost_on_failure, read, scene, x, y, phi, v\)"),
    ("[predicates.at]\nread = [\"x\", \"z\"]\n",
     r"\[predicates.at\] read: unknown quantity 'z' \(known: x, y, phi, v\)"),
    ("[predicates.at]\nread = \"x\"\n", r"\[predicates.at\] read must be a list of quantity names"),
    ("[predicates.at]\nread = [\"x\", \"x\"]\n", r"\[predicates.at\] read names a quantity twice"),
    ("[predicates.at]\nscene = \"robot\"\n", r"\[predicates.at\] scene = 'robot' needs a read list"),
    ("[predicates.at]\nread = [\"x\"]\nscene = 3\n",
     r"\[predicates.at\] scene must be the name of a scene object"),
    ("[predicates.at]\nargs = []\n", r"\[predicates.at\] args must be a non-empty list of argument indices"),
    ("[predicates.at]\nv = [0.3, 0.0]\n", r"\[predicates.at\] v = \[0.3, 0\] is empty \(low > high\)"),
    ("[predicates.at]\nv = [0.3]\n", r"\[predicates.at\] v must be a range \[low, high\], not \[0.3\]"),
    ("[predicates.at]\nv = 0.3\n", r"\[predicates.at\] v must be a range \[low, high\], not 0.3"),
    ("[predicates.at]\nphi = [\"-tau\", \"pi\"]\n",
     r"\[predicates.at\] phi: '-tau' is not a number \(or \"pi\" / \"-pi\"\)"),
    ("[predicates.at]\nv = [0.0, nan]\n", r"\[predicates.at\] v: nan is not a finite number"),
    ("[predicates.at]\nv = [0.0, 1e300]\n", r"\[predicates.at\] v: 1e\+300 is beyond 1e\+09"),
    ("[types.pos]\nz = [0.0, 1.0]\n", r"\[types.pos\]: unknown key 'z' \(expected one of x, y, phi, v\)"),
    ("[types.pos]\nread = [\"x\"]\n", r"\[types.pos\]: unknown key 'read'"),
    ("[types.pos]\nx = [true, 1.0]\n", r"\[types.pos\] x: True is not a number"),
]


# Top-level errors about the simulator itself: these texts are written as they are.
BAD_SIMULATORS = [
    (VALID_ACTION, r"missing 'simulator': the name of the simulator whose actions the domain binds "
                   r"\(see `tailor domains`\)$"),
    ("simulator = 3\n", r"simulator = 3 must name a simulator \(a string; see `tailor domains`\)$"),
    ('simulator = ""\n', r"simulator = '' must name a simulator"),
    ('simulator = "hovercraft"\n' + VALID_ACTION,
     r"simulator = 'hovercraft': no simulator 'hovercraft' is installed \(known: .*soccer.*\)$"),
]


@pytest.mark.parametrize("text, message", [(SOCCER_SIM + t, m) for t, m in BAD_BINDINGS] + BAD_SIMULATORS)
def test_binding_errors_name_the_file_and_the_problem(tmp_path, text, message):
    path = tmp_path / "actions.toml"
    path.write_text(text)
    with pytest.raises(BindingError, match=f"^{re.escape(str(path))}: {message}") as info:
        load_binding(path)
    assert "\n" not in str(info.value)
    assert info.value.exit_code == 11


def test_binding_bad_toml_gives_line_and_column(tmp_path):
    path = tmp_path / "actions.toml"
    path.write_text(VALID_ACTION + "[actions.go]\n")
    where = re.escape(str(path))
    with pytest.raises(BindingError,
                       match=rf"^{where}:5:\d+: invalid TOML: Cannot declare \('actions', 'go'\) twice$"):
        load_binding(path)


def test_missing_binding_file(tmp_path):
    where = re.escape(str(tmp_path / "actions.toml"))
    with pytest.raises(BindingError, match=rf"^{where}: action library binding file not found$"):
        load_domain_binding(tmp_path)


def test_pi_strings_and_integers_are_accepted(tmp_path):
    path = tmp_path / "actions.toml"
    path.write_text(SOCCER_SIM + '[types.t]\nphi = [" -PI", "pi"]\nx = [-1, 2]\n')
    assert dict(load_binding(path).types["t"]) == {"phi": (-math.pi, math.pi), "x": (-1.0, 2.0)}


def test_a_binding_with_a_byte_order_mark_reads_as_without(tmp_path):
    """Editors on Windows start UTF-8 files with a byte-order mark; PDDL files with one are read, and so are
    the TOML files beside them."""
    path = tmp_path / "actions.toml"
    path.write_text("\ufeff" + SOCCER_SIM + VALID_ACTION, encoding="utf-8")
    assert load_binding(path).action("go").executable == "goToPose"
