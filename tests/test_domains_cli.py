"""`tailor domains` names a domain by its PDDL name, and says the folder where that differs."""

from __future__ import annotations

import json
from pathlib import Path

from tailor.cli.main import main

FIXTURE = Path(__file__).parent / "fixtures" / "pointmass" / "domain"


def test_a_folder_is_named_by_its_pddl_domain(capsys):
    assert main(["domains", str(FIXTURE), "--json"]) == 0
    listing = json.loads(capsys.readouterr().out)
    rail = next(d for d in listing["domains"] if d["path"] == str(FIXTURE))
    assert (rail["name"], rail["folder"]) == ("rail", "domain")
    soccer = next(d for d in listing["domains"] if d["folder"] == "soccer")
    assert soccer["name"] == "soccer"
    assert main(["domains", str(FIXTURE)]) == 0
    line = next(l for l in capsys.readouterr().out.splitlines() if l.strip().startswith("rail "))
    assert line.endswith(f"(folder {FIXTURE})")
