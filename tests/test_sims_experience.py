"""Experience gathering: independence of the worker count, storage round trip, malformed files."""

import numpy as np
import pytest

from tailor.errors import DataError, SimError
from tailor.sims.experience import SCHEMA, gather, load_episodes, save_episodes


def _same(a, b):
    assert len(a) == len(b)
    for x, y in zip(a, b):
        assert (x.action, x.outcome, x.duration, x.seed) == (y.action, y.outcome, y.duration, y.seed)
        assert x.columns == y.columns == ("x", "y", "phi", "v", "ball_x", "ball_y")
        for f in ("params", "t", "state"):
            np.testing.assert_array_equal(getattr(x, f), getattr(y, f))


def test_gather_is_the_same_whatever_the_number_of_jobs():
    one = gather("soccer", "goToPoseAtBall", 12, seed=5, jobs=1, progress=False)
    two = gather("soccer", "goToPoseAtBall", 12, seed=5, jobs=2, progress=False)
    _same(one, two)
    assert len({e.seed for e in one}) == 12
    assert {e.action for e in one} == {"goToPose"}  # the scenario's action


def test_gather_names_an_unknown_simulator_or_scenario():
    with pytest.raises(SimError, match=r"no simulator 'hovercraft' is installed"):
        gather("hovercraft", "goToPose", 1, seed=0, progress=False)
    with pytest.raises(SimError, match=r"simulator 'soccer' has no experience scenario 'kick'; known: goToPose, "):
        gather("soccer", "kick", 1, seed=0, progress=False)


def test_save_load_round_trip(tmp_path):
    eps = gather("soccer", "approachBall", 3, seed=1, progress=False)
    path = tmp_path / "exp.npz"
    save_episodes(path, eps)
    _same(load_episodes(path), eps)


def test_malformed_file_names_the_file(tmp_path):
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not an npz")
    with pytest.raises(DataError, match="bad.npz: not an episode file"):
        load_episodes(bad)
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(DataError, match="other.npz: not an episode file"):
        load_episodes(tmp_path / "other.npz")
    eps = gather("soccer", "goToPose", 2, seed=1, progress=False)
    save_episodes(tmp_path / "old.npz", eps)
    with np.load(tmp_path / "old.npz") as data:
        arrays = {k: data[k] for k in data.files}
    np.savez(tmp_path / "old.npz", **{**arrays, "schema": np.array(1)})
    with pytest.raises(DataError, match=f"old.npz: episode schema 1, expected {SCHEMA}"):
        load_episodes(tmp_path / "old.npz")


def test_a_ctrl_c_swallowed_during_a_call_still_stops_a_serial_run():
    """pymunk frees its shapes in a cffi callback whose exceptions Python drops: a Ctrl-C landing there was lost
    and a gather ran on to the end (2 of 30 tries). The serial runner remembers it and stops after the call."""
    import os
    import signal
    import time

    from tailor.sims.parallel import ordered_results

    def swallowing(i):
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)  # (the handler runs here)
        except KeyboardInterrupt:
            pass  # as Python does in a garbage-collection callback
        return i

    done = []
    with pytest.raises(KeyboardInterrupt):
        for value in ordered_results(swallowing, [(1,), (2,), (3,)]):
            done.append(value)
    assert done == [] and signal.getsignal(signal.SIGINT) is signal.default_int_handler
    assert list(ordered_results(lambda i: i, [(1,), (2,)])) == [1, 2]  # and nothing is remembered after it
