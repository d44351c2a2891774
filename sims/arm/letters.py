"""The letters the arm draws (Sec. 5.5, Fig. 5.13) as Cartesian way-points, random strokes, and the writer of
their problem and belief files in domains/arm/problems/.

A letter's way-points lie in a LETTER_WIDTH x LETTER_HEIGHT box whose lower left corner is LETTER_ORIGIN
(in front of the shoulder, well inside the joint limits); the pen rests at the first and the last way-point.
Each problem is one chain p1 -> p2 -> ... (PDDL `next`), its belief file gives the way-points' joint angles
(inverse kinematics, world.ELBOW_SIGN) and, for the first way-point only, the joint velocities (at rest).
Regenerate the files with
`python -c "from tailor.sims.arm.letters import write_problem_files; write_problem_files()"`.
"""

from __future__ import annotations

import math
from itertools import pairwise
from pathlib import Path

import numpy as np

from tailor.sims.arm import world as W

LETTER_ORIGIN = (0.40, -0.15)  # m, lower left corner of a letter's box
LETTER_WIDTH = 0.20  # m
LETTER_HEIGHT = 0.30  # m
PROBLEMS_DIR = Path(__file__).resolve().parents[2] / "domains" / "arm" / "problems"

# problem name -> (object prefix, way-points in units of the box (0..1, 0..1), comment of the problem file)
LETTERS: dict[str, tuple[str, tuple[tuple[float, float], ...], str]] = {
    "letter-f": ("f", ((0, 0), (0, 0.5), (0, 1), (1, 1), (0, 1), (0, 0.5), (0.8, 0.5)),
                 ("Fig. 5.13(a): an 'F' in one stroke: up the stem (f1 -> f2 -> f3), along the top bar (f4), "
                  "back to the\nstem (f5) and along the middle bar (f6, f7); "
                  "the belief file places the way-points.")),
    "letter-s": ("s", ((1, 1), (0, 1), (0, 0.5), (1, 0.5), (1, 0), (0, 0)),
                 ("A second letter, 'S' (the initial of a co-author of Stulp et al. 2007, Sec. 5.5), "
                  "through six way-points.")),
    "letter-l": ("l", ((0, 1), (0, 0.5), (0, 0), (1, 0)),
                 "An 'L': down the stem (l1 -> l2 -> l3) and along the foot (l4)."),
    "letter-z": ("z", ((0, 1), (1, 1), (0.5, 0.5), (0, 0), (1, 0)),
                 ("A 'Z': along the top (z1 -> z2), down the diagonal through its middle (z3, z4), "
                  "along the foot (z5).")),
    "letter-n": ("n", ((0, 0), (0, 1), (1, 0), (1, 1)),
                 "An 'N': up the left stem (n1 -> n2), down the diagonal (n3), up the right stem (n4)."),
    "letter-m": ("m", ((0, 0), (0, 1), (0.5, 0.5), (1, 1), (1, 0)),
                 ("An 'M': up the left stem (m1 -> m2), down to the middle (m3), up (m4), "
                  "down the right stem (m5).")),
    "letter-w": ("w", ((0, 1), (0.25, 0), (0.5, 0.5), (0.75, 0), (1, 1)),
                 ("A 'W': four strokes from the top left (w1) through the bottoms (w2, w4) "
                  "and the middle (w3) to w5.")),
}

# random strokes (the evaluation's situations, Sec. 5.5): way-points inside this workspace
STROKE_X = (0.2, 0.8)  # m, range of a way-point's x
STROKE_Y = (-0.5, 0.5)  # m, range of a way-point's y
STROKE_RADIUS = (0.3, 0.8)  # m, range of a way-point's distance from the shoulder
STROKE_STEP = (0.1, 0.4)  # m, distance between consecutive way-points
STROKE_LIMIT_MARGIN = 0.2  # rad, way-points' joint angles keep this distance to the joint limits
STROKE_LENGTHS = (4, 5, 6)  # way-points per random stroke


def letter_points(name: str) -> list[tuple[float, float]]:
    """The Cartesian way-points (m) of a bundled letter."""
    _, unit, _ = LETTERS[name]
    x0, y0 = LETTER_ORIGIN
    return [(x0 + LETTER_WIDTH * u, y0 + LETTER_HEIGHT * v) for u, v in unit]


def _usable(p: tuple[float, float]) -> bool:
    x, y = p
    if not (STROKE_X[0] <= x <= STROKE_X[1] and STROKE_Y[0] <= y <= STROKE_Y[1]
            and STROKE_RADIUS[0] <= math.hypot(x, y) <= STROKE_RADIUS[1]):
        return False
    return W.within_limits(*W.inverse(x, y), margin=STROKE_LIMIT_MARGIN)


def random_stroke(rng: np.random.Generator, n: int) -> list[tuple[float, float]]:
    """n random Cartesian way-points (m) in the stroke workspace, consecutive ones STROKE_STEP apart."""
    while True:
        points = []
        while not points:
            p = (float(rng.uniform(*STROKE_X)), float(rng.uniform(*STROKE_Y)))
            if _usable(p):
                points.append(p)
        for _ in range(100 * n):
            if len(points) == n:
                return points
            angle, step = float(rng.uniform(-math.pi, math.pi)), float(rng.uniform(*STROKE_STEP))
            p = (points[-1][0] + step * math.cos(angle), points[-1][1] + step * math.sin(angle))
            if _usable(p):
                points.append(p)


def belief_objects(prefix: str, points: list[tuple[float, float]]) -> dict[str, dict[str, float]]:
    """Belief values of way-points prefix1..prefixN: joint angles, and for the first (at rest) velocities."""
    objects = {}
    for k, (x, y) in enumerate(points, start=1):
        theta_a, theta_b = W.inverse(x, y)
        objects[f"{prefix}{k}"] = ({"theta_a": theta_a, "omega_a": 0.0, "theta_b": theta_b, "omega_b": 0.0}
                                   if k == 1 else {"theta_a": theta_a, "theta_b": theta_b})
    return objects


def problem_text(name: str, prefix: str, n: int, comment: str) -> str:
    """The PDDL problem of a chain of n way-points: the pen rests at the last, which it must reach."""
    names = [f"{prefix}{k}" for k in range(1, n + 1)]
    lines = [f"; {line}" for line in comment.splitlines()]
    lines += [f"(define (problem {name})", "  (:domain arm)", f"  (:objects {' '.join(names)} - waypoint)",
              f"  (:init (at {names[0]})",
              "         " + " ".join(f"(next {p} {q})" for p, q in pairwise(names)),
              f"         (rest {names[-1]}))",
              "  (:goal (and " + " ".join(f"(reached {p})" for p in names[1:]),
              f"              (at {names[-1]}) (rest {names[-1]}))))"]
    return "\n".join(lines) + "\n"


def belief_text(comment: str, objects: dict[str, dict[str, float]]) -> str:
    """The belief file (TOML) of a problem: a comment, then one table per way-point, values to 4 decimals."""
    lines = [f"# {line}" for line in comment.splitlines()]
    for name, values in objects.items():
        lines.append(f"[objects.{name}]")
        lines += [f"{key} = {round(value, 4)!r}" for key, value in values.items()]
        lines.append("")
    return "\n".join(lines)


def _points_comment(prefix: str, points: list[tuple[float, float]]) -> str:
    cells = [f"{prefix}{k} ({x:.2f}, {y:.2f})" for k, (x, y) in enumerate(points, start=1)]
    return "\n".join("  " + ", ".join(cells[i:i + 4]) for i in range(0, len(cells), 4))


def problem_files() -> dict[str, str]:
    """Every bundled arm problem and belief file: file name -> text (letters and the stroke-N chains)."""
    files = {}
    for name, (prefix, _, comment) in LETTERS.items():
        points = letter_points(name)
        files[f"{name}.pddl"] = problem_text(name, prefix, len(points), comment)
        comment = (f"Belief state of problem `{name}`: the pen at rest at {prefix}1; joint angles by inverse "
                   "kinematics (elbow down)\nof the Cartesian way-points (m):\n"
                   + _points_comment(prefix, points))
        files[f"{name}.toml"] = belief_text(comment, belief_objects(prefix, points))
    for n in STROKE_LENGTHS:
        points = random_stroke(np.random.default_rng(n), n)
        name = f"stroke-{n}"
        comment = (f"A generic stroke of {n} way-points (the random situations of `tailor evaluate arm` "
                   f"are of this shape):\np1 -> ... -> p{n}, the pen resting at the end; "
                   "the belief file is one example.")
        files[f"{name}.pddl"] = problem_text(name, "p", n, comment)
        comment = (f"Belief state of problem `{name}`: a random stroke (letters.random_stroke, seed {n}), "
                   "the pen at rest at p1;\njoint angles by inverse kinematics (elbow down) of the Cartesian "
                   "way-points (m):\n" + _points_comment("p", points))
        files[f"{name}.toml"] = belief_text(comment, belief_objects("p", points))
    return files


def write_problem_files(folder: str | Path = PROBLEMS_DIR) -> list[Path]:
    """Write problem_files() into `folder`; returns the paths written."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, text in problem_files().items():
        path = folder / name
        path.write_text(text)
        paths.append(path)
    return paths
