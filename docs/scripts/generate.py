"""Write the generated pages of the documentation site, or check that the committed ones are current.

    python docs/scripts/generate.py            # write docs/commands.md and docs/results/*.md, name what changed
    python docs/scripts/generate.py --check    # write nothing; print a diff and exit 1 where a page is stale
    python docs/scripts/generate.py --outputs  # also run the commands docs/getting-started.md shows the output
                                               # of, and write what they print now into it (a minute or so)

The pages are committed (they read on GitHub as well as in the site, and a change to a parser or a result file
shows in the diff that caused it); tests/test_docs.py runs `--check`, and `mkdocs build --strict` fails on a
stale page too (docs/scripts/hooks.py).
"""

from __future__ import annotations

import argparse
import difflib
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:  # run as a file or loaded by the mkdocs hook: its sibling modules
    sys.path.insert(0, str(HERE))

import commands_page  # noqa: E402
import results_pages  # noqa: E402
import shown_commands  # noqa: E402

DOCS = HERE.parent
WITH_OUTPUTS = ("getting-started.md",)  # pages that show what their commands print


def pages() -> dict[str, str]:
    """Every generated page: its path under docs/ and its text."""
    return {"commands.md": commands_page.page(), **results_pages.pages()}


def stale(generated: dict[str, str]) -> dict[str, str]:
    """The pages whose file differs from what is generated (or is missing), with a unified diff of each."""
    out = {}
    for name, text in generated.items():
        path = DOCS / name
        current = path.read_text(encoding="utf-8") if path.is_file() else ""
        if current != text:
            out[name] = "".join(difflib.unified_diff(current.splitlines(True), text.splitlines(True),
                                                     f"docs/{name} (committed)", f"docs/{name} (generated)"))
    return out


def orphans(generated: dict[str, str]) -> list[str]:
    """Result pages left from a domain that no longer has results."""
    return sorted(p.relative_to(DOCS).as_posix() for p in (DOCS / "results").glob("*.md")
                  if p.relative_to(DOCS).as_posix() not in generated)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="write nothing; exit 1 where a page is stale")
    parser.add_argument("--outputs", action="store_true",
                        help=f"also run the commands of {', '.join(WITH_OUTPUTS)} and write the outputs shown anew")
    args = parser.parse_args(argv)
    if args.outputs and not args.check:
        for name in WITH_OUTPUTS:
            path = DOCS / name
            with tempfile.TemporaryDirectory() as scratch:
                text = shown_commands.with_outputs(path.read_text(encoding="utf-8"), Path(scratch))
            if text != path.read_text(encoding="utf-8"):
                path.write_text(text, encoding="utf-8")
                print(f"wrote the outputs shown in docs/{name}")
    generated = pages()
    changed, left = stale(generated), orphans(generated)
    if args.check:
        for name, diff in changed.items():
            sys.stdout.write(diff or f"docs/{name}: missing\n")
        for name in left:
            print(f"docs/{name}: no longer generated (remove it)")
        if changed or left:
            print("stale generated pages: run `python docs/scripts/generate.py`", file=sys.stderr)
        return 1 if changed or left else 0
    for name in changed:
        path = DOCS / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(generated[name], encoding="utf-8")
        print(f"wrote docs/{name}")
    for name in left:
        (DOCS / name).unlink()
        print(f"removed docs/{name}")
    if not changed and not left:
        print("every generated page is current")
    return 0


if __name__ == "__main__":
    sys.exit(main())
