"""Regenerate the golden plans (tests/golden/plan/) and refined sequences (tests/golden/refine/), show what changed.

    python tests/regenerate_golden.py           # rewrite the golden files, print a unified diff of changes
    python tests/regenerate_golden.py --check   # only print the diff; exit status 1 when anything differs

For every bundled pair domains/<domain>/problems/<problem>.pddl the golden file <domain>/<problem>.json holds
exactly what `tailor plan <domain> <problem> --json` prints but its provenance (tailor's version, the command line); <domain>/<problem>.txt holds the text rendering.
The golden file tests/golden/pocl/<domain>/<problem>.txt holds the text of `tailor plan <domain> <problem>
--planner pocl` (our partial-order causal-link planner).
For every bundled problem of a domain with an action library binding (actions.toml), the golden file
tests/golden/refine/<domain>/<problem>.json holds what `tailor refine <domain> <problem> --simulate --json`
prints with seed 0, without the optimizers' wall-clock times ("seconds"), which differ from run to run, and
without its provenance.
Files are written atomically (temporary file, then os.replace).
"""

from __future__ import annotations

import argparse
import contextlib
import difflib
import io
import os
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
GOLDEN_DIR = ROOT / "tests" / "golden" / "plan"
REFINE_GOLDEN_DIR = ROOT / "tests" / "golden" / "refine"
POCL_GOLDEN_DIR = ROOT / "tests" / "golden" / "pocl"
POCL_ARGS = ["--planner", "pocl"]
REFINE_ARGS = ["--simulate", "--json", "--seed", "0"]
RENDERINGS = {".json": ["--json"], ".txt": []}  # golden file suffix -> extra `tailor plan` arguments


def bundled_pairs() -> list[tuple[str, str]]:
    """(domain, problem) names of every problem file under domains/."""
    return sorted((p.parent.parent.name, p.stem) for p in (ROOT / "domains").glob("*/problems/*.pddl"))


def golden_path(domain: str, problem: str, suffix: str) -> Path:
    return GOLDEN_DIR / domain / f"{problem}{suffix}"


def tailor_plan_output(domain: str, problem: str, extra: list[str]) -> str:
    """What `tailor plan DOMAIN PROBLEM [extra]` prints on stdout (run in this process)."""
    from tailor.cli.main import main

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        status = main(["plan", domain, problem, *extra])
    if status != 0:
        raise SystemExit(f"tailor plan {domain} {problem} {' '.join(extra)} failed with status {status}")
    return without_provenance(out.getvalue()) if "--json" in extra else out.getvalue()


def without_provenance(text: str) -> str:
    """`tailor plan --json`'s output without its provenance (tailor's version and the command line change from
    release to release and from call to call; the plan does not), in the same layout."""
    import json

    from tailor.cli.plan import format_json

    data = json.loads(text)
    data.pop("provenance", None)
    return format_json(data)


def pocl_golden_path(domain: str, problem: str) -> Path:
    return POCL_GOLDEN_DIR / domain / f"{problem}.txt"


# The arm's letters all refine alike (reaches through way-points, the GA): two of them keep the default test
# run short; the other letters are refined by `tailor evaluate arm`'s random strokes. The kitchen: scenario 1 (scenario
# 2 refines alike, with twice the actions; `tailor evaluate kitchen --situations scenario2` measures it).
REFINE_SAMPLE = {"arm": ("letter-f", "letter-s"), "kitchen": ("scenario1",)}


def refine_pairs() -> list[tuple[str, str]]:
    """(domain, problem) of the bundled problems whose domain binds its actions (can be refined); of the arm,
    the letters F and S of Fig. 5.13."""
    return [(d, p) for d, p in bundled_pairs() if (ROOT / "domains" / d / "actions.toml").exists()
            and p in REFINE_SAMPLE.get(d, (p,))]


def refine_golden_path(domain: str, problem: str) -> Path:
    return REFINE_GOLDEN_DIR / domain / f"{problem}.json"


MACHINE_DEPENDENT = ("seconds", "models", "provenance")  # wall-clock times; the model folder's absolute path;
# tailor's version and the command line


def without_timings(value):
    """The JSON value without "seconds" entries (wall-clock times are not reproducible), without the
    model folder's path (it depends on where tailor is installed) and without its provenance."""
    if isinstance(value, dict):
        return {k: without_timings(v) for k, v in value.items() if k not in MACHINE_DEPENDENT}
    if isinstance(value, list):
        return [without_timings(v) for v in value]
    return value


def tailor_refine_output(domain: str, problem: str) -> str:
    """What `tailor refine DOMAIN PROBLEM --simulate --json --seed 0` prints, timings removed."""
    import json

    from tailor.cli.main import main

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        status = main(["refine", domain, problem, *REFINE_ARGS])
    if status != 0:
        raise SystemExit(f"tailor refine {domain} {problem} failed with status {status}")
    return json.dumps(without_timings(json.loads(out.getvalue())), indent=1) + "\n"


def write_atomically(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.NamedTemporaryFile("w", dir=path.parent, delete=False, suffix=".tmp", encoding="utf-8") as tmp:
        tmp.write(text)
    os.replace(tmp.name, path)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="do not write; exit 1 when a golden file differs")
    args = parser.parse_args(argv)
    changed = 0
    outputs = [(golden_path(d, p, suffix), lambda d=d, p=p, extra=extra: tailor_plan_output(d, p, extra))
               for d, p in bundled_pairs() for suffix, extra in RENDERINGS.items()]
    outputs += [(pocl_golden_path(d, p), lambda d=d, p=p: tailor_plan_output(d, p, POCL_ARGS))
                for d, p in bundled_pairs()]
    outputs += [(refine_golden_path(d, p), lambda d=d, p=p: tailor_refine_output(d, p)) for d, p in refine_pairs()]
    for path, output in outputs:
        old = path.read_text(encoding="utf-8") if path.exists() else ""
        new = output()
        if new == old:
            continue
        changed += 1
        name = str(path.relative_to(ROOT))
        sys.stdout.writelines(difflib.unified_diff(old.splitlines(True), new.splitlines(True), name, name))
        if not args.check:
            write_atomically(path, new)
    print(f"{changed} golden file(s) {'differ' if args.check else 'changed'}", file=sys.stderr)
    return 1 if (args.check and changed) else 0


if __name__ == "__main__":
    sys.exit(main())
