"""`tailor new robot NAME`: a plug-in package that trains, refines and evaluates as generated.

The package is made in a temporary folder and registered the way `pip install` would (a dist-info with its entry
point beside it on PYTHONPATH, as the pointmass fixture is); then the steps the command prints run unchanged.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tailor.cli.main import main


def tailor(*args: str, site: Path | None = None, cwd: Path | None = None) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)
    if site is not None:
        env["PYTHONPATH"] = str(site)
    return subprocess.run([sys.executable, "-m", "tailor.cli", *args], capture_output=True, text=True, env=env,
                          timeout=600, cwd=cwd)


def installed(package: Path, name: str) -> Path:
    """PYTHONPATH on which the made package is found as installed: its module and a dist-info with its entry point."""
    entry = re.search(r'\[project.entry-points."tailor.simulators"\]\n(.*)\n', (package / "pyproject.toml").read_text())
    info = package / f"tailor_{name}-0.1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: tailor-{name}\nVersion: 0.1.0\n")
    point = entry.group(1).replace(" ", "").replace('"', "")
    (info / "entry_points.txt").write_text(f"[tailor.simulators]\n{point}\n")
    return package


def test_the_robot_made_runs_the_steps_it_prints(tmp_path):
    made = tailor("new", "robot", "demo", cwd=tmp_path)
    assert made.returncode == 0, made.stderr
    steps = [line.strip() for line in made.stdout.splitlines() if line.startswith("  tailor ")]
    assert len(steps) == 3 and "pip install -e demo" in made.stdout
    package = tmp_path / "demo"
    assert sorted(p.relative_to(package).as_posix() for p in package.rglob("*") if p.is_file()) == [
        "README.md", "domain/actions.toml", "domain/domain.pddl", "domain/problems/tour.pddl",
        "domain/problems/tour.toml", "pyproject.toml", "tailor_demo/__init__.py", "tests/test_demo.py"]
    site = installed(package, "demo")
    for step in steps:  # train, refine --simulate, evaluate: as printed
        words = step.split()[1:]
        if words[0] == "train":
            words[words.index("200")] = "120"  # (fewer episodes: the same steps, a shorter test)
        run = tailor(*words, "--json", site=site, cwd=tmp_path)
        assert run.returncode == 0, (step, run.stderr)
        if words[0] == "refine":
            result = json.loads(run.stdout)
            assert result["refined"]["succeeded"] and [p["id"] for p in result["free_parameters"]] == ["p1.v", "p2.v"]


def test_nothing_is_overwritten_and_bad_names_are_one_line(tmp_path, capsys):
    (tmp_path / "taken").mkdir()
    assert main(["new", "robot", "demo", "--out", str(tmp_path / "taken")]) == 16
    assert "already exists" in capsys.readouterr().err and not any((tmp_path / "taken").iterdir())
    for bad in ("Demo", "1robot", "my-robot", "class", "a" * 41):
        assert main(["new", "robot", bad, "--out", str(tmp_path / "x")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "robot name" in err[0]
    assert not (tmp_path / "x").exists()


@pytest.mark.parametrize("name", ["demo", "arm_2"])
def test_the_name_is_put_everywhere(tmp_path, name, capsys):
    assert main(["new", "robot", name, "--out", str(tmp_path / name)]) == 0
    capsys.readouterr()
    texts = [p.read_text() for p in (tmp_path / name).rglob("*") if p.is_file()]
    assert not any("__NAME__" in t or "__DIR__" in t for t in texts)
    assert f'{name} = "tailor_{name}:SIMULATOR"' in (tmp_path / name / "pyproject.toml").read_text()
