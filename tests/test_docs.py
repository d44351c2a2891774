"""The documentation site: it builds strictly (no broken link, reference or anchor), its generated pages are what
the scripts make of the parsers and the committed result files, and every command line of the getting-started
page runs as shown and prints what the page shows."""

from __future__ import annotations

import importlib.util
import inspect
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import tailor.errors

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
SCRIPTS = DOCS / "scripts"


def _module(name: str):
    spec = importlib.util.spec_from_file_location(f"docs_{name}", SCRIPTS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # (a dataclass looks its module up there)
    spec.loader.exec_module(module)
    return module


shown = _module("shown_commands")
cli_main = importlib.import_module("tailor.cli.main")  # (the package's `main` attribute is the function)


def quiet_env() -> dict:
    env = dict(os.environ)
    env["NO_MKDOCS_2_WARNING"] = "1"  # Material's notice about MkDocs 2, printed on every build
    env.pop("PYTHONPATH", None)
    return env


def test_site_builds_strictly(tmp_path):
    built = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
                           cwd=ROOT, capture_output=True, text=True, env=quiet_env(), timeout=600)
    assert built.returncode == 0, built.stdout + built.stderr
    for page in ("index.html", "getting-started/index.html", "commands/index.html", "api/index.html",
                 "results/soccer/index.html"):
        assert (tmp_path / "site" / page).is_file(), page
    assert (tmp_path / "site" / "results" / "soccer" / "mae_vs_n_i.png").is_file()  # the committed pictures
    api = (tmp_path / "site" / "api" / "index.html").read_text(encoding="utf-8")
    assert "A plan refined for the fastest predicted execution" in api  # the docstrings are rendered


def test_generated_pages_are_current():
    checked = subprocess.run([sys.executable, str(SCRIPTS / "generate.py"), "--check"], cwd=ROOT,
                             capture_output=True, text=True, env=quiet_env(), timeout=600)
    assert checked.returncode == 0, ("stale generated pages: run `python docs/scripts/generate.py`\n"
                                     + checked.stdout[-20000:] + checked.stderr)


def test_getting_started_commands_run_and_print_what_the_page_shows(tmp_path):
    page = (DOCS / "getting-started.md").read_text(encoding="utf-8")
    commands = shown.commands(page)
    outputs = {s.command: s.output for s in shown.shown_outputs(page)}
    assert len(commands) >= 8 and len(outputs) >= 2
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    work = tmp_path / "work"
    work.mkdir()
    for command in commands:
        if command.startswith(shown.INSTALL):  # setting up: the README's own first line, which CI runs
            assert command in readme, command
            continue
        done = shown.run(command, work, env=quiet_env())
        assert done.returncode == 0, f"{command}: exit {done.returncode}\n{done.stderr}"
        if command in outputs:
            assert shown.same_output(outputs[command], done.stdout), (
                f"docs/getting-started.md shows another output of `{command}` than it prints now: run "
                f"`python docs/scripts/generate.py --outputs`\n--- printed:\n{done.stdout}")
    assert (work / "score.png").is_file() and list((work / "my-models" / "models").glob("*.json"))


def test_your_own_robot_page_shows_the_steps_the_scaffold_prints(tmp_path):
    made = shown.run("tailor new robot demo", tmp_path, env=quiet_env())
    assert made.returncode == 0, made.stderr
    page = (DOCS / "your-own-robot.md").read_text(encoding="utf-8")
    assert made.stdout in page
    steps = [line.strip() for line in made.stdout.splitlines() if line.startswith("  ")]
    assert steps and set(steps) <= set(shown.commands(page))


def test_exit_status_page_lists_every_status():
    page = (DOCS / "exit-statuses.md").read_text(encoding="utf-8")
    listed = {int(status) for status in re.findall(r"^\| (\d+) \|", page, flags=re.M)}
    errors = {cls.exit_code for _, cls in inspect.getmembers(tailor.errors, inspect.isclass)
              if issubclass(cls, tailor.errors.TailorError)}
    assert listed == errors | {0, cli_main.EXIT_USAGE, cli_main.EXIT_INTERRUPTED, cli_main.EXIT_TERMINATED,
                               cli_main.EXIT_NOT_COMPLETED}


def test_api_page_example_is_the_readmes():
    """The README's example runs in tests/test_readme.py; the API page shows the same one."""
    example = re.compile(r"```python\n(.*?)```", re.S)
    assert example.findall((DOCS / "api.md").read_text(encoding="utf-8")) == example.findall(
        (ROOT / "README.md").read_text(encoding="utf-8"))


def test_the_readme_is_short_and_its_links_resolve():
    """The README is the way in (at most 300 lines); the rest is the site, linked relatively so the links work
    on a repository page too."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(readme.splitlines()) <= 300
    links = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", readme)
    assert links and all((ROOT / link).exists() for link in links if "://" not in link), links
