"""Guaranteed enclosures of the soccer robot's feature spaces (FeatureSpace.bounds) for the certified optimizer:
the pose row, the Dubins words its controllers plan, and goToPose's lure, over boxes of parameters.

Interval arithmetic through the same formulas the features evaluate (sims.soccer.pose, sims.soccer.features:
Shkel & Lumelsky's normalized frame), in the same order, every operation bounded by sims.intervals and widened
for its rounding. Where a box meets a jump (an arc's length wrapping at a full turn, the shortest word
changing, a word coming into existence), the bound is the hull of what the box may hold: the shortest word's
length lies between the least lower length of the words that may exist and the least upper length of those that
surely do; its arcs and the shortest exact word's length are the hull over every word that may be the shortest.
At a single point every test is decided and the bounds are the features, but for one case: where the planned
word must be chosen among words leaving the walls' box (shortest_word_inside's "hard" case, a path near a wall),
the bounds are the hull over every word that may exist, sound but not tight (their path bounds are not enclosed).
"""

from __future__ import annotations

import numpy as np
from tailor.sims import intervals as I
from tailor.sims.dubins import WordBounds, _add, _rows, _scale, _slack, _stack, _sub, modulo
from tailor.sims.dubins_inside import extent_bounds
from tailor.sims.soccer.dubins import TANGENT_SLACK
from tailor.sims.soccer.pose import pose_parts
from tailor.sims.soccer.world import BALL_POINT_OFFSET

TWO_PI, PI = 2.0 * np.pi, np.pi
def norm_bounds(lo: np.ndarray, hi: np.ndarray) -> I.Pair:
    """pose.norm (wrap to [-pi, pi)) over [lo, hi]: shifted where clear of the seam, else [-pi, pi]."""
    a, b = modulo(lo + PI, hi + PI)
    return a - PI, b - PI


# --- the pose row -----------------------------------------------------------------------------------------------
def pose_bounds(columns: list[I.Pair]) -> dict[str, I.Pair]:
    """pose.pose_parts over boxes of (x, y, phi, v, xg, yg, phig, vg)."""
    x, y, phi, v, xg, yg, phig, vg = columns
    dx, dy = _sub(xg, x), _sub(yg, y)
    bearing = I.direction(dx, dy)
    signed = norm_bounds(*_slack(_sub(bearing, phi)))
    # where the start pose and the goal position are points, the side the goal lies on is the features' own
    # (a goal dead ahead is on the +1 side, which no enclosure of the angle could tell)
    point = np.all([a[0] == a[1] for a in (x, y, phi, xg, yg)], axis=0)
    if point.any():
        with np.errstate(invalid="ignore"):
            exact = np.mod(np.arctan2(yg[0] - y[0], xg[0] - x[0]) - phi[0] + PI, TWO_PI) - PI
        signed = (np.where(point, exact, signed[0]), np.where(point, exact, signed[1]))
    at = norm_bounds(*_slack(_sub(phig, bearing)))
    ahead, behind = signed[0] >= 0.0, signed[1] < 0.0  # sgn(angle_to_signed) is +1, or -1, over the whole box
    angle_at = (np.where(ahead, at[0], np.where(behind, -at[1], np.minimum(at[0], -at[1]))),
                np.where(ahead, at[1], np.where(behind, -at[0], np.maximum(at[1], -at[0]))))
    out = {"v": v, "vg": vg, "dist": I.hypot(dx, dy), "angle_to": I.abs_wrapped(*_sub(bearing, phi)),
           "angle_at": angle_at, "delta_angle": I.abs_wrapped(*_sub(phig, phi))}
    # a box that is a point: the features themselves (a wrapped angle at its seam is -pi, which no interval
    # around it could tell from pi)
    point = np.all([a[0] == a[1] for a in columns], axis=0)
    if point.any():
        parts = pose_parts(np.column_stack([a[0][point] for a in columns]))
        for name, (lo, hi) in out.items():
            lo, hi = np.array(lo, dtype=float), np.array(hi, dtype=float)
            lo[point], hi[point] = parts[name], parts[name]
            out[name] = (lo, hi)
    return out


def pose_row_bounds(columns: list[I.Pair], names: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    parts = pose_bounds(columns)
    return np.column_stack([parts[n][0] for n in names]), np.column_stack([parts[n][1] for n in names])


def _wall_bounds(x: I.Pair, y: I.Pair, phi: I.Pair, wall_x: float, wall_y: float) -> list[I.Pair]:
    """walls.wall_features over boxes: the clearances, and the heading's turn from each nearer wall's direction
    (the hull of both walls' where the box holds points on either side)."""
    ax, ay = I.absolute(*x), I.absolute(*y)

    def turn(side_lo: np.ndarray, side_hi: np.ndarray, positive: float, negative: float) -> I.Pair:
        ahead = I.abs_wrapped(phi[0] - positive, phi[1] - positive)  # the wall of coordinates >= 0
        behind = I.abs_wrapped(phi[0] - negative, phi[1] - negative)
        upper, lower = side_lo >= 0.0, side_hi < 0.0
        return (np.where(upper, ahead[0], np.where(lower, behind[0], np.minimum(ahead[0], behind[0]))),
                np.where(upper, ahead[1], np.where(lower, behind[1], np.maximum(ahead[1], behind[1]))))

    return [I.widen(wall_x - ax[1], wall_x - ax[0]), I.widen(wall_y - ay[1], wall_y - ay[0]),
            turn(*x, 0.0, PI), turn(*y, 0.5 * PI, -0.5 * PI)]


def pose_walls_bounds(low: np.ndarray, high: np.ndarray, wall_x: float, wall_y: float
                      ) -> tuple[np.ndarray, np.ndarray]:
    """A guaranteed enclosure of the "pose_walls" space (sims.soccer.walls) over boxes of parameters: the pose
    row, and the walls' clearances and turns at the start and at the goal."""
    low, high = np.atleast_2d(np.asarray(low, dtype=float)), np.atleast_2d(np.asarray(high, dtype=float))
    columns = [(low[:, k], high[:, k]) for k in range(low.shape[1])]
    pose = pose_bounds(columns)
    x, y, phi, _, xg, yg, phig, _ = columns
    pairs = ([pose[n] for n in ("v", "vg", "dist", "angle_to", "angle_at")]
             + _wall_bounds(x, y, phi, wall_x, wall_y) + _wall_bounds(xg, yg, phig, wall_x, wall_y))
    return np.column_stack([p[0] for p in pairs]), np.column_stack([p[1] for p in pairs])


# --- Dubins words ---------------------------------------------------------------------------------------------
Pose = tuple[I.Pair, I.Pair, I.Pair]  # x, y, heading (unwrapped) intervals


def _headings(columns: list[I.Pair]) -> tuple[I.Pair, I.Pair]:
    """(sin, cos) of the start and the goal heading, (2, k) each: one call."""
    phi, phig = columns[2], columns[6]
    return I.sin_cos(*_stack(*(np.broadcast_arrays(*h) for h in (phi, phig))))


def axle_pose_bounds(columns: list[I.Pair], final: float, headings: tuple[I.Pair, I.Pair] | None = None
                     ) -> tuple[Pose, Pose]:
    """features.axle_poses over boxes: the axle at the start, its pre-pose `final` behind the axle at the goal
    (`headings`: _headings(columns), where known)."""
    x, y, phi, _, xg, yg, phig, _ = columns
    s, c = _headings(columns) if headings is None else headings
    start = (_slack(_sub(x, _scale(_rows(c, 0), BALL_POINT_OFFSET))),
             _slack(_sub(y, _scale(_rows(s, 0), BALL_POINT_OFFSET))), phi)
    back = BALL_POINT_OFFSET + final
    return start, (_slack(_sub(xg, _scale(_rows(c, 1), back))), _slack(_sub(yg, _scale(_rows(s, 1), back))), phig)


class Words(WordBounds):
    """WordBounds of the soccer controllers' words (their tangent slack, sims.soccer.dubins.TANGENT_SLACK)."""

    def __init__(self, start: Pose, goal: Pose, radius: float):
        super().__init__(start, goal, radius, TANGENT_SLACK)


def shortest_bounds(words: Words, final: float, choices: np.ndarray | None = None
                    ) -> tuple[I.Pair, I.Pair, I.Pair]:
    """shortest_word's (path, arcs, exact_path) over the boxes: the shortest word among those that may exist, its
    arcs the hull over the words that may be the shortest, the shortest exact word's length likewise. With
    `choices` (k, 6) the words the planner may choose instead (the hard case of shortest_word_inside): the hull
    over them."""
    lo = words.lo
    upper = np.where(words.surely, words.hi, np.inf).min(axis=1)  # no longer than a word surely there ...
    # ... or than the longer of LSL and RSR where the ends lie apart: the larger of their circles' centres'
    # distances is then at least half the ends' (normalized) distance, and one of them is there
    apart = words.d[0] ** 2 / 4.0 > 1e-6
    upper = np.where(apart, np.minimum(upper, words.hi[:, :2].max(axis=1)), upper)
    may_be = words.maybe & (lo <= upper[:, None])
    path = (lo.min(axis=1), upper)
    arcs = (np.where(may_be, words.arcs_lo, np.inf).min(axis=1),
            np.where(may_be, words.arcs_hi, -np.inf).max(axis=1))
    exact_lo = np.where(words.exact_maybe & words.maybe, words.lo, np.inf).min(axis=1)
    exact_hi = np.where(words.exact_surely & words.surely, words.hi, np.inf).min(axis=1)
    if choices is not None:  # (rows without choices keep the shortest word's bounds)
        some = choices.any(axis=1)
        path = (np.minimum(path[0], np.where(choices, words.lo, np.inf).min(axis=1)),
                np.maximum(path[1], np.where(choices, words.hi, -np.inf).max(axis=1)))
        arcs = (np.minimum(arcs[0], np.where(choices, words.arcs_lo, np.inf).min(axis=1)),
                np.maximum(arcs[1], np.where(choices, words.arcs_hi, -np.inf).max(axis=1)))
        exact_lo = np.where(some, np.minimum(exact_lo, path[0]), exact_lo)
        exact_hi = np.where(some, np.maximum(exact_hi, path[1]), exact_hi)
    return (path[0] + final, path[1] + final), arcs, (exact_lo + final, exact_hi + final)


def _within(pose: Pose, box: tuple[float, float, float, float], margin: float) -> np.ndarray:
    """Whether the position surely lies within the box less `margin` on every side."""
    (x_lo, x_hi), (y_lo, y_hi) = pose[0], pose[1]
    return ((box[0] + margin <= x_lo) & (x_hi <= box[1] - margin)
            & (box[2] + margin <= y_lo) & (y_hi <= box[3] - margin))


def word_extent(start: Pose, seg_lo: np.ndarray, seg_hi: np.ndarray, words: np.ndarray, radius: float
                 ) -> tuple[I.Pair, I.Pair]:
    """Per (start box, word) pair, an outer box (x, y intervals) holding every point of the word's path from every
    start pose of the box (`start` intervals, (P,)), for every segment length its enclosure allows ((P, 3) lower
    and upper, m; `words` (P,) the words' indices in WORDS): the generic sims.dubins_inside.extent_bounds, its
    outer box alone, widened by 1e-9."""
    x, y, _ = extent_bounds(start, seg_lo, seg_hi, words, radius, slack=1e-9, inner=False)
    return x, y


def shortest_inside_bounds(start: Pose, goal: Pose, radius: float, final: float,
                           box: tuple[float, float, float, float]) -> tuple[I.Pair, I.Pair, I.Pair]:
    """shortest_word_inside over the boxes: as shortest_word where both ends surely lie 4 radii inside the box (2
    where no CCC word may exist), where every word stays inside; elsewhere the hull over every word that may
    exist (the planner may choose any by the words' bounds, which are not enclosed here)."""
    words = Words(start, goal, radius)
    far = _within(start, box, 4.0 * radius) & _within(goal, box, 4.0 * radius)
    near = _within(start, box, 2.0 * radius) & _within(goal, box, 2.0 * radius) & ~words.maybe[:, 4:].any(axis=1)
    simple = far | near
    # elsewhere, as the planner: where every word that may be the shortest, or the shortest exact one, surely
    # stays inside the box, they are the choice
    upper = np.where(words.surely, words.hi, np.inf).min(axis=1)
    exact_upper = np.where(words.surely & words.exact_surely, words.hi, np.inf).min(axis=1)
    candidate = words.maybe & ((words.lo <= upper[:, None])
                               | (words.exact_maybe & (words.lo <= exact_upper[:, None])))
    inside = np.ones(candidate.shape, dtype=bool)
    rows, which = np.nonzero(~simple[:, None] & candidate)
    if len(rows):
        sub = tuple((a[rows], b[rows]) for a, b in start)
        (x_lo, x_hi), (y_lo, y_hi) = word_extent(sub, words.seg_lo[rows, which], words.seg_hi[rows, which], which,
                                                  radius)
        inside[rows, which] = (box[0] <= x_lo) & (x_hi <= box[1]) & (box[2] <= y_lo) & (y_hi <= box[3])
    simple |= (inside | ~candidate).all(axis=1)
    return shortest_bounds(words, final, np.where(simple[:, None], False, words.maybe))


def detour_bounds(path: I.Pair, start: Pose, pre: Pose, final: float) -> I.Pair:
    """goto_path_features' detour: the word's length (its `final` straight left out) over the straight line."""
    straight = I.hypot(_sub(pre[0], start[0]), _sub(pre[1], start[1]))
    return _slack((path[0] - final - straight[1], path[1] - final - straight[0]), 1e-9)


# --- goToPose's lure ------------------------------------------------------------------------------------------
def lure_bounds(columns: list[I.Pair], box: tuple[float, float, float, float], lure_min: float, lure_gain: float,
                lure_max: float) -> tuple[I.Pair, I.Pair, I.Pair]:
    """features.lure_features over boxes: (length through the IP, turn toward it, turn at it)."""
    headings = _headings(columns)
    start, goal = axle_pose_bounds(columns, 0.0, headings)
    s, c = (_slack(_rows(q, 1)) for q in headings)
    along = _slack(_add(I.product(_sub(start[0], goal[0]), c), I.product(_sub(start[1], goal[1]), s)))
    behind = (np.maximum(0.0, -along[1]), np.maximum(0.0, -along[0]))
    d = _slack((np.minimum(lure_max, lure_min + lure_gain * behind[0]),
                np.minimum(lure_max, lure_min + lure_gain * behind[1])))
    ix = _slack(_sub(goal[0], I.product(d, c)))
    iy = _slack(_sub(goal[1], I.product(d, s)))
    ix = (np.clip(ix[0], box[0], box[1]), np.clip(ix[1], box[0], box[1]))
    iy = (np.clip(iy[0], box[2], box[3]), np.clip(iy[1], box[2], box[3]))
    to_ip = I.direction(_sub(ix, start[0]), _sub(iy, start[1]))
    length = _slack(_add(I.hypot(_sub(ix, start[0]), _sub(iy, start[1])),
                         I.hypot(_sub(goal[0], ix), _sub(goal[1], iy))))
    onto = I.direction(_sub(goal[0], ix), _sub(goal[1], iy))
    return length, I.abs_wrapped(*_sub(to_ip, start[2])), I.abs_wrapped(*_sub(onto, to_ip))
