"""What the tests of planner processes look at: the live processes whose command line names something (/proc)."""

from __future__ import annotations

from pathlib import Path


def processes_naming(text: str) -> dict[int, str]:
    """pid -> command line of the live (not zombie) processes whose command line contains `text`, from /proc."""
    found = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            state = stat.read_text().rsplit(")", 1)[1].split()[0]
            cmdline = (stat.parent / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace").strip()
        except (OSError, IndexError):
            continue  # it ended meanwhile
        if state != "Z" and text in cmdline:
            found[int(stat.parent.name)] = cmdline
    return found
