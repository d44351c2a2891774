"""The soccer robot's own feature spaces for approachBall and dribbleBall (Table 4.1 rows of their own): the
pose features and the path the action's controller plans.

approachBall follows a Dubins path of turning radius R_APPROACH from the wheel axle to a pre-pose behind the
ball (sims.soccer.approach). Its duration is nearly linear in that path's length and in how much of it is arc
(arcs are driven slower than straights), but a discontinuous function of dist, angle_to and angle_at: where
the shortest word changes (a loop instead of a turn and a straight), the time jumps by seconds. A model tree on
the pose features alone must cut such a boundary out of scattered examples; from the team's standing starts a
metre or two from the ball it erred by up to 3 s there (`tailor coordinate`, README). With the planned length
and arc length as features, the boundary is in the features; the shortest exact word's length beside it flags
where the shortest word only nearly exists (a turn and a straight whose circles overlap a little: the robot
cannot quite follow it and may end up driving the loop). Walls and the ball's clearance are left out, so that
these features stay invariant to moving the whole scene.

goToPose (sims.soccer.goto) switches between two ways of getting there: the Dubins path onto its pre-pose where
that path is at most MAX_DETOUR longer than the straight line, else the lure through an intermediate point (IP)
behind the goal. Which one it drives, and so its duration, jumps where the detour crosses MAX_DETOUR: in refined
`score` situations a start heading 0.07 rad away from greedy's took the robot from the path into the lure and
its approach from 2.75 s to 4.9 s, where the pose features predicted the same. Its space ("goto") has the word
its controller plans (inside the walls, as it plans it), that word's detour over the straight line, and the
lure's own length, first turn and turn at the IP.

dribbleBall follows the shortest Dubins path of radius R_DRIBBLE that keeps the ball clear of the walls
(sims.soccer.dribble): its space has the same columns for that word, the walls included. Refinement needs it:
on the pose features (5-fold cross-validated MAE 0.61 s on 6000 episodes) the optimizer chose approach headings
whose dribble the model predicted seconds too short; with the free shortest word (0.38 s) it chose headings
whose free word would leave the field, so the robot drove a longer one; with the word inside the walls 0.31 s.

Vectorized (numpy): the words are sims.dubins's (the generic Dubins maths, here with the controllers'
TANGENT_SLACK), in the normalized frame of Shkel & Lumelsky (2001) as in sims.soccer.dubins, whose scalar
candidates(), word_bounds() and shortest_path_inside() it reproduces (tests): coordination predicts millions of
approach times per run, and the genetic algorithm thousands of dribbles per window. Each space declares a
guaranteed enclosure over boxes of parameters for the certified optimizer (sims.soccer.feature_bounds).
"""

from __future__ import annotations

import numpy as np
from tailor.sims import dubins
from tailor.sims import intervals as I
from tailor.sims.dubins import ARC, SIGN
from tailor.sims.dubins import totals as _lengths
from tailor.sims.dubins_inside import extents
from tailor.sims.protocol import FeatureSpace
from tailor.sims.soccer import feature_bounds as B
from tailor.sims.soccer.approach import PRE_DISTANCE, R_APPROACH
from tailor.sims.soccer.dribble import DRIBBLE as DRIBBLE_FOLLOWER
from tailor.sims.soccer.dribble import FINAL_STRAIGHT, R_DRIBBLE
from tailor.sims.soccer.dubins import TANGENT_SLACK, WORDS
from tailor.sims.soccer.goto import GOTO, GOTO_STRAIGHT, LURE_GAIN, LURE_MAX, LURE_MIN
from tailor.sims.soccer.pose import POSE, POSE_PARAMETERS, pose_row, rigid_motion
from tailor.sims.soccer.walls import mirror_field
from tailor.sims.soccer.world import BALL_POINT_OFFSET

TWO_PI = 2.0 * np.pi
DRIBBLE_BOX = DRIBBLE_FOLLOWER.box  # where dribbleBall's axle path keeps the ball clear of the walls
# Table 4.1's pose row (as the space "pose" computes it, sims.soccer.pose), then the planned path's length and its arcs'
APPROACH_FEATURES = POSE + ("path", "arcs", "exact_path")
# goToPose's: its planned word (inside the walls), that word's detour over the straight line (the switch to the
# lure at MAX_DETOUR), the lure's length through the IP, the turn toward the IP and the turn at it
GOTO_FEATURES = APPROACH_FEATURES + ("detour", "lure_path", "lure_bearing", "lure_turn")


def dubins_words(start: np.ndarray, goal: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """(M, 6, 3) segment lengths (m) of each word of WORDS from the poses `start` (M, 3) to `goal` (M, 3), NaN
    where a word does not exist (mixed words within TANGENT_SLACK of touching exist, as in candidates()), and
    (M, 6) whether each is exact (not such a near-touching mixed word): sims.dubins.words, as the controllers
    take words."""
    return dubins.words(start, goal, radius, TANGENT_SLACK)


def shortest_word(start: np.ndarray, pre: np.ndarray, radius: float, final: float) -> np.ndarray:
    """(M, 3): length (m) of the shortest Dubins path of turning radius `radius` from the poses `start` to `pre`
    (M, 3), plus the final straight `final`; the length of its arcs; the length of the shortest exact one plus
    the final straight (longer where the shortest is a near-touching mixed word the robot cannot quite follow)."""
    words, exact = dubins_words(start, pre, radius)
    total = _lengths(words)
    best = np.argmin(total, axis=1)
    rows = np.arange(len(start))
    arcs = (words[rows, best] * ARC[best]).sum(axis=1)
    return np.column_stack([total[rows, best] + final, arcs, np.where(exact, total, np.inf).min(axis=1) + final])


def path_bounds(start: np.ndarray, lengths: np.ndarray, signs: np.ndarray, radius: float) -> np.ndarray:
    """(N, 4) the bounding box (xmin, xmax, ymin, ymax) of N paths driven from `start` (N, 3), segment lengths
    `lengths` (N, 3; NaN read as 0) and kinds `signs` (N, 3: 1 left arc, -1 right arc, 0 straight), as
    sims.soccer.dubins.word_bounds (tests): the generic sims.dubins_inside.extents. All paths at once, whatever
    their words: the genetic algorithm asks for a few hundred at a time, where numpy's per-call cost dominates."""
    return extents(start, lengths, signs, radius)


def word_bounds(start: np.ndarray, words: np.ndarray, radius: float) -> np.ndarray:
    """(M, 6, 4) path_bounds of each word of WORDS driven from `start` (M, 3) with the segment lengths `words`
    (M, 6, 3); NaN where a word does not exist."""
    m = len(start)
    out = path_bounds(np.repeat(start, len(WORDS), axis=0), words.reshape(-1, 3), np.tile(SIGN, (m, 1)),
                      radius).reshape(m, len(WORDS), 4)
    out[np.isnan(words).any(axis=2)] = np.nan
    return out


def _excess(bounds: np.ndarray, box: tuple[float, float, float, float]) -> np.ndarray:
    """How far paths with these bounds (..., 4) leave the box (<= 0: inside)."""
    return np.max(np.stack([box[0] - bounds[..., 0], bounds[..., 1] - box[1], box[2] - bounds[..., 2],
                            bounds[..., 3] - box[3]]), axis=0)


def shortest_word_inside(start: np.ndarray, pre: np.ndarray, radius: float, final: float,
                         box: tuple[float, float, float, float]) -> np.ndarray:
    """(M, 3) as shortest_word, of the word sims.soccer.dubins.shortest_path_inside plans: the shortest that
    stays inside box = (xmin, xmax, ymin, ymax), else the one that leaves it least; the third column the
    same choice among the exact words (the shortest word inside where no exact word exists). Bounds are
    computed only where needed: not where every word surely stays inside, and where the shortest word and the
    shortest exact one stay inside, not for the other words."""
    words, exact = dubins_words(start, pre, radius)
    total = _lengths(words)
    rows = np.arange(len(start))
    shortest = np.argmin(total, axis=1)
    shortest_exact = np.where(exact.any(axis=1), np.argmin(np.where(exact, total, np.inf), axis=1), shortest)
    def ends_within(m: float) -> np.ndarray:
        return np.all([(box[0] + m <= a) & (a <= box[1] - m) & (box[2] + m <= b) & (b <= box[3] - m)
                       for a, b in ((start[:, 0], start[:, 1]), (pre[:, 0], pre[:, 1]))], axis=0)

    # surely_inside: every word stays in the box (no word strays 4 radii from its ends); where no CCC word
    # exists, 2 radii (a CSC word lies on the circles through its ends and a tangent between them)
    simple = ends_within(4.0 * radius) | (ends_within(2.0 * radius) & np.isnan(words[:, 4:]).all(axis=(1, 2)))
    near = np.flatnonzero(~simple)
    if len(near):  # where both shortest words stay inside, they are the choice
        picks = np.concatenate([shortest[near], shortest_exact[near]])
        ends = np.concatenate([start[near], start[near]])
        both = _excess(path_bounds(ends, words[np.concatenate([near, near]), picks], SIGN[picks], radius), box)
        simple[near] = (both[:len(near)] <= 0.0) & (both[len(near):] <= 0.0)
    best, best_exact = shortest, shortest_exact  # where simple; elsewhere chosen by the words' bounds
    hard = ~simple
    if hard.any():
        excess = np.zeros(total.shape)  # (where simple the other words' bounds are not needed)
        excess[hard] = _excess(word_bounds(start[hard], words[hard], radius), box)
        excess = np.where(np.isfinite(total), excess, np.inf)

        def choose(usable: np.ndarray, simple_pick: np.ndarray) -> np.ndarray:
            length = np.where(usable, total, np.inf)
            inside = np.where(excess <= 0.0, length, np.inf)
            least = np.where(usable, excess, np.inf)  # the shortest of those leaving it least (ties within 1e-9)
            least = np.where(least <= least.min(axis=1, keepdims=True) + 1e-9, length, np.inf)
            pick = np.where(np.isfinite(inside.min(axis=1)), np.argmin(inside, axis=1), np.argmin(least, axis=1))
            return np.where(simple, simple_pick, pick)

        best = choose(np.isfinite(total), shortest)
        best_exact = np.where(exact.any(axis=1), choose(np.isfinite(total) & exact, shortest_exact), best)
    arcs = (np.nan_to_num(words[rows, best]) * ARC[best]).sum(axis=1)
    return np.column_stack([total[rows, best] + final, arcs, total[rows, best_exact] + final])


def axle_poses(params: np.ndarray, final: float) -> tuple[np.ndarray, np.ndarray]:
    """The axle's pose at the start and its pre-pose `final` behind the axle at the goal."""
    x, y, phi, _, xg, yg, phig, _ = params.T
    start = np.column_stack([x - BALL_POINT_OFFSET * np.cos(phi), y - BALL_POINT_OFFSET * np.sin(phi), phi])
    back = BALL_POINT_OFFSET + final
    return start, np.column_stack([xg - back * np.cos(phig), yg - back * np.sin(phig), phig])


def planned_path(params: np.ndarray) -> np.ndarray:
    """(M, 3) shortest_word of approachBall: R_APPROACH from the axle to its pre-pose PRE_DISTANCE behind."""
    return shortest_word(*axle_poses(params, PRE_DISTANCE), R_APPROACH, PRE_DISTANCE)


def dribble_path(params: np.ndarray) -> np.ndarray:
    """(M, 3) shortest_word_inside of dribbleBall: R_DRIBBLE from the axle to its pre-pose FINAL_STRAIGHT behind,
    the ball kept clear of the walls (the word its controller plans)."""
    return shortest_word_inside(*axle_poses(params, FINAL_STRAIGHT), R_DRIBBLE, FINAL_STRAIGHT, DRIBBLE_BOX)


def goto_path_features(params: np.ndarray) -> np.ndarray:
    """(M, 4) of goToPose: shortest_word_inside of the word it plans (R_APPROACH from the axle to its pre-pose
    GOTO_STRAIGHT behind, inside its box) and that word's detour over the straight line to the pre-pose, the
    quantity sims.soccer.goto compares with MAX_DETOUR."""
    start, pre = axle_poses(params, GOTO_STRAIGHT)
    word = shortest_word_inside(start, pre, R_APPROACH, GOTO_STRAIGHT, GOTO.box)
    straight = np.hypot(pre[:, 0] - start[:, 0], pre[:, 1] - start[:, 1])
    return np.column_stack([word, word[:, 0] - GOTO_STRAIGHT - straight])


def _wrapped(a: np.ndarray) -> np.ndarray:
    return np.mod(a + np.pi, TWO_PI) - np.pi


def lure_features(params: np.ndarray) -> np.ndarray:
    """(M, 3) of goToPose's lure (sims.soccer.goto.lure_point): the length from the axle through the IP to the
    axle's goal, the turn toward the IP from the start heading, and the turn at the IP onto the goal."""
    start, goal = axle_poses(params, 0.0)
    c, s = np.cos(goal[:, 2]), np.sin(goal[:, 2])
    along = (start[:, 0] - goal[:, 0]) * c + (start[:, 1] - goal[:, 1]) * s
    d = np.minimum(LURE_MAX, LURE_MIN + LURE_GAIN * np.maximum(0.0, -along))
    box = GOTO.box
    ix, iy = np.clip(goal[:, 0] - d * c, box[0], box[1]), np.clip(goal[:, 1] - d * s, box[2], box[3])
    to_ip = np.arctan2(iy - start[:, 1], ix - start[:, 0])
    length = np.hypot(ix - start[:, 0], iy - start[:, 1]) + np.hypot(goal[:, 0] - ix, goal[:, 1] - iy)
    return np.column_stack([length, np.abs(_wrapped(to_ip - start[:, 2])),
                            np.abs(_wrapped(np.arctan2(goal[:, 1] - iy, goal[:, 0] - ix) - to_ip))])


# the columns of POSE_PARAMETERS a planned path depends on: the poses, not the speeds
PATH_COLUMNS = [POSE_PARAMETERS.index(name) for name in ("x", "y", "phi", "xg", "yg", "phig")]


def _per_pose(path, params: np.ndarray) -> np.ndarray:
    """path(params), computed once per distinct pair of poses: the speeds do not change a planned path, and the
    genetic algorithm (a mutated speed) and the neighbourhood (a speed moved, the poses not) ask for the same
    path again within one batch. The same rows as path(params) (row-wise functions)."""
    poses = np.ascontiguousarray(params[:, PATH_COLUMNS], dtype=float)
    keys = poses.view(np.dtype((np.void, poses.itemsize * poses.shape[1]))).ravel()
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    if len(first) == len(params):
        return path(params)
    return path(params[first])[inverse.ravel()]


def _goto_paths(params: np.ndarray) -> np.ndarray:
    return np.column_stack([goto_path_features(params), lure_features(params)])


def _goto(params: np.ndarray) -> np.ndarray:
    return np.column_stack([pose_row(params), _per_pose(_goto_paths, params)])


def _approach(params: np.ndarray) -> np.ndarray:
    return np.column_stack([pose_row(params), _per_pose(planned_path, params)])


def _dribble(params: np.ndarray) -> np.ndarray:
    return np.column_stack([pose_row(params), _per_pose(dribble_path, params)])


def _bounds(path_bounds) -> callable:
    """A guaranteed enclosure of the pose row and the path features `path_bounds(columns)` gives (a list of (low,
    high) pairs; sims.soccer.feature_bounds) over boxes of parameters; the paths bounded once per distinct box of
    poses (the speeds do not change them: a neighbourhood's offsets along a speed ask for the same again)."""
    def bounds(low: np.ndarray, high: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        low, high = np.atleast_2d(np.asarray(low, dtype=float)), np.atleast_2d(np.asarray(high, dtype=float))
        columns = [(low[:, k], high[:, k]) for k in range(low.shape[1])]
        pose = B.pose_bounds(columns)
        first, inverse = I.distinct_rows(np.column_stack([low[:, PATH_COLUMNS], high[:, PATH_COLUMNS]]))
        paths = path_bounds([(a[first], b[first]) for a, b in columns])
        pairs = [pose[n] for n in POSE] + [(a[inverse], b[inverse]) for a, b in paths]
        return np.column_stack([p[0] for p in pairs]), np.column_stack([p[1] for p in pairs])

    return bounds


def _approach_paths(columns: list) -> list:
    """planned_path's (path, arcs, exact_path) enclosed."""
    return list(B.shortest_bounds(B.Words(*B.axle_pose_bounds(columns, PRE_DISTANCE), R_APPROACH), PRE_DISTANCE))


def _dribble_paths(columns: list) -> list:
    """dribble_path's enclosed."""
    start, pre = B.axle_pose_bounds(columns, FINAL_STRAIGHT)
    return list(B.shortest_inside_bounds(start, pre, R_DRIBBLE, FINAL_STRAIGHT, DRIBBLE_BOX))


def _goto_paths_bounds(columns: list) -> list:
    """_goto_paths enclosed: the word inside the walls, its detour over the straight line, the lure."""
    start, pre = B.axle_pose_bounds(columns, GOTO_STRAIGHT)
    path, arcs, exact = B.shortest_inside_bounds(start, pre, R_APPROACH, GOTO_STRAIGHT, GOTO.box)
    return [path, arcs, exact, B.detour_bounds(path, start, pre, GOTO_STRAIGHT),
            *B.lure_bounds(columns, GOTO.box, LURE_MIN, LURE_GAIN, LURE_MAX)]


APPROACH = FeatureSpace("approach", POSE_PARAMETERS, APPROACH_FEATURES, _approach,
                        "translation, rotation and mirroring of the scene", rigid_motion, _bounds(_approach_paths))
# dribbleBall's: the same with the path it plans with the ball (tighter radius, its own final straight, kept
# clear of the walls, so not invariant to moving the scene). Not piecewise affine in a heading: refinement over
# a subgoal dribbled from falls back to the genetic algorithm
# goToPose's: the word and the lure it plans inside the walls, so, as dribbleBall's, invariant only to mirroring
GOTO_SPACE = FeatureSpace("goto", POSE_PARAMETERS, GOTO_FEATURES, _goto, "mirroring the field", mirror_field,
                          _bounds(_goto_paths_bounds))
DRIBBLE = FeatureSpace("dribble", POSE_PARAMETERS, APPROACH_FEATURES, _dribble, "mirroring the field",
                       mirror_field, _bounds(_dribble_paths))
