"""What a simulator declares about itself as data (tailor.sims.protocol): each quantity's unit and whether it is
an angle, and the pictures of its learned models it can draw. Pictures and printed values ask these
declarations; a robot that declares nothing still works, with nothing assumed."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from tailor.sims import Quantity, registry
from tailor.sims.protocol import UNDECLARED, ActionSpec, DurationCurve, SimulatorEntry, SuccessRegion

POINTMASS = Path(__file__).parent / "fixtures" / "pointmass" / "site"
BUNDLED = ("soccer", "arm", "kitchen")


def _bare(**declarations) -> SimulatorEntry:
    return SimulatorEntry("bare", {"move": ActionSpec("move", "bare", ("x",), ("xg",), ("x",), ("x",))},
                          create=lambda seed, noise=None: None, **declarations)


@pytest.mark.parametrize("name", BUNDLED)
def test_every_bundled_robot_declares_each_quantity_and_drawn_column(name):
    entry = registry.get(name)
    drawn = set()
    for view in entry.views:
        for layer in ((view,) if isinstance(view[0], str) else view):
            drawn.update(layer)
    undeclared = [q for q in (*entry.quantities, *drawn) if entry.quantity(q) is UNDECLARED]
    assert not undeclared, f"{name} declares no unit for {undeclared}"
    assert all(entry.quantity(q).unit for q in entry.quantities)


def test_angles_are_declared_not_guessed_from_names():
    soccer, arm, kitchen = (registry.get(name) for name in BUNDLED)
    assert soccer.quantity("phi") == Quantity("rad", angle=True) and soccer.quantity("v") == Quantity("m/s")
    assert kitchen.quantity("heading").angle and kitchen.quantity("ophi").angle  # no "phi" at their start
    assert not kitchen.quantity("along").angle and kitchen.quantity("along").unit == "m"
    assert arm.quantity("theta_a").angle and not arm.quantity("omega_a").angle
    assert arm.quantity("omega_a").unit == "rad/s"


def test_a_parameter_id_or_name_names_its_quantity():
    soccer, kitchen = registry.get("soccer"), registry.get("kitchen")
    assert soccer.quantity("pos2.phi") is soccer.quantity("phi")
    assert soccer.quantity("ball.x").unit == "m"
    assert soccer.quantity("pos2.nothing") is UNDECLARED
    assert soccer.quantity("phig") is soccer.quantity("phi") and soccer.quantity("vg").unit == "m/s"
    assert kitchen.quantity("headingg").angle and kitchen.quantity("cx").unit == "m"  # the goal's, a cup's
    assert kitchen.quantity("nothing") is UNDECLARED


def test_a_robot_that_declares_nothing_has_nothing_assumed():
    bare = _bare()
    assert bare.units == {} and bare.model_pictures == ()
    assert bare.quantity("phi") is UNDECLARED and bare.quantity("p1.phi") == Quantity("", False)
    assert _bare(units={"x": Quantity("m")}).quantity("x").unit == "m"
    with pytest.raises(ValueError, match=r"units\['x'\] must be a Quantity"):
        _bare(units={"x": "m"})


def test_the_outside_robot_declares_its_quantities(monkeypatch):
    monkeypatch.syspath_prepend(str(POINTMASS))
    monkeypatch.delitem(sys.modules, "tailor_pointmass", raising=False)
    import tailor_pointmass

    entry = tailor_pointmass.SIMULATOR
    assert entry.quantity("x") == Quantity("m") and entry.quantity("p1.v") == Quantity("m/s")
    assert not any(entry.quantity(q).angle for q in entry.quantities)


def test_the_soccer_robot_declares_the_pictures_of_its_models():
    soccer = registry.get("soccer")
    curves = [p for p in soccer.model_pictures if isinstance(p, DurationCurve)]
    regions = [p for p in soccer.model_pictures if isinstance(p, SuccessRegion)]
    assert len(curves) == len(regions) == 1
    parameters = set(soccer.action("goToPose").parameters)
    assert curves[0].parameters <= parameters and regions[0].parameters <= parameters
    assert soccer.quantity(curves[0].varied).angle  # swept over the full circle: an angle
    assert regions[0].goal_heading in regions[0].situation
    for name in ("arm", "kitchen"):
        assert registry.get(name).model_pictures == ()


def test_declaring_the_bundled_robots_loads_no_physics():
    """Listing the robots (tailor domains, tailor plan) builds their entries without pymunk: each simulator
    module is imported with its first simulator, and its names still import from the robot's package."""
    script = ("import sys\nfrom tailor.sims import registry\n"
              "entries = [registry.get(name) for name in ('arm', 'kitchen', 'soccer')]\n"
              "print('pymunk' in sys.modules)\n"
              "from tailor.sims.arm import ArmSim\nfrom tailor.sims.kitchen import KitchenSim\n"
              "from tailor.sims.soccer import Noise, SoccerSim, simulate_sequence\n"
              "sims = [entry.create(0, None) for entry in entries]\n"
              "print(list(map(type, sims)) == [ArmSim, KitchenSim, SoccerSim] and 'pymunk' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert done.stdout.split() == ["False", "True"], done.stderr[-2000:]
