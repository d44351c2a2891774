"""No module outside a robot's own package names that robot: tailor's core is robot-generic (docs/architecture.md).

Each bundled robot's vocabulary (its name, its objects, its actions, its parts, its parameters) may appear only in
its own sims/<robot>/ and domains/<robot>/; the core (planner_bridge, refinement, the generic modules of sims, the
command line and the namespace root) finds robots through the simulator registry and asks what they declare."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CORE = ("planner_bridge", "refinement", "sims", "cli")
CORE_MODULES = ("__init__.py", "errors.py", "outputs.py", "progress.py")  # the namespace root's modules
ROBOTS = ("soccer", "arm", "kitchen")
ROBOT_PACKAGES = tuple(f"sims/{robot}" for robot in ROBOTS)  # each robot's own package may use its own words
SOCCER = re.compile(r"soccer|ball|dribbl|gotopose|approach_?ball|field_(half|x|y|margin)|pioneer|robocup", re.I)
# the arm's: its name, its joints (shoulder, elbow) and their parameters, its tip and pen, the letters it draws
# and their strokes, its feature space, its action where written as one ("reach" alone is an English word)
ARM = re.compile(r"\barms?\b|powercube|shoulder|elbow|theta_g?[ab]\b|omega_g?[ab]\b|\btip(_[xy])?\b|\bpen\b"
                 r"|\bletters?\b|\bstrokes?\b|joint[- ]space|\bramps\b|[\"'(.]reach\b", re.I)
# the kitchen's: its name, its robot, its cups and tables, its actions' and spots' words ("table" alone is a
# TOML table, an HTML one or one of the dissertation's; "gripper" the classic planning domain)
KITCHEN = re.compile(r"kitchen|\bb21\b|\bcups?\b|\btable\d|\btable \{object\}|\bgrip\b|dropoff|pickup|\bisland\b"
                     r"|divider|serving edge|\bophi\b|\bbase (pose|heading|radius)\b", re.I)
VOCABULARY = {"soccer": SOCCER, "arm": ARM, "kitchen": KITCHEN}


def core_files() -> list[Path]:
    files = [ROOT / name for name in CORE_MODULES]
    for package in CORE:
        for path in sorted((ROOT / package).rglob("*")):
            relative = path.relative_to(ROOT).as_posix()
            if path.is_file() and path.suffix in (".py", ".toml", ".json") and not relative.startswith(ROBOT_PACKAGES):
                files.append(path)
    return files


def robot_words(line: str) -> list[str]:
    """The robots whose vocabulary `line` uses."""
    return [robot for robot, words in VOCABULARY.items() if words.search(line)]


def test_the_core_names_no_robot():
    offending = []
    for path in core_files():
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if robot_words(line):
                offending.append(f"{path.relative_to(ROOT)}:{number}: ({', '.join(robot_words(line))}) {line.strip()}")
    assert not offending, "a robot's vocabulary outside its own package:\n" + "\n".join(offending)


def test_the_check_sees_the_core_and_would_fail_on_a_robot_name():
    names = {p.relative_to(ROOT).as_posix() for p in core_files()}
    assert {"refinement/dispatch.py", "sims/registry.py", "sims/team.py", "planner_bridge/bridge.py",
            "cli/main.py", "errors.py"} <= names
    assert not any(n.startswith(ROBOT_PACKAGES) for n in names)
    assert SOCCER.search("from tailor.sims.soccer import SoccerSim")
    assert SOCCER.search('RANGES["goToPose"]') and SOCCER.search("dribbleBall")
    assert KITCHEN.search("from tailor.sims.kitchen import KitchenSim") and KITCHEN.search("grip the cup")
    assert KITCHEN.search('scene = "table {object}"') and KITCHEN.search("spot (ox, oy, ophi)")
    assert ARM.search("from tailor.sims.arm import ArmSim") and ARM.search('("theta_a", "omega_a")')
    assert ARM.search("the elbow's angle") and ARM.search('e.g. "(reach f1 f2)"') and ARM.search("tip_x")
    # words of the dissertation and of planning that a robot happens to share are not a robot's
    for generic in ("Table 4.1", "a [training] table", "table { border: 0 }", "reach its goal", "reachable",
                    "the gripper domain",
                    "one exception base", "the joint utility model", "theta (batch, n_free)"):
        assert not robot_words(generic), generic


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


def test_no_robot_package_imports_another():
    """A robot is its own package: what two robots share lives in the generic sims modules."""
    found = []
    for robot in ROBOTS:
        others = tuple(f"tailor.sims.{other}" for other in ROBOTS if other != robot)
        for path in sorted((ROOT / "sims" / robot).rglob("*.py")):
            for module in IMPORT.findall(path.read_text(encoding="utf-8")):
                if module.startswith(others):
                    found.append(f"{path.relative_to(ROOT)} imports {module}")
    assert not found, "\n".join(found)


IMPORT = re.compile(r"^\s*(?:from|import)\s+(tailor\.[\w.]+)", re.M)
BOUNDARIES = {  # package -> the tailor packages it must not import (the layout of docs/architecture.md)
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
