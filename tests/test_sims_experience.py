"""Experience gathering: independence of the worker count, storage round trip, malformed files."""

import numpy as np
import pytest

from tailor.sims.errors import SimError
from tailor.sims.experience import gather, load_episodes, save_episodes


def _same(a, b):
    assert len(a) == len(b)
    for x, y in zip(a, b):
        assert (x.action, x.outcome, x.duration, x.seed) == (y.action, y.outcome, y.duration, y.seed)
        for f in ("params", "t", "robot", "ball"):
            np.testing.assert_array_equal(getattr(x, f), getattr(y, f))


def test_gather_is_the_same_whatever_the_number_of_jobs():
    one = gather("goToPoseAtBall", 12, seed=5, jobs=1, progress=False)
    two = gather("goToPoseAtBall", 12, seed=5, jobs=2, progress=False)
    _same(one, two)
    assert len({e.seed for e in one}) == 12


def test_save_load_round_trip(tmp_path):
    eps = gather("approachBall", 3, seed=1, progress=False)
    path = tmp_path / "exp.npz"
    save_episodes(path, eps)
    _same(load_episodes(path), eps)


def test_malformed_file_names_the_file(tmp_path):
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not an npz")
    with pytest.raises(SimError, match="bad.npz"):
        load_episodes(bad)
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(SimError, match="other.npz: not an episode file"):
        load_episodes(tmp_path / "other.npz")
