"""Issue 32: every JSON output and report says where it comes from: the tailor version, the command line, the
seeds and the SHA-256 of the model files read, so a result can be told apart from another and made again."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import tailor
import synthetic_episodes
from tailor.cli.main import main
from tailor.outputs import Provenance, file_digest, provenance, provenance_lines

DOMAINS = Path(__file__).resolve().parents[1] / "domains"


def sha256(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def test_a_provenance_names_the_version_the_command_the_seeds_and_digests_the_models(tmp_path):
    model = tmp_path / "reach.json"
    model.write_bytes(b'{"any": "bytes"}\n')
    made = provenance(["refine", "arm", "letter-f"], {"seed": 3}, [model, str(model)])
    assert isinstance(made, Provenance) and made.version == tailor.__version__
    assert made.to_json() == {"tailor": tailor.__version__, "argv": ["tailor", "refine", "arm", "letter-f"],
                              "seeds": {"seed": 3}, "models": [{"file": str(model), "sha256": sha256(model)}]}
    assert file_digest(model) == hashlib.sha256(b'{"any": "bytes"}\n').hexdigest()
    lines = provenance_lines(made.to_json())
    assert lines[0] == f"tailor {tailor.__version__}; command: tailor refine arm letter-f; seeds: seed 3"
    assert lines[1] == f"model read: {model} (sha256 {sha256(model)})"
    with pytest.raises(tailor.TailorError, match="cannot read"):
        file_digest(tmp_path / "gone.json")


def test_refine_json_carries_the_command_line_as_the_program_was_called(tmp_path):
    """As the `tailor` program (its own process): argv is the command line after the program name."""
    env = {**os.environ, "MPLBACKEND": "Agg"}
    run = subprocess.run([sys.executable, "-m", "tailor.cli", "-q", "refine", "arm", "letter-f", "--json",
                          "--seed", "5"], capture_output=True, text=True, env=env, timeout=300,
                         check=False)
    assert run.returncode == 0, run.stderr
    data = json.loads(run.stdout)
    assert list(data)[:3] == ["schema", "units", "provenance"]
    reach = DOMAINS / "arm" / "models" / "reach.json"
    assert data["provenance"] == {"tailor": tailor.__version__,
                                  "argv": ["tailor", "-q", "refine", "arm", "letter-f", "--json", "--seed", "5"],
                                  "seeds": {"seed": 5}, "models": [{"file": str(reach), "sha256": sha256(reach)}]}


def test_the_digest_changes_when_a_model_file_changes(tmp_path, capsys):
    models = tmp_path / "models"
    shutil.copytree(DOMAINS / "arm" / "models", models)
    digests = []
    for change in (None, b" "):  # the same model, then one byte more (still valid JSON)
        if change:
            (models / "reach.json").write_bytes((models / "reach.json").read_bytes() + change)
        assert main(["refine", "arm", "letter-f", "--json", "--models", str(models)]) == 0
        read = json.loads(capsys.readouterr().out)["provenance"]["models"]
        assert [m["file"] for m in read] == [str(models / "reach.json")]
        assert read[0]["sha256"] == sha256(models / "reach.json")
        digests.append(read[0]["sha256"])
    assert digests[0] == sha256(DOMAINS / "arm" / "models" / "reach.json") != digests[1]


def test_refine_names_the_success_classifiers_and_the_meta_model_it_read(capsys):
    """soccer's score: the duration models of its two executable actions (the approach is a goToPose), the
    success classifier guarding the approach, and the meta model the filter judges with."""
    assert main(["refine", "soccer", "score", "--json", "--filter"]) == 0
    read = {Path(m["file"]).name: m["sha256"] for m in json.loads(capsys.readouterr().out)["provenance"]["models"]}
    assert set(read) == {"goToPose.json", "dribbleBall.json", "goToPose.collision.json", "meta.json"}
    assert all(read[name] == sha256(DOMAINS / "soccer" / "models" / name) for name in read)


def test_evaluate_json_carries_it(capsys):
    assert main(["-q", "evaluate", "soccer", "--episodes", "1", "--oracle-episodes", "0", "--horizon-episodes", "0",
                 "--seed", "2", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)["provenance"]
    assert (data["tailor"], data["seeds"]) == (tailor.__version__, {"seed": 2})
    folder = DOMAINS / "soccer" / "models"  # (worker processes load what their situations need: every file)
    assert data["models"] == [{"file": str(path), "sha256": sha256(path)} for path in sorted(folder.glob("*.json"))]


@pytest.mark.parametrize("argv", [["plan", "soccer", "score", "--json"], ["check", "soccer", "score", "--json"],
                                  ["domains", "--json"]])
def test_plan_check_and_domains_json_carry_it(argv, capsys):
    assert main(argv) == 0
    data = json.loads(capsys.readouterr().out)["provenance"]
    assert (data["tailor"], data["argv"][0], data["seeds"], data["models"]) == (tailor.__version__, "tailor", {}, [])


def test_the_training_report_carries_it_in_json_text_and_html(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr("tailor.sims.experience.gather", synthetic_episodes.gather)
    out = tmp_path / "out"
    assert main(["-q", "train", "soccer", "--only", "goToPosition", "--episodes", "24", "--n-i", "1,3", "--seed", "4",
                 "--out", str(out), "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    report = json.loads((out / "training" / "report.json").read_text())
    assert printed["provenance"] == report["provenance"]
    assert (report["provenance"]["tailor"], report["provenance"]["seeds"]) == (tailor.__version__, {"seed": 4})
    assert report["provenance"]["models"] == []  # goToPosition alone refines nothing: no model read
    line = provenance_lines(report["provenance"])[0]
    assert line in (out / "training" / "report.txt").read_text()
    assert line in (out / "training" / "report.html").read_text()  # (nothing in it to escape)
    assert '"provenance"' not in (out / "models" / "goToPosition.json").read_text()  # models: the same for a seed


def test_a_library_call_has_no_command_line(tmp_path, monkeypatch):
    from tailor.refinement.learning.recipe import load_recipe
    from tailor.refinement.learning.training import train_domain
    from tailor.cli.train import _only

    recipe = _only(load_recipe(DOMAINS / "soccer"), ("goToPosition",))
    report = train_domain(recipe, 24, 1, tmp_path, gather=synthetic_episodes.gather, n_i_candidates=(1, 3),
                          progress=False)
    assert report["provenance"] == {"tailor": tailor.__version__, "argv": [], "seeds": {"seed": 1}, "models": []}
