"""The robots' own feature spaces declare sound enclosures (FeatureSpace.bounds) for the certified optimizer:
every feature value of every parameter vector in a box lies within the box's bounds, checked against dense
random sampling (corners included) in random small and large boxes; at a single point the bounds shrink to the
features; and the check has teeth: the same bounds shrunk by 10% of their width toward their middle fail it."""

from __future__ import annotations

import numpy as np
import pytest
from tailor.sims import intervals as I
from tailor.sims.arm import world as AW
from tailor.sims.arm.features import RAMPS
from tailor.sims.kinematics import transfer_time
from tailor.sims.kitchen import world as KW
from tailor.sims.kitchen.features import GRASP, ROUTE
from tailor.sims.soccer import dubins
from tailor.sims.soccer import feature_bounds as B
from tailor.sims.soccer.features import APPROACH, DRIBBLE, GOTO_SPACE
from tailor.sims.soccer.walls import POSE_WALLS

SAMPLES = 300  # parameter vectors per box, the box's corners among them
SHRINK = 0.1


def sample(low: np.ndarray, high: np.ndarray, rng: np.random.Generator, samples: int = SAMPLES) -> np.ndarray:
    """(k, samples, p) points of each box: up to 64 of its corners (those varying the widest parameters), the
    rest uniform inside."""
    k, p = low.shape
    u = rng.uniform(size=(k, samples, p))
    m = min(6, p)
    wide = np.argsort(-(high - low), axis=1)[:, :m]  # corners over the (up to) six widest parameters
    bits = ((np.arange(2 ** m)[:, None] >> np.arange(m)[None, :]) & 1).astype(float)
    rows = np.arange(2 ** m)
    for r in range(k):
        u[r, rows[:, None], wide[r][None, :]] = bits
    return low[:, None] + (high - low)[:, None] * u


def violations(space, low: np.ndarray, high: np.ndarray, rng: np.random.Generator, shrink: float = 0.0) -> int:
    """How many sampled features lie outside their box's bounds (shrunk by `shrink` of their width)."""
    f_lo, f_hi = space.bounds(low, high)
    assert f_lo.shape == f_hi.shape == (len(low), len(space.names))
    assert np.all(f_lo <= f_hi)
    with np.errstate(invalid="ignore"):  # (inf - inf: an unbounded end is not shrunk)
        width = np.where(np.isfinite(f_hi - f_lo), f_hi - f_lo, 0.0)
    f_lo, f_hi = f_lo + shrink * width, f_hi - shrink * width
    points = sample(low, high, rng)
    F = space(points.reshape(-1, low.shape[1])).reshape(points.shape[0], points.shape[1], -1)
    return int(np.sum((F < f_lo[:, None]) | (F > f_hi[:, None])))


def boxes(rng: np.random.Generator, ranges: np.ndarray, n: int, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """n random boxes within `ranges` (p, 2), each side up to `scale` of its range (squared: many narrow)."""
    span = ranges[:, 1] - ranges[:, 0]
    width = span * scale * rng.uniform(size=(n, len(span))) ** 2
    low = ranges[:, 0] + (span - width) * rng.uniform(size=(n, len(span)))
    return low, low + width


def check_space(space, ranges: np.ndarray, seed: int, fixed: tuple[int, ...] = (), n: int = 150,
                tight_share: float = 0.97) -> None:
    """Sound on large and small boxes (and on boxes with `fixed` parameters a point, as refinement passes them),
    tight at (at least `tight_share` of) points, and a 10% shrink is caught."""
    rng = np.random.default_rng(seed)
    caught = 0
    for scale in (1.0, 0.2, 0.02, 1e-3):
        low, high = boxes(rng, ranges, n, scale)
        if fixed:
            high[:, list(fixed)] = low[:, list(fixed)]
        assert violations(space, low, high, rng) == 0, f"unsound at scale {scale}"
        caught += violations(space, low, high, rng, SHRINK)
    assert caught > 0, "a 10% shrink went unnoticed: the sampling has no teeth"
    point = boxes(rng, ranges, 200, 0.0)[0]
    f_lo, f_hi = space.bounds(point, point)
    values = space(point)
    near = np.isfinite(values)
    assert np.all(f_lo[near] <= values[near]) and np.all(values[near] <= f_hi[near])
    with np.errstate(invalid="ignore"):
        tight = (f_hi - f_lo) <= 1e-6 * (1.0 + np.abs(values))
    assert tight.mean() >= tight_share, f"the bounds shrink to the features at only {tight.mean():.0%} of points"


# --- the time-optimal transfer -------------------------------------------------------------------------------
@pytest.mark.parametrize("tol", [1e-9, 1e-12])
def test_the_transfer_time_enclosure_holds_on_boxes_across_and_beside_the_direct_ramp(tol):
    """Boxes of (d, v0, vg) anywhere, and boxes whose d range holds the direct ramp's displacement D0 (the jump),
    also exactly at D0, where the tolerance decides between the direct ramp and a reversal."""
    rng = np.random.default_rng(7)
    v_max, a_max = 1.0, 2.0
    for scale in (1.0, 0.1, 1e-3, 1e-7):
        k = 400
        low = np.column_stack([rng.uniform(-3, 3, k), rng.uniform(-1.2, 1.2, k), rng.uniform(-1.2, 1.2, k)])
        width = rng.uniform(size=(k, 3)) ** 2 * scale * np.array([3.0, 1.0, 1.0])
        v0, vg = np.clip(low[:, 1], -v_max, v_max), np.clip(low[:, 2], -v_max, v_max)
        d0 = np.abs(vg - v0) * (vg + v0) / (2 * a_max)
        across = rng.uniform(size=k) < 0.5
        low[across, 0] = d0[across] - width[across, 0] * rng.uniform(size=across.sum())
        high = low + width
        pairs = [(low[:, j], high[:, j]) for j in range(3)]
        t_lo, t_hi = I.transfer_time_bounds(*pairs, v_max, a_max, tol)
        points = sample(low, high, rng)
        points[across, 0, 1:] = low[across, 1:]
        points[across, 0, 0] = np.clip(d0[across], low[across, 0], high[across, 0])  # D0 itself
        T = transfer_time(points[..., 0], points[..., 1], points[..., 2], v_max, a_max, tol)
        assert np.all(T >= t_lo[:, None]) and np.all(T <= t_hi[:, None])
        width = t_hi - t_lo
        assert np.any((T < (t_lo + SHRINK * width)[:, None]) | (T > (t_hi - SHRINK * width)[:, None]))
    point = low[~across]
    t_lo, t_hi = I.transfer_time_bounds(*[(point[:, j], point[:, j]) for j in range(3)], v_max, a_max, tol)
    T = transfer_time(point[:, 0], point[:, 1], point[:, 2], v_max, a_max, tol)
    assert np.mean(t_hi - t_lo <= 1e-6 * (1 + T)) >= 0.97


def test_the_angle_enclosures_hold():
    rng = np.random.default_rng(3)
    low = rng.uniform(-10, 10, size=(500, 2))
    high = low + rng.uniform(size=(500, 2)) ** 2 * rng.choice([0.01, 1.0, 8.0], size=(500, 1))
    points = sample(low, high, rng)
    (s_lo, s_hi), (c_lo, c_hi) = I.sin_cos(low[:, 0], high[:, 0])
    a = points[..., 0]
    assert np.all((np.sin(a) >= s_lo[:, None]) & (np.sin(a) <= s_hi[:, None]))
    assert np.all((np.cos(a) >= c_lo[:, None]) & (np.cos(a) <= c_hi[:, None]))
    turn = I.abs_wrapped(low[:, 0], high[:, 0])
    size = np.abs((a + np.pi) % (2 * np.pi) - np.pi)
    assert np.all((size >= turn[0][:, None]) & (size <= turn[1][:, None]))
    x, y = (low[:, 0] / 3, high[:, 0] / 3), (low[:, 1] / 3, high[:, 1] / 3)
    arc = I.direction(x, y)
    angle = np.arctan2(points[..., 1] / 3, points[..., 0] / 3)
    shifted = arc[0][:, None] + (angle - arc[0][:, None]) % (2 * np.pi)  # the angle's turn at or above arc's low
    assert np.all(shifted <= arc[1][:, None])


# --- the robots' spaces ----------------------------------------------------------------------------------------
ARM_RANGES = np.array([[*AW.THETA_A_LIMITS], [-1.2, 1.2], [*AW.THETA_B_LIMITS], [-1.2, 1.2]] * 2)
KITCHEN_SPOT = np.array([[-1.0, 11.0], [-1.0, 7.0], [-np.pi, np.pi], [-0.5, 0.5], [0.0, 0.8], [-np.pi, np.pi]])
KITCHEN_PASSING = np.vstack([KITCHEN_SPOT, [[0.0, KW.V_MAX]]])  # navigate's start and goal: a spot and a speed
KITCHEN_NAVIGATE = np.vstack([KITCHEN_PASSING, KITCHEN_PASSING, [KW.CRUISE]])  # ... and the goal's cruise speed


@pytest.mark.parametrize("seed", range(3))
def test_the_arm_ramps_bounds_are_sound_and_tight(seed):
    check_space(RAMPS, ARM_RANGES, seed)


def test_the_arm_ramps_bounds_with_the_angles_fixed_as_refinement_passes_them():
    """Refinement frees the way-points' joint velocities only: the angles are points of every box."""
    check_space(RAMPS, ARM_RANGES, 11, fixed=(0, 2, 4, 6))


@pytest.mark.parametrize("seed", range(3))
def test_the_kitchen_grasp_bounds_are_sound_and_tight(seed):
    check_space(GRASP, np.vstack([KITCHEN_SPOT, [[-1.0, 11.0], [-1.0, 7.0]]]), seed)


def test_the_kitchen_grasp_bounds_with_the_frame_and_the_point_fixed():
    check_space(GRASP, np.vstack([KITCHEN_SPOT, [[-1.0, 11.0], [-1.0, 7.0]]]), 12, fixed=(0, 1, 2, 6, 7))


@pytest.mark.parametrize("seed", range(3))
def test_the_kitchen_route_bounds_are_sound_and_tight(seed):
    check_space(ROUTE, KITCHEN_NAVIGATE, seed, n=80)


def test_the_kitchen_route_bounds_with_the_frames_fixed_as_refinement_passes_them():
    """Start and goal spots at the tables' frames, their offsets and speeds free (and a start pose fixed
    whole)."""
    check_space(ROUTE, KITCHEN_NAVIGATE, 13, fixed=(0, 1, 2, 7, 8, 9), n=80)
    check_space(ROUTE, KITCHEN_NAVIGATE, 14, fixed=(0, 1, 2, 3, 4, 5, 7, 8, 9), n=80)


# the field with its run-off, any heading, the speeds
SOCCER_POSE = np.array([[-4.5, 4.5], [-3.5, 3.5], [-np.pi, np.pi], [0.0, 1.0]] * 2)


@pytest.mark.parametrize("seed", range(2))
def test_the_soccer_walls_bounds_are_sound_and_tight(seed):
    """The success classifier's space: refinement drops boxes where it surely predicts failure."""
    check_space(POSE_WALLS, SOCCER_POSE, seed)
    check_space(POSE_WALLS, SOCCER_POSE, 30 + seed, fixed=(0, 1, 3, 4, 5, 7))


@pytest.mark.parametrize("space", [APPROACH, DRIBBLE, GOTO_SPACE], ids=lambda s: s.name)
@pytest.mark.parametrize("seed", range(2))
def test_the_soccer_path_bounds_are_sound_and_tight(space, seed):
    """Tight at every point where the planned word is decided without the words' path bounds (all of approach;
    for the words kept inside the walls, where the ends lie clear of them or the candidates surely stay inside):
    anywhere on the field most, not all, points."""
    check_space(space, SOCCER_POSE, seed, tight_share=1.0 if space is APPROACH else 0.65)


@pytest.mark.parametrize("space", [DRIBBLE, GOTO_SPACE], ids=lambda s: s.name)
def test_the_soccer_path_bounds_with_one_heading_free_as_in_score(space):
    """Refinement frees a heading and a speed at a subgoal: the rest of every box a point."""
    check_space(space, SOCCER_POSE, 21, fixed=(0, 1, 3, 4, 5, 6, 7), tight_share=0.6)
    check_space(space, SOCCER_POSE, 22, fixed=(0, 1, 2, 3, 4, 5, 7), tight_share=0.6)


def test_the_soccer_bounds_at_the_seams_of_wrapped_angles():
    """A goal dead ahead (the sign of angle_at decided at +1), arcs of numerically a full turn (0): tight there."""
    point = np.array([[0.0, 1.0, 0.0, 0.0, 3.0, 1.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.1, 3.0, 1.0, np.pi, 0.2]])
    for space in (GOTO_SPACE, DRIBBLE, APPROACH):
        f_lo, f_hi = space.bounds(point, point)
        np.testing.assert_allclose(f_lo, space(point), atol=1e-6)
        np.testing.assert_allclose(f_hi, space(point), atol=1e-6)


def test_the_soccer_word_extent_holds_every_path_of_its_boxes():
    """feature_bounds.word_extent, every (start box, word) pair at once: every pose along every word driven from
    a start pose of the box with segment lengths within their intervals lies inside it (the hard case of the
    walls decides on it), and 10% less would miss some."""
    rng = np.random.default_rng(5)
    radius, n = 0.4, 60
    low = np.column_stack([rng.uniform(-2, 2, n), rng.uniform(-2, 2, n), rng.uniform(-7, 7, n)])
    high = low + rng.uniform(size=(n, 3)) ** 2 * rng.choice([0.0, 0.05, 0.5], size=(n, 1))
    words = rng.integers(0, 6, n)
    seg_lo = rng.uniform(0, 1.5, (n, 3)) * rng.choice([0.0, 1.0], (n, 3), p=[0.2, 0.8])
    seg_hi = seg_lo + rng.uniform(0, 0.5, (n, 3)) * rng.choice([0.0, 1.0], (n, 1))
    (x_lo, x_hi), (y_lo, y_hi) = B.word_extent(tuple((low[:, j], high[:, j]) for j in range(3)), seg_lo, seg_hi,
                                               words, radius)
    caught = False
    for i in range(n):
        poses = []
        for start, lengths in zip(sample(low[i:i + 1], high[i:i + 1], rng, 12)[0],
                                  sample(seg_lo[i:i + 1], seg_hi[i:i + 1], rng, 12)[0]):
            path = dubins.DubinsPath(dubins.WORDS[words[i]], tuple(lengths), radius)
            poses += dubins.sample(tuple(start), path, 0.02)
        x, y = np.array(poses)[:, 0], np.array(poses)[:, 1]
        assert np.all((x >= x_lo[i]) & (x <= x_hi[i]) & (y >= y_lo[i]) & (y <= y_hi[i])), i
        shrink = [SHRINK * (x_hi[i] - x_lo[i]), SHRINK * (y_hi[i] - y_lo[i])]
        caught |= bool(np.any((x < x_lo[i] + shrink[0]) | (x > x_hi[i] - shrink[0])
                              | (y < y_lo[i] + shrink[1]) | (y > y_hi[i] - shrink[1])))
    assert caught, "a 10% shrink went unnoticed: the sampling has no teeth"
