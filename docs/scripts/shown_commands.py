"""The command lines a page shows and the outputs it shows for them.

A page's ```shell blocks hold command lines, one a line (`#` starts a comment); tests/test_docs.py runs every one
of them. A ```text block right after a line `<!-- output of the command above -->` is what the last command of
the shell block before it prints on stdout: the test compares the two, and `python docs/scripts/generate.py
--outputs` runs the commands again and writes what they print into the page.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

OUTPUT_MARK = "<!-- output of the command above -->"
SHELL_BLOCK = re.compile(r"^```shell\n(.*?)^```\n", re.S | re.M)
OUTPUT_BLOCK = re.compile(r"^```shell\n(.*?)^```\n\n" + re.escape(OUTPUT_MARK) + r"\n```text\n(.*?)^```\n",
                          re.S | re.M)
# The optimizer's line says how long it took (different in every run) and why other optimizers did not apply (a
# note that changes with every optimizer added): an output shown matches whatever that line says.
OPTIMIZER_LINE = re.compile(r"^Optimizer: .*$", re.M)
INSTALL = ("python3 -m venv", "pip install")  # setting up, which .ci/run does (tests/test_docs.py checks the line)


@dataclass(frozen=True)
class Shown:
    command: str
    output: str | None  # what the page shows it prints, where it shows it


def commands(page: str) -> list[str]:
    """Every command line in the page's shell blocks, in order."""
    lines = []
    for block in SHELL_BLOCK.findall(page):
        lines += [line.strip() for line in block.splitlines() if line.strip() and not line.lstrip().startswith("#")]
    return lines


def shown_outputs(page: str) -> list[Shown]:
    """The commands whose output the page shows, with that output."""
    out = []
    for block, output in OUTPUT_BLOCK.findall(page):
        out.append(Shown(commands(f"```shell\n{block}```\n")[-1], output))
    return out


def same_output(shown: str, printed: str) -> bool:
    """Whether an output shown is what the command printed, but for the optimizer's line."""
    return (OPTIMIZER_LINE.sub("Optimizer: ...", shown.rstrip("\n"))
            == OPTIMIZER_LINE.sub("Optimizer: ...", printed.rstrip("\n")))


def run(command: str, cwd: Path, env: dict | None = None, timeout: float = 600) -> subprocess.CompletedProcess:
    """A command line as a shell runs it in `cwd`, as on a fresh machine: `tailor` is the one installed beside this
    Python, and neither $TAILOR_MODELS nor models trained into the user's data folder are found (its data folder
    is `cwd`/.data)."""
    env = dict(os.environ if env is None else env)
    env["PATH"] = str(Path(sys.executable).parent) + os.pathsep + env.get("PATH", "")
    env.pop("TAILOR_MODELS", None)
    env["XDG_DATA_HOME"] = str(Path(cwd).resolve() / ".data")
    return subprocess.run(command, shell=True, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout,
                          executable="/bin/bash")


def with_outputs(page: str, cwd: Path) -> str:
    """The page with every output it shows replaced by what the command prints now (run in `cwd`, in order)."""
    printed = {}
    for command in commands(page):
        if command.startswith(INSTALL):
            continue
        done = run(command, cwd)
        if done.returncode != 0:
            raise SystemExit(f"{command}: exit {done.returncode}\n{done.stderr}")
        printed[command] = done.stdout

    def replace(match: re.Match) -> str:
        command = commands(f"```shell\n{match.group(1)}```\n")[-1]
        return f"```shell\n{match.group(1)}```\n\n{OUTPUT_MARK}\n```text\n{printed[command].rstrip(chr(10))}\n```\n"

    return OUTPUT_BLOCK.sub(replace, page)
