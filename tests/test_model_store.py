"""Where models are read from and written to: bundled models are never overwritten, `--models` and
$TAILOR_MODELS choose others, models trained into the user data folder are found there, and every command says
which it used."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from tailor.errors import ModelFileError
from tailor.cli.main import main
from tailor.refinement.model_store import USER_DATA, default_training_out, domain_key, resolve_models, user_root

DOMAINS = Path(__file__).resolve().parents[1] / "domains"


def test_the_default_training_folder_is_the_users_not_the_package(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path))
    assert user_root() == tmp_path / "tailor"
    assert default_training_out(DOMAINS / "soccer") == tmp_path / "tailor" / "soccer"


def test_folders_named_alike_never_share_a_data_folder(tmp_path, monkeypatch):
    """A copy named like a bundled domain, and two of your own folders of one name, each get their own data
    folder (models, experience, and the $TAILOR_MODELS lookup): the name plus a digest of the path."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    folders = [tmp_path / "x" / "soccer", tmp_path / "a" / "robot", tmp_path / "b" / "robot"]
    keys = [domain_key(folder) for folder in folders]
    assert domain_key(DOMAINS / "soccer") == "soccer" and len({"soccer", *keys}) == 4
    assert [key.rsplit("-", 1)[0] for key in keys] == ["soccer", "robot", "robot"]
    assert keys[1] == domain_key(tmp_path / "a" / ".." / "a" / "robot")  # the path resolved: one folder, one key
    assert [default_training_out(folder) for folder in folders] == [tmp_path / "data" / "tailor" / k for k in keys]
    monkeypatch.setenv("TAILOR_MODELS", str(tmp_path / "data" / "tailor"))
    (tmp_path / "data" / "tailor" / "soccer" / "models").mkdir(parents=True)  # trained for the bundled soccer
    assert resolve_models(folders[0]).origin == "domain folder"  # not the copy's


def test_models_are_resolved_from_the_option_then_the_variable_then_the_domain(tmp_path, monkeypatch):
    trained = tmp_path / "run"
    (trained / "models").mkdir(parents=True)
    assert resolve_models(DOMAINS / "soccer", trained).path == trained / "models"  # a training output folder
    assert resolve_models(DOMAINS / "soccer", trained / "models").origin == "--models"
    with pytest.raises(ModelFileError, match="no such model folder"):
        resolve_models(DOMAINS / "soccer", tmp_path / "missing")
    assert resolve_models(DOMAINS / "soccer").path == DOMAINS / "soccer" / "models"
    monkeypatch.setenv("TAILOR_MODELS", str(tmp_path))
    (tmp_path / "soccer" / "models").mkdir(parents=True)
    chosen = resolve_models(DOMAINS / "soccer")
    assert (chosen.path, chosen.origin) == (tmp_path / "soccer" / "models", "$TAILOR_MODELS")
    assert resolve_models(DOMAINS / "arm").origin == "domain folder"  # nothing trained for the arm there


def test_refine_uses_the_models_it_is_given_and_says_so(tmp_path, capsys):
    """Models copied elsewhere and made twice as slow double every prediction; the line names the folder."""
    models = tmp_path / "slow"
    shutil.copytree(DOMAINS / "arm" / "models", models)
    data = json.loads((models / "reach.json").read_text())
    bundled = main(["refine", "arm", "letter-f", "--json"])
    assert bundled == 0
    out, err = capsys.readouterr()
    assert f"action models: {DOMAINS / 'arm' / 'models'} (domain folder)" in err
    base = json.loads(out)
    _scale_model(data, 2.0)
    (models / "reach.json").write_text(json.dumps(data))
    assert main(["refine", "arm", "letter-f", "--json", "--models", str(models)]) == 0
    out, err = capsys.readouterr()
    assert f"action models: {models} (--models)" in err
    slow = json.loads(out)
    assert slow["models"] == str(models)
    assert slow["greedy"]["predicted_total"] == pytest.approx(2 * base["greedy"]["predicted_total"], rel=1e-3)


def test_a_missing_models_folder_is_one_line(tmp_path, capsys):
    assert main(["refine", "arm", "letter-f", "--models", str(tmp_path / "none")]) == 12
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"tailor refine: error: {tmp_path / 'none'}: no such model folder (--models)"]


def _scale_model(data: dict, factor: float) -> None:
    """Multiply every leaf's linear model (coefficients and intercept) by `factor`, wherever it is stored."""
    def walk(node):
        if isinstance(node, dict):
            for key, value in node.items():
                if key in ("coef", "intercept", "coefficients", "constant"):
                    node[key] = [v * factor for v in value] if isinstance(value, list) else value * factor
                else:
                    walk(value)
        elif isinstance(node, list):
            for item in node:
                walk(item)
    walk(data)


def test_train_without_out_writes_the_users_folder_and_never_the_bundled_models(tmp_path, monkeypatch, capsys):
    import synthetic_episodes

    monkeypatch.setattr("tailor.sims.experience.gather", synthetic_episodes.gather)
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path))
    bundled = {p.name: p.read_bytes() for p in (DOMAINS / "soccer" / "models").iterdir()}
    assert main(["train", "soccer", "--only", "goToPosition", "--episodes", "24", "--n-i", "1,3"]) == 0
    out = tmp_path / "tailor" / "soccer"
    printed = capsys.readouterr().out
    assert f"  {out / 'models' / 'goToPosition.json'}" in printed  # every file named, in the user's folder
    assert "`tailor refine soccer PROBLEM` uses them from now on" in printed
    assert {p.name for p in (out / "models").iterdir()} == {"goToPosition.json"}
    assert {p.name: p.read_bytes() for p in (DOMAINS / "soccer" / "models").iterdir()} == bundled
    chosen = resolve_models(DOMAINS / "soccer")  # what the printed line says: refine finds them, no variable set
    assert (chosen.path, chosen.origin) == (out / "models", "user data folder")


@pytest.fixture(scope="module")
def module_data_home():
    """What a module-scoped fixture sees (set up before the per-test isolation of conftest.py)."""
    import os

    return os.environ.get("XDG_DATA_HOME"), os.environ.get("TAILOR_MODELS")


def test_no_test_sees_the_developers_data_folder(module_data_home, tmp_path_factory):
    """The user data folder of every test, and of every module fixture, is a temporary one (conftest.py)."""
    base = tmp_path_factory.getbasetemp()
    data_home, variable = module_data_home
    assert variable is None and data_home is not None and base in Path(data_home).parents
    assert base in user_root().parents


def test_models_are_found_in_the_order_option_variable_user_data_folder_bundled(tmp_path, monkeypatch):
    """Issue 32: `tailor train room` wrote to the user data folder and `tailor refine room tour` did not look
    there. The order: --models, $TAILOR_MODELS/<domain>, <user data>/<domain>/models (where training wrote
    model files), the bundled models."""
    soccer = DOMAINS / "soccer"
    trained = default_training_out(soccer) / "models"
    trained.mkdir(parents=True)
    assert resolve_models(soccer).origin == "domain folder"  # an empty folder: nothing trained there
    (trained / "goToPosition.json").write_text("{}")
    assert (resolve_models(soccer).path, resolve_models(soccer).origin) == (trained, USER_DATA)
    assert resolve_models(DOMAINS / "arm").origin == "domain folder"  # trained for soccer only
    monkeypatch.setenv("TAILOR_MODELS", str(tmp_path / "root"))
    assert resolve_models(soccer).origin == USER_DATA  # the variable names no folder for soccer
    (tmp_path / "root" / "soccer" / "models").mkdir(parents=True)
    assert resolve_models(soccer).origin == "$TAILOR_MODELS"
    (tmp_path / "mine").mkdir()
    assert resolve_models(soccer, tmp_path / "mine").origin == "--models"


def test_refine_uses_the_models_training_wrote_to_the_user_data_folder_and_says_so(capsys):
    """The models `tailor train arm` (without --out) would write, made twice as slow: refine reads them without
    being told, names the folder on stderr and in the JSON, and digests the file it read."""
    import hashlib

    folder = default_training_out(DOMAINS / "arm") / "models"
    folder.mkdir(parents=True)
    data = json.loads((DOMAINS / "arm" / "models" / "reach.json").read_text())
    _scale_model(data, 2.0)
    (folder / "reach.json").write_text(json.dumps(data))
    assert main(["refine", "arm", "letter-f", "--json"]) == 0
    out, err = capsys.readouterr()
    assert f"action models: {folder} (user data folder)" in err
    result = json.loads(out)
    assert result["models"] == str(folder)
    assert result["provenance"]["models"] == [
        {"file": str(folder / "reach.json"), "sha256": hashlib.sha256((folder / "reach.json").read_bytes()).hexdigest()}]
