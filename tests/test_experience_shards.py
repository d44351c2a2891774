"""Persisted experience: shards gathered apart merge bit for bit into one serial gather; gaps are simulated,
overlaps and foreign files are one-line errors; Ctrl-C keeps the finished episodes as a complete shard; parallel
gathering on the multiprocessing and Dask backends gives the serial episodes."""

from __future__ import annotations

import dataclasses
import importlib.util
import os

import numpy as np
import pytest

from tailor.errors import BackendError, DataError
from tailor.cli.main import main
from tailor.sims import experience, registry
from tailor.sims.experience import SCHEMA, Origin, episode_seeds, gather, load_episodes, read_origin, save_episodes
from tailor.sims.parallel import backend_session
from tailor.sims.shards import find_shards, stored_gather, write_shard

SIM, SCENARIO = "soccer", "approachBall"


def same(a, b) -> None:
    """Bit-identical episode lists."""
    assert len(a) == len(b)
    for x, y in zip(a, b):
        assert (x.action, x.outcome, x.duration, x.seed, x.columns) == (y.action, y.outcome, y.duration, y.seed,
                                                                         y.columns)
        for field in ("params", "t", "state"):
            assert getattr(x, field).tobytes() == getattr(y, field).tobytes()


@pytest.fixture(scope="module")
def serial():
    return gather(SIM, SCENARIO, 14, seed=3, progress=False)


def no_simulation(*args, **kwargs):
    raise AssertionError("simulated episodes that the shards hold")


def test_shards_gathered_apart_merge_into_the_serial_gather(tmp_path, serial, monkeypatch, capsys):
    for seeds in ("0:6", "6:14"):
        assert main(["gather", "soccer", "--seeds", seeds, "--seed", "3", "--scenario", SCENARIO,
                     "--out", str(tmp_path)]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"{SCENARIO}.seed3.0-6.npz", f"{SCENARIO}.seed3.6-14.npz"]
    assert read_origin(tmp_path / f"{SCENARIO}.seed3.6-14.npz") == Origin(SIM, SCENARIO, 3, 6, 14,
                                                                          registry.code_fingerprint(SIM))
    monkeypatch.setattr(experience, "gather", no_simulation)  # everything is on disk: nothing is simulated
    same(stored_gather(tmp_path, SIM, SCENARIO, 14, seed=3, progress=False), serial)
    same(stored_gather(tmp_path, SIM, SCENARIO, 5, seed=3, progress=False, first=4), serial[4:9])  # across shards


def test_gaps_are_simulated_and_kept(tmp_path, serial):
    write_shard(tmp_path, Origin(SIM, SCENARIO, 3, 2, 5), serial[2:5])
    write_shard(tmp_path, Origin(SIM, SCENARIO, 3, 9, 11), serial[9:11])
    same(stored_gather(tmp_path, SIM, SCENARIO, 14, seed=3, progress=False), serial)
    ranges = sorted((s.origin.first, s.origin.stop) for s in find_shards(tmp_path, SIM))
    assert ranges == [(0, 2), (2, 5), (5, 9), (9, 11), (11, 14)]  # the gaps are shards now, no more, no less


def test_overlapping_shards_name_both_files(tmp_path, serial, capsys):
    write_shard(tmp_path, Origin(SIM, SCENARIO, 3, 0, 6), serial[:6])
    write_shard(tmp_path, Origin(SIM, SCENARIO, 3, 4, 8), serial[4:8])
    with pytest.raises(DataError, match=rf"{SCENARIO}.seed3.0-6.npz: overlaps {SCENARIO}.seed3.4-8.npz "
                                        r"\(episodes 4:6 are in both\): remove one of them"):
        stored_gather(tmp_path, SIM, SCENARIO, 8, seed=3, progress=False)
    code = main(["train", "soccer", "--episodes", "8", "--seed", "3", "--out", str(tmp_path / "out"),
                 "--experience", str(tmp_path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 14 and err[-1].startswith("tailor train: error: ") and "overlaps" in err[-1]
    assert not (tmp_path / "out" / "models").exists()


def test_other_streams_in_the_folder_are_left_alone(tmp_path, serial, monkeypatch):
    write_shard(tmp_path, Origin(SIM, SCENARIO, 3, 0, 14), serial)
    other = gather(SIM, "goToPose", 3, seed=3, progress=False)
    write_shard(tmp_path, Origin(SIM, "goToPose", 3, 0, 3), other)
    monkeypatch.setattr(experience, "gather", no_simulation)
    same(stored_gather(tmp_path, SIM, SCENARIO, 14, seed=3, progress=False), serial)


@pytest.mark.parametrize("fault, message", [
    ("simulator", "a shard of simulator 'arm', not 'soccer': one experience folder per simulator"),
    ("renamed", "holds episodes 0:4 of approachBall seed 3, which its name does not say "
                "(expected approachBall.seed3.0-4.npz)"),
    ("schema", f"episode schema 99, expected {SCHEMA}"),
    ("no origin", "an episode file without its origin (simulator, scenario, seed range) is not a shard"),
    ("seeds", "its episodes' seeds are not those of approachBall seed 3, episodes 0:4"),
    ("garbage", "not an episode file (not an .npz archive)"),
    ("code", "gathered by simulator code 0123456789abcdef, and 'soccer' is code "),
    ("no code", "gathered before tailor recorded the simulator's code, and 'soccer' is code "),
    ("nan duration", "its duration hold values that are not finite (NaN or infinity)"),
    ("inf params", "its params hold values that are not finite (NaN or infinity)"),
    ("negative duration", "episode 0 has a negative duration"),
    ("text durations", "its duration are not numbers (<U"),
    ("other action", "episode 0 is 'fly' with 8 parameters, not 'approachBall' of scenario approachBall with 8"),
    ("fewer params", "episode 0 is 'approachBall' with 3 parameters, not 'approachBall' of scenario approachBall"),
])
def test_a_shard_that_does_not_match_is_one_line_naming_the_file(tmp_path, serial, fault, message):
    path = tmp_path / f"{SCENARIO}.seed3.0-4.npz"
    write_shard(tmp_path, Origin(SIM, SCENARIO, 3, 0, 4), serial[:4])
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    if fault == "simulator":
        arrays["simulator"] = np.array("arm")
    elif fault == "renamed":
        path.unlink()
        path = tmp_path / f"{SCENARIO}.seed3.0-5.npz"
    elif fault == "schema":
        arrays["schema"] = np.array(99)
    elif fault == "no origin":
        del arrays["first"]
    elif fault == "seeds":
        arrays["seed"] = arrays["seed"][::-1].copy()
    elif fault == "code":
        arrays["simulator_code"] = np.array("0123456789abcdef")
    elif fault == "no code":
        del arrays["simulator_code"]
    elif fault == "nan duration":
        arrays["duration"][0] = np.nan
    elif fault == "inf params":
        arrays["params"][0, 0] = np.inf
    elif fault == "negative duration":
        arrays["duration"][0] = -5.0
    elif fault == "text durations":
        arrays["duration"] = arrays["duration"].astype(str)
    elif fault == "other action":
        arrays["action"] = np.array(["fly"] + list(arrays["action"][1:]))
    elif fault == "fewer params":
        arrays["params"] = arrays["params"][:, :3].copy()
    if fault == "garbage":
        path.write_bytes(b"PK\x03\x04 half a zip")
    else:
        np.savez_compressed(path, **arrays)
    with pytest.raises(DataError) as error:
        stored_gather(tmp_path, SIM, SCENARIO, 4, seed=3, progress=False)
    assert str(error.value) == f"{path}: {message}" or str(error.value).startswith(f"{path}: {message}")
    assert "\n" not in str(error.value)


def test_the_code_fingerprint_follows_the_simulators_package(tmp_path, monkeypatch):
    """Experience is stamped with a fingerprint of the simulator package's files: editing any of them (a
    controller's constant) changes it, so shards gathered before are refused rather than trained on."""
    package = tmp_path / "my_robot"
    package.mkdir()
    (package / "__init__.py").write_text("def create(seed, noise=None):\n    return None\n")
    (package / "controller.py").write_text("A_MAX = 0.6\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    import my_robot

    monkeypatch.setattr(registry, "get", lambda name: type("Entry", (), {"create": staticmethod(my_robot.create)}))
    fingerprints = []
    try:
        for a_max in ("0.6", "0.3", "0.6"):
            (package / "controller.py").write_text(f"A_MAX = {a_max}\n")
            registry.code_fingerprint.cache_clear()
            fingerprints.append(registry.code_fingerprint("my_robot"))
    finally:
        registry.code_fingerprint.cache_clear()
    assert len(fingerprints[0]) == 16 and fingerprints[1] != fingerprints[0] == fingerprints[2]


def test_ctrl_c_keeps_the_finished_episodes_as_a_complete_shard(tmp_path, serial, monkeypatch, caplog):
    batches = []
    run_batch = experience._run_batch

    def interrupted(*args):
        if len(batches) == 1:  # the second batch of EPISODES_PER_TASK: Ctrl-C
            raise KeyboardInterrupt
        batches.append(args)
        return run_batch(*args)

    monkeypatch.setattr(experience, "EPISODES_PER_TASK", 4)
    monkeypatch.setattr(experience, "_run_batch", interrupted)
    with pytest.raises(KeyboardInterrupt):
        stored_gather(tmp_path, SIM, SCENARIO, 14, seed=3, progress=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"{SCENARIO}.seed3.0-4.npz"]  # no temporary file left
    assert "kept the 4 finished episodes" in caplog.text  # (a warning: on stderr even with -q)
    monkeypatch.setattr(experience, "_run_batch", run_batch)
    same(stored_gather(tmp_path, SIM, SCENARIO, 14, seed=3, progress=False), serial)  # resumed after them
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"{SCENARIO}.seed3.0-4.npz", f"{SCENARIO}.seed3.4-14.npz"]


def test_an_interrupted_write_leaves_no_file(tmp_path, serial, monkeypatch):
    def interrupted(file, **arrays):
        file.write(b"half")
        raise KeyboardInterrupt

    monkeypatch.setattr(np, "savez_compressed", interrupted)
    with pytest.raises(KeyboardInterrupt):
        save_episodes(tmp_path / "x.npz", serial[:2], Origin(SIM, SCENARIO, 3, 0, 2))
    assert list(tmp_path.iterdir()) == []


def synthetic_gather(simulator, name, episodes, seed, jobs=1, progress=True, first=0, into=None):
    """tests/synthetic_episodes.gather with each episode's seed the one of its place in the stream."""
    import synthetic_episodes

    made = synthetic_episodes.gather(simulator, name, episodes, seed, first=first)
    made = [dataclasses.replace(e, seed=s) for e, s in zip(made, episode_seeds(seed, episodes, first))]
    out = [] if into is None else into
    out.extend(made)
    return out


def stop_after_gathering(monkeypatch) -> None:
    """Training itself is covered by test_train_cli: here `tailor train` stops (Ctrl-C) once it has gathered."""

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("tailor.refinement.learning.training.train_duration_model", interrupted)


def test_train_keeps_its_experience_and_reuses_it(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(experience, "gather", synthetic_gather)
    stop_after_gathering(monkeypatch)
    args = ["train", "soccer", "--episodes", "12", "--fresh-episodes", "10", "--experience", str(tmp_path / "exp"),
            "--out", str(tmp_path / "out")]
    assert main(args) == 130
    names = sorted(p.name for p in (tmp_path / "exp").iterdir())
    assert names == ["approachBall.seed0.0-12.npz", "dribbleBall.seed0.0-12.npz", "goToPose.seed0.0-12.npz",
                     "goToPoseAtBall.seed0.0-12.npz", "goToPoseAtBall.seed7919000.0-10.npz",  # the fresh episodes too
                     "goToPoseFarSide.seed0.0-12.npz", "goToPoseFarSide.seed7919000.0-10.npz",  # the classifier's 2nd
                     "goToPosition.seed0.0-12.npz"]
    same(load_episodes(tmp_path / "exp" / "goToPose.seed0.0-12.npz"), synthetic_gather(SIM, "goToPose", 12, 0))
    assert not (tmp_path / "out" / "models").exists()
    monkeypatch.setattr(experience, "gather", no_simulation)
    assert main(args) == 130  # everything read from the shards: nothing simulated the second time
    assert "read from 1 shard(s)" in capsys.readouterr().err


def test_train_extends_the_experience_it_has(tmp_path, monkeypatch):
    monkeypatch.setattr(experience, "gather", synthetic_gather)
    stop_after_gathering(monkeypatch)
    exp = tmp_path / "exp"
    base = ["train", "soccer", "--fresh-episodes", "10", "--experience", str(exp), "--out", str(tmp_path / "out")]
    assert main([*base, "--episodes", "8"]) == 130
    assert main([*base, "--episodes", "12"]) == 130
    assert {(s.origin.scenario, s.origin.first, s.origin.stop) for s in find_shards(exp, SIM)
            if s.origin.scenario == "goToPose"} == {("goToPose", 0, 8), ("goToPose", 8, 12)}


def test_gather_command_errors_are_one_line(tmp_path, capsys):
    assert main(["gather", "soccer", "--seeds", "0:4", "--scenario", "kick", "--out", str(tmp_path)]) == 14
    assert capsys.readouterr().err.strip() == ("tailor gather: error: 'soccer' trains on no experience scenario "
                                               "'kick' (known: goToPose, approachBall, dribbleBall, goToPosition, "
                                               "goToPoseAtBall, goToPoseFarSide)")
    with pytest.raises(SystemExit) as exit:
        main(["gather", "soccer", "--seeds", "5:5"])
    assert exit.value.code == 2
    assert "expected 0 <= A < B <= 9223372036854775807, got '5:5'" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exit:  # shards store seeds as 64-bit integers
        main(["gather", "soccer", "--seeds", "0:2", "--seed", str(2**63)])
    assert exit.value.code == 2
    assert "argument --seed: must be at most 9223372036854775807" in capsys.readouterr().err
    assert main(["gather", "soccer", "--seeds", "0:4", "--scheduler", "tcp://x:1", "--out", str(tmp_path)]) == 17
    assert "--scheduler joins a Dask or Ray cluster" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_the_multiprocessing_backend_gathers_the_serial_episodes(serial):
    from joblib import parallel_config

    with parallel_config(backend="multiprocessing"):  # cannot stream results: gathered in ordered waves
        same(gather(SIM, SCENARIO, 14, seed=3, jobs=2, progress=False), serial)


@pytest.mark.skipif(importlib.util.find_spec("distributed") is None, reason="needs the dask extra")
def test_a_local_dask_cluster_gathers_the_serial_episodes(serial):
    with backend_session("dask", jobs=2):
        same(gather(SIM, SCENARIO, 14, seed=3, jobs=1, progress=False), serial)


def test_a_missing_backend_is_named(monkeypatch):
    monkeypatch.setattr("tailor.sims.parallel.missing_packages", lambda backend: ["ray"])
    with pytest.raises(BackendError, match=r"backend 'ray' needs ray: pip install 'tailor\[ray\]'"):
        with backend_session("ray", jobs=1):
            pass


def test_ctrl_c_in_a_gather_with_workers_leaves_complete_shards_only(tmp_path):
    import signal
    import subprocess
    import sys
    import time

    process = subprocess.Popen([sys.executable, "-m", "tailor.cli", "gather", "soccer", "--seeds", "0:20000",
                                "--scenario", SCENARIO, "--jobs", "2", "--out", str(tmp_path)],
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        time.sleep(8)  # the workers started, some batches done (or not: then no shard at all)
        process.send_signal(signal.SIGINT)
        assert process.wait(timeout=60) == 130
        err = process.stderr.read().strip()
        assert err.endswith("tailor gather: interrupted") and "Traceback" not in err
    finally:
        try:
            os.killpg(process.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    shards = find_shards(tmp_path, SIM)  # every file a complete shard: no temporary file, nothing half-written
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(s.path.name for s in shards)
    assert all(s.origin.first == 0 and s.origin.stop < 20000 for s in shards)
    for shard in shards:
        episodes = stored_gather(tmp_path, SIM, SCENARIO, shard.origin.stop, seed=0, progress=False)  # no gap
        assert [e.seed for e in episodes] == episode_seeds(0, shard.origin.stop)
