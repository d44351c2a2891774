"""`tailor new robot NAME [--out DIR]`: a plug-in package for a robot of one's own, ready to install, train, refine
and evaluate as generated: a simulator stub with one action, its PDDL domain, the binding, a problem with its
belief state, a test and a README with the steps. The files come from cli/templates/robot (package data), with
the robot's name put in; nothing is written where a file exists, and nothing half-way.
"""

from __future__ import annotations

import argparse
import keyword
import re
import shutil
import sys
import tempfile
from pathlib import Path

from tailor.errors import OutputFileError, UsageError
from tailor.outputs import check_output_dir

TEMPLATES = Path(__file__).parent / "templates"
KINDS = ("robot",)
NAME = re.compile(r"^[a-z][a-z0-9_]{0,39}$")
PLACEHOLDER, DIR_PLACEHOLDER = "__NAME__", "__DIR__"

DESCRIPTION = ("make a plug-in package for a robot of your own (a simulator stub with one action, its PDDL domain, "
               "binding, a problem with its belief state, a test and a README with the steps), ready to install, "
               "train, refine and evaluate as generated")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("kind", choices=KINDS, help="what to make")
    parser.add_argument("name", metavar="NAME", help="the robot's name: lower case characters a-z, digits and _, not beginning with a digit or _ "
                        "(the simulator's, the domain's and the package's name: tailor_NAME)")
    parser.add_argument("--out", metavar="DIR", help="the folder to make (default: ./NAME; it must not exist)")


def run(args: argparse.Namespace) -> int:
    name = args.name
    if not NAME.match(name) or keyword.iskeyword(name):
        raise UsageError(f"robot name {name!r}: use lower case characters a-z, digits and _, not beginning with a digit or _ "
                         "(at most 40)")
    target = Path(args.out if args.out else name)
    if target.exists() or target.is_symlink():
        raise OutputFileError("already exists: choose another --out (nothing is overwritten)", str(target))
    check_output_dir(target)
    written = make_robot(name, target)
    shown = str(target)
    sys.stdout.write(f"Made the {name} robot in {shown}/ ({len(written)} files). Next:\n"
                     f"  pip install -e {shown}\n"
                     f"  tailor train {shown}/domain --episodes 200 --out {shown}/trained\n"
                     f"  tailor refine {shown}/domain/domain.pddl tour --models {shown}/trained --simulate\n"
                     f"  tailor evaluate {shown}/domain --models {shown}/trained --episodes 20 --oracle-episodes 2 "
                     "--horizon-episodes 4\n"
                     f"(the steps, and what to change to make it your robot, are in {shown}/README.md)\n")
    return 0


def make_robot(name: str, target: Path) -> list[Path]:
    """Write the robot's package into `target` (made in a staging folder beside it, then renamed into place:
    a failure or Ctrl-C leaves nothing)."""
    source = TEMPLATES / "robot"
    target = Path(target)
    staging = Path(tempfile.mkdtemp(prefix=f".{target.name}-", dir=target.parent if str(target.parent) else "."))
    written = []
    try:
        for template in sorted(source.rglob("*.tmpl")):
            relative = template.relative_to(source).with_suffix("")  # drop .tmpl
            parts = [f"tailor_{name}" if part == "package" else part.replace(PLACEHOLDER, name)
                     for part in relative.parts]
            path = staging.joinpath(*parts)
            path.parent.mkdir(parents=True, exist_ok=True)
            text = template.read_text(encoding="utf-8")
            path.write_text(text.replace(PLACEHOLDER, name).replace(DIR_PLACEHOLDER, str(target)), encoding="utf-8")
            written.append(target.joinpath(*parts))
        staging.rename(target)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return written
