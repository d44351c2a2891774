"""The kitchen's grip and put experience written as a plan writes those actions' start: the serving frame and the
free offsets from it (along, dist, heading), not the base's pose with zero offsets; the same physical episode,
so the kitchen's own "grasp" space predicts the same on both."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tailor.refinement.models.features import compute_features
from tailor.sims.episode import ActionCall
from tailor.sims.kitchen import world as W
from tailor.sims.kitchen.features import GRASP
from tailor.sims.kitchen.scenarios import in_frame, run_grip, run_put, subgoal_episode
from tailor.sims.kitchen.simulator import KitchenSim, Noise

OFFSETS = slice(3, 6)


def test_spot_offsets_invert_spot_pose():
    rng = np.random.default_rng(0)
    for _ in range(50):
        frame = (*rng.uniform(0, 10, 2), rng.uniform(-math.pi, math.pi))
        offsets = (rng.uniform(*W.SPOT_ALONG), rng.uniform(*W.SPOT_DIST), rng.uniform(*W.SPOT_HEADING))
        assert W.spot_offsets(frame, W.spot_pose(*frame, *offsets)) == pytest.approx(offsets, abs=1e-12)


@pytest.mark.parametrize("run, facing", [(run_grip, W.TABLE1[2]), (run_put, W.TABLE2[2])])
def test_grip_and_put_experience_records_the_free_offsets(run, facing):
    episodes = [run(seed) for seed in range(16)]
    offsets = np.array([e.params[OFFSETS] for e in episodes])
    # the offsets vary over their Fig. 5.12 ranges (zeros, the base's pose as its own frame, must not come back)
    assert np.all(np.ptp(offsets, axis=0) > np.array([0.3, 0.1, 0.5]))
    assert np.all((W.SPOT_DIST[0] - 0.05 <= offsets[:, 1]) & (offsets[:, 1] <= W.SPOT_DIST[1] + 0.05))
    for e in episodes:
        assert e.params[2] == pytest.approx(facing)  # the serving frame faces the table
        # every logged row is written in the same frame, its offsets near the start's (the base stands)
        assert np.all(e.state[:, :3] == e.params[:3])
        assert np.allclose(e.column("dist"), e.params[4], atol=0.1)


def test_in_frame_keeps_the_episode_and_what_the_grasp_space_sees():
    frame = W.serving_frame(W.TABLE1, *W.table_point(W.TABLE1, 0.2, 0.2))
    cup = W.table_point(W.TABLE1, 0.2, 0.2)
    sim = KitchenSim(3, Noise())
    sim.place(W.spot_pose(*frame, 0.3, 0.6, -0.4), {"table1": W.TABLE1}, {"cup1": cup})
    pose_spot = sim.run(ActionCall("grip", cup))
    spot = in_frame(pose_spot, frame)
    assert pose_spot.outcome == spot.outcome == "success" and spot.duration == pose_spot.duration
    assert np.all(pose_spot.params[OFFSETS] == 0.0)
    assert spot.params[OFFSETS] == pytest.approx((0.3, 0.6, -0.4), abs=0.05)  # up to the believed pose's noise
    for new, old in [(spot.params, pose_spot.params), *zip(spot.state, pose_spot.state)]:
        assert W.spot_pose(*new[:6]) == pytest.approx(tuple(old[:3]), abs=1e-12)
    assert np.all(spot.state[:, 6:] == pose_spot.state[:, 6:]) and np.all(spot.params[6:] == pose_spot.params[6:])
    both = compute_features(GRASP, np.array([spot.params, pose_spot.params]))
    assert both[0] == pytest.approx(both[1], abs=1e-9)


@pytest.mark.parametrize("action", ["grip", "put"])
def test_a_subgoal_episode_is_written_in_the_subgoals_frame(action):
    table = W.TABLE1 if action == "grip" else W.TABLE2
    point = W.table_point(table, -0.1, 0.15)
    frame = W.serving_frame(table, *point)
    spot = np.array([*frame, -0.2, 0.55, 0.5, *point])
    episode = subgoal_episode(action, spot, seed=5)
    assert np.all(episode.params[:3] == spot[:3])
    assert episode.params[OFFSETS] == pytest.approx(spot[OFFSETS], abs=0.05)
