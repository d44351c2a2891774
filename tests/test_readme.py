"""The README's Python API example runs as written and shows refinement at work."""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

README = Path(__file__).resolve().parent.parent / "README.md"


def test_readme_python_example_runs():
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), flags=re.S)
    assert len(blocks) == 1
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(blocks[0], str(README), "exec"), {"__name__": "readme_example"})
    lines = out.getvalue().splitlines()
    assert lines[0] == "[('approachball', ('pos1', 'pos2')), ('dribbleball', ('pos2', 'pos3'))]"
    greedy, refined = (float(re.search(r"predicted ([\d.]+) s", line).group(1)) for line in lines[1:3])
    assert lines[1].startswith("1 {'pos2.phi': ") and lines[2].startswith("2 {'pos2.phi': ")
    assert refined <= greedy  # horizon 2 minimizes the summed prediction that greedy minimizes action by action
    assert lines[3].startswith("{'pos2.phi': (-3.14")


def test_readme_opens_with_the_two_setup_commands():
    text = README.read_text(encoding="utf-8")
    commands = re.findall(r"```\n(.*?)\n```", text, flags=re.S)[:2]
    assert "pip install -e . && tailor refine soccer score --simulate" in commands[0]
    assert "pip install -e '.[test]' && pytest -q" in commands[1]
    ci = (README.parent / ".ci" / "run").read_text(encoding="utf-8")
    assert "pip install -e '.[test]' && pytest -q" in ci
