"""MkDocs hooks of the documentation site (mkdocs.yml `hooks:`).

- A generated page that is not what docs/scripts/generate.py makes now is a warning, so `mkdocs build --strict`
  fails on it as on a broken link.
- The results pages show the pictures committed beside each domain's results (domains/NAME/training/*.png):
  they are added to the site under results/NAME/, and the pages' links to them, written relative to the
  repository so that they work on GitHub too, are pointed there.
- The changelog page shows the repository's CHANGELOG.md, its links into docs/ made relative to the page.
"""

from __future__ import annotations

import logging
import re
import sys
from pathlib import Path

from mkdocs.structure.files import File

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))

import generate  # noqa: E402


log = logging.getLogger("mkdocs.plugins.tailor")

PICTURE = re.compile(r"\]\(\.\./\.\./domains/([\w-]+)/training/([\w.-]+\.png)\)")
CHANGELOG_MARK = "<!-- CHANGELOG.md -->"


def on_startup(command, dirty, **kwargs) -> None:
    # Run as the `mkdocs` script, Python puts the script's folder first on sys.path, and that folder holds the
    # `tailor` script too: griffe (mkdocstrings) would take that file for the `tailor` package and find nothing in
    # it. The package is found through its installed finder (pip install -e) or site-packages, which stay. (Not
    # at import, since mkdocs puts sys.path back as it was after loading a hook; and before any plugin's on_config,
    # where mkdocstrings makes its handler.)
    sys.path[:] = [p for p in sys.path if not (Path(p or ".") / "tailor").is_file()]


def on_pre_build(config, **kwargs) -> None:
    for name in generate.stale(generate.pages()):
        log.warning(f"docs/{name} is not what docs/scripts/generate.py makes now: run `python docs/scripts/generate.py`")


def on_files(files, config, **kwargs):
    for png in sorted((ROOT / "domains").glob("*/training/*.png")):
        uri = f"results/{png.parent.parent.name}/{png.name}"
        files.append(File.generated(config, uri, abs_src_path=str(png)))
    return files


def on_page_markdown(markdown: str, page, config, files, **kwargs) -> str:
    if page.file.src_uri.startswith("results/"):
        return PICTURE.sub(r"](\1/\2)", markdown)
    if CHANGELOG_MARK in markdown:
        changelog = ROOT / "CHANGELOG.md"
        if not changelog.is_file():
            return markdown.replace(CHANGELOG_MARK, "# Changelog\n\nThere is no CHANGELOG.md in this tree yet.")
        text = changelog.read_text(encoding="utf-8")
        text = re.sub(r"\]\(docs/", "](", text)  # a link into docs/ from the repository's root
        return markdown.replace(CHANGELOG_MARK, text)
    return markdown
