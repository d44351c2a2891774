"""No module outside a robot's own package names that robot: tailor's core is domain-generic (DESIGN.md).

The soccer robot's vocabulary (its name, its ball, its actions, its field) may appear only in sims/soccer/ and
domains/soccer/; the core finds robots through the simulator registry."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CORE = ("planner_bridge", "refinement", "sims")
ROBOT_PACKAGES = ("sims/soccer", "sims/arm", "sims/kitchen")  # each robot's own package may use its own words
SOCCER = re.compile(r"soccer|ball|dribbl|gotopose|approach_?ball|field_(half|x|y|margin)|pioneer|robocup", re.I)
KITCHEN = re.compile(r"kitchen|\bcups?\b|\bb21\b", re.I)  # the kitchen robot's words


def core_files() -> list[Path]:
    files = [ROOT / "__init__.py", ROOT / "errors.py"]
    for package in CORE:
        for path in sorted((ROOT / package).rglob("*")):
            relative = path.relative_to(ROOT).as_posix()
            if path.is_file() and path.suffix in (".py", ".toml", ".json") and not relative.startswith(ROBOT_PACKAGES):
                files.append(path)
    return files


def test_the_core_names_no_robot():
    offending = []
    for path in core_files():
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if SOCCER.search(line) or KITCHEN.search(line):
                offending.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()}")
    assert not offending, "a robot's vocabulary outside its own package:\n" + "\n".join(offending)


def test_the_check_sees_the_core_and_would_fail_on_a_robot_name():
    names = {p.relative_to(ROOT).as_posix() for p in core_files()}
    assert {"refinement/dispatch.py", "sims/registry.py", "planner_bridge/bridge.py"} <= names
    assert not any(n.startswith("sims/soccer/") for n in names)
    assert SOCCER.search("from tailor.sims.soccer import SoccerSim")
    assert KITCHEN.search("from tailor.sims.kitchen import KitchenSim") and KITCHEN.search("grip the cup")
    assert SOCCER.search('RANGES["goToPose"]') and SOCCER.search("dribbleBall")


def test_the_other_robots_do_not_borrow_the_soccer_robot():
    """The arm's and the kitchen's packages and domains neither import the soccer robot nor use its words (its
    action names included: the kitchen base's action is `navigate`)."""
    found = []
    for robot in ("arm", "kitchen"):
        paths = [*(ROOT / "sims" / robot).rglob("*.py"), *(ROOT / "domains" / robot).rglob("*.toml"),
                 *(ROOT / "domains" / robot).rglob("*.pddl"), *(ROOT / "domains" / robot / "models").glob("*.json")]
        for path in sorted(paths):
            for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
                if "sims.soccer" in line or SOCCER.search(line):
                    found.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()}")
    assert not found, "soccer vocabulary in another robot:\n" + "\n".join(found)


IMPORT = re.compile(r"^\s*(?:from|import)\s+(tailor\.[\w.]+)", re.M)
BOUNDARIES = {  # package -> the tailor packages it must not import (DESIGN.md's layout table)
    "sims": ("tailor.refinement", "tailor.planner_bridge"),
    "planner_bridge": ("tailor.refinement", "tailor.sims"),
    "refinement/models": ("tailor.refinement.learning", "tailor.refinement.evaluation", "tailor.cli"),
    "refinement/learning": ("tailor.refinement.evaluation", "tailor.cli"),
}


def test_packages_import_only_what_the_layout_allows():
    broken = []
    for package, forbidden in BOUNDARIES.items():
        for path in sorted((ROOT / package).rglob("*.py")):
            for module in IMPORT.findall(path.read_text(encoding="utf-8")):
                if module.startswith(forbidden):
                    broken.append(f"{path.relative_to(ROOT)} imports {module}")
    assert not broken, "\n".join(broken)
    assert IMPORT.findall("    from tailor.refinement.evaluation.experiments import x") == [
        "tailor.refinement.evaluation.experiments"]
