"""The kitchen's random layouts (Fig. 5.11(a)), experience scenarios (Sec. 4.1) and situations (Sec. 5.5).

A layout displaces, uniformly along documented axes: table1 along room A's north wall (+-TABLE1_SHIFT),
table2 along room B's east wall (+-TABLE2_SHIFT), each cup along table1 (+-CUP_ALONG from its centre) and into
it (CUP_INSET), each put location likewise on table2, and the robot's start within START_REGION with any
heading. Two cups (or put locations) lie CUP_SEPARATION apart along their table.

Experience scenarios (the instant environment modification of Sec. 4.1):
- "navigate": the legs of both scenarios' plans in a random layout: from the start to a pickup spot, from a
  pickup spot through the door (east), from the door to a dropoff spot, from a dropoff spot through the door
  (west) and from the door to a pickup spot, every free offset uniform in its Fig. 5.12 range and the door's
  in DOOR_ALONG, DOOR_HEADING, the speed of passing it uniform in PASS_SPEED (a fifth of the passes: 0, a
  stop); a leg from the door starts there driving at that speed. The leg's cruise speed is uniform in
  world.CRUISE (a quarter of the legs: its top, V_MAX, the fastest), drawn after the rest. Its start is written
  as the plan writes it, the spot's frame and offsets (in_frame);
- "grip": the base at a random pickup spot, gripping the cup there;
- "put": the base at a random dropoff spot with a cup in the gripper, putting it at the put location.
Every episode writes the base's start (and logged) pose as a plan writes it: its spot's frame (the serving frame,
the door's, or the start pose itself) and the offsets from it (in_frame), so that what is learned from the
parameters sees the offsets.
Situations "scenario1" and "scenario2" give the belief values of the problems of the same names.
Every scenario's run and subgoal_episode take `variant` (None, or one of the kitchen's VARIANTS): the same
episode on the changed robot, for experience of it.
"""

from __future__ import annotations

import math
from dataclasses import replace
from itertools import pairwise
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from tailor.sims.episode import ActionCall, Episode
from tailor.sims.kitchen import world as W

if TYPE_CHECKING:
    from tailor.sims.kitchen.simulator import KitchenSim, Noise

SAMPLING_STREAM = 1  # second seed word: a scenario's draws are independent of the simulator's noise
STOP_SHARE = 0.2  # of the door spots in experience, the share passed at speed 0 (a stop)
TOP_CRUISE_SHARE = 0.25  # of the legs in experience, the share driven at the top cruise speed (V_MAX)
PROBLEMS_DIR = Path(__file__).resolve().parents[2] / "domains" / "kitchen" / "problems"


def _alongs(rng: np.random.Generator, n: int) -> list[float]:
    while True:
        values = sorted(float(v) for v in rng.uniform(-W.CUP_ALONG, W.CUP_ALONG, n))
        if all(b - a >= W.CUP_SEPARATION for a, b in pairwise(values)):
            return [float(v) for v in rng.permutation(values)]


def random_layout(rng: np.random.Generator, cups: int) -> dict:
    """Tables, cups, put locations and the robot's start of one random episode."""
    t1 = (W.TABLE1[0] + float(rng.uniform(-W.TABLE1_SHIFT, W.TABLE1_SHIFT)), W.TABLE1[1], W.TABLE1[2])
    t2 = (W.TABLE2[0], W.TABLE2[1] + float(rng.uniform(-W.TABLE2_SHIFT, W.TABLE2_SHIFT)), W.TABLE2[2])
    cup_points = [W.table_point(t1, a, float(rng.uniform(*W.CUP_INSET))) for a in _alongs(rng, cups)]
    put_points = [W.table_point(t2, a, float(rng.uniform(*W.CUP_INSET))) for a in _alongs(rng, cups)]
    (x0, x1), (y0, y1) = W.START_REGION
    start = (float(rng.uniform(x0, x1)), float(rng.uniform(y0, y1)), float(rng.uniform(-math.pi, math.pi)))
    return {"table1": t1, "table2": t2, "cups": cup_points, "puts": put_points, "start": start}


def belief_objects(layout: dict) -> dict[str, dict[str, float]]:
    """The belief values of a layout: start (a spot with zero offsets, at rest), tables, cups, pickup spots p<i>
    and dropoff spots d<i> (their frames, and the put location), and the door spots w<j> of the crossings
    (their frames: east from room A for odd j, west for even j)."""
    x, y, phi = layout["start"]
    objects: dict[str, dict[str, float]] = {
        "start": {"ox": x, "oy": y, "ophi": phi, "along": 0.0, "dist": 0.0, "heading": 0.0, "v": 0.0}}
    for name in ("table1", "table2"):
        objects[name] = dict(zip(("ox", "oy", "ophi"), layout[name]))  # centre, direction facing it
    for i, (cup, put) in enumerate(zip(layout["cups"], layout["puts"]), start=1):
        objects[f"cup{i}"] = {"x": cup[0], "y": cup[1]}
        objects[f"p{i}"] = dict(zip(("ox", "oy", "ophi"), W.serving_frame(layout["table1"], *cup)))
        objects[f"d{i}"] = {**dict(zip(("ox", "oy", "ophi"), W.serving_frame(layout["table2"], *put))),
                            "tx": put[0], "ty": put[1]}
    for j in range(1, 2 * len(layout["cups"])):
        objects[f"w{j}"] = dict(zip(("ox", "oy", "ophi"), W.door_frame(eastward=j % 2 == 1)))
    return objects


def _offsets(rng: np.random.Generator) -> tuple[float, float, float]:
    return (float(rng.uniform(*W.SPOT_ALONG)), float(rng.uniform(*W.SPOT_DIST)), float(rng.uniform(*W.SPOT_HEADING)))


def _door_spot(rng: np.random.Generator, eastward: bool) -> tuple[float, ...]:
    """A door spot (frame, offsets and passing speed) with its free values drawn (see the module doc)."""
    speed = 0.0 if rng.uniform() < STOP_SHARE else float(rng.uniform(*W.PASS_SPEED))
    return (*W.door_frame(eastward), float(rng.uniform(*W.DOOR_ALONG)), 0.0, float(rng.uniform(*W.DOOR_HEADING)),
            speed)


def _sim(seed: int, layout: dict, pose, holding: str | None = None, noise: Noise | None = None,
         variant: str | None = None, speed: float = 0.0) -> KitchenSim:
    from tailor.sims.kitchen.simulator import KitchenSim, Noise  # deferred: pymunk loads when an episode runs

    sim = KitchenSim(seed, Noise() if noise is None else noise, variant=variant)
    cups = {f"cup{i}": c for i, c in enumerate(layout["cups"], start=1)}
    sim.place(pose, {"table1": layout["table1"], "table2": layout["table2"]}, cups, holding, speed)
    return sim


def sample_goto(rng: np.random.Generator) -> tuple[dict, tuple[float, ...], tuple[float, ...]]:
    """A layout, a start spot (ox, oy, ophi, along, dist, heading, v) and the goal of one leg: a spot and the
    cruise speed."""
    layout = random_layout(rng, 1)
    pickup = (*W.serving_frame(layout["table1"], *layout["cups"][0]), *_offsets(rng), 0.0)
    dropoff = (*W.serving_frame(layout["table2"], *layout["puts"][0]), *_offsets(rng), 0.0)
    east, west = _door_spot(rng, True), _door_spot(rng, False)
    start = (*layout["start"], 0.0, 0.0, 0.0, 0.0)
    kind = int(rng.integers(5))  # start -> pickup, pickup -> door, door -> dropoff, dropoff -> door, door -> pickup
    legs = ((start, pickup), (pickup, east), (east, dropoff), (dropoff, west), (west, pickup))
    cruise = W.CRUISE[1] if rng.uniform() < TOP_CRUISE_SHARE else float(rng.uniform(*W.CRUISE))
    start, goal = legs[kind]
    return layout, start, (*goal, cruise)


def run_goto(seed: int, noise: Noise | None = None, *, variant: str | None = None) -> Episode:
    """One random navigate leg (see the module doc)."""
    layout, start, goal = sample_goto(np.random.default_rng((seed, SAMPLING_STREAM)))
    sim = _sim(seed, layout, W.spot_pose(*start[:6]), noise=noise, variant=variant, speed=start[6])
    return in_frame(sim.run(ActionCall("navigate", goal)), start[:3])


def run_grip(seed: int, noise: Noise | None = None, *, variant: str | None = None) -> Episode:
    """One random grip from a pickup spot (see the module doc)."""
    return _at_table(seed, noise, "grip", "table1", "cups", variant=variant)


def run_put(seed: int, noise: Noise | None = None, *, variant: str | None = None) -> Episode:
    """One random put from a dropoff spot, the cup in the gripper (see the module doc)."""
    return _at_table(seed, noise, "put", "table2", "puts", holding="cup1", variant=variant)


def _at_table(seed: int, noise: Noise | None, action: str, table: str, places: str,
              holding: str | None = None, variant: str | None = None) -> Episode:
    """`action` at the first of a random layout's `places` on `table`, from a random spot before it."""
    rng = np.random.default_rng((seed, SAMPLING_STREAM))
    layout = random_layout(rng, 1)
    place = layout[places][0]
    frame = W.serving_frame(layout[table], *place)
    pose = W.spot_pose(*frame, *_offsets(rng))
    sim = _sim(seed, layout, pose, holding=holding, noise=noise, variant=variant)
    return in_frame(sim.run(ActionCall(action, place)), frame)


def in_frame(episode: Episode, frame: tuple[float, float, float]) -> Episode:
    """The episode with its start and logged base poses written as spots of `frame` (the serving frame), as a
    plan writes an action's start: the simulator logs a pose as a spot with zero offsets, with which a
    model on the parameters alone would never see the offsets that refinement chooses. Same poses, same run."""
    state = episode.state.copy()
    state[:, :3] = frame
    state[:, 3:6] = np.column_stack(W.spot_offsets(frame, episode.state[:, :3].T))
    params = episode.params.copy()
    params[:6] = (*frame, *W.spot_offsets(frame, tuple(params[:3])))
    return replace(episode, params=params, state=state)


def subgoal_episode(action: str, params: np.ndarray, seed: int, variant: str | None = None) -> Episode:
    """An episode of `action` from a refined subgoal: params = start spot (6; navigate: and its speed), then the
    action's goal (navigate: a spot, its speed and the cruise speed). The layout around it is drawn from the seed
    (only the furniture near the path matters)."""
    p = [float(v) for v in params]
    rng = np.random.default_rng((seed, SAMPLING_STREAM))
    layout = random_layout(rng, 1)
    pose = W.spot_pose(*p[:6])
    if action == "navigate":
        sim = _sim(seed, layout, pose, variant=variant, speed=p[6])
        return in_frame(sim.run(ActionCall(action, tuple(p[7:15]))), (p[0], p[1], p[2]))
    point = (p[6], p[7])
    table = "table1" if action == "grip" else "table2"
    layout[table] = _table_under(point, layout[table])
    holding = None
    if action == "grip":
        layout["cups"] = [point]
    else:
        holding = "cup1"
    episode = _sim(seed, layout, pose, holding=holding, variant=variant).run(ActionCall(action, point))
    return in_frame(episode, (p[0], p[1], p[2]))


def _table_under(point, table):
    """The table moved along its wall so that it stands under `point` (as in the situation it came from)."""
    x, y, phi = table
    if abs(math.cos(phi)) < 0.5:  # table along a north/south wall: shift in x
        return (point[0], y, phi)
    return (x, point[1], phi)


def scenario1(rng: np.random.Generator) -> tuple[str, dict[str, dict[str, float]]]:
    """Scenario 1 (Fig. 5.11): one cup from table1 to table2, in a random layout."""
    return "scenario1", belief_objects(random_layout(rng, 1))


def scenario2(rng: np.random.Generator) -> tuple[str, dict[str, dict[str, float]]]:
    """Scenario 2: two cups from table1 to table2, one at a time, in a random layout."""
    return "scenario2", belief_objects(random_layout(rng, 2))


SITUATIONS = {"scenario1": scenario1, "scenario2": scenario2}


BELIEF_SEEDS = {"scenario1": 1, "scenario2": 2}  # the layouts of the bundled belief files


def belief_text(name: str) -> str:
    """The belief file (TOML) of a bundled problem: one random layout (seed BELIEF_SEEDS[name])."""
    seed = BELIEF_SEEDS[name]
    _, objects = SITUATIONS[name](np.random.default_rng(seed))
    lines = [f"# Belief state of problem `{name}`: one random layout of the kitchen (tailor.sims.kitchen.scenarios,",
             f"# situation generator {name!r}, seed {seed}); `tailor evaluate kitchen` draws many. Spots: ox, oy, ophi",
             "# (frame: the foot of the cup or put location on the table's serving edge, facing the table; the start:",
             "# the robot's pose) and, for the start, its zero offsets and speed; tables ox, oy, ophi (centre, facing",
             "# direction); cups x, y; put locations tx, ty; door spots w<j>: the door's frame, facing through it.",
             "# Regenerate: python -c \"from tailor.sims.kitchen.scenarios import write_belief_files; write_belief_files()\""]
    for obj, values in objects.items():
        lines.append(f"[objects.{obj}]")
        lines += [f"{key} = {_rounded(value, key in ('ophi', 'heading'))!r}" for key, value in values.items()]
        lines.append("")
    return "\n".join(lines)


def _rounded(value: float, angle: bool) -> float:
    """The value to 4 decimals; an angle toward zero where rounding would carry it out of [-pi, pi] (a door
    facing west, ophi = pi)."""
    rounded = round(value, 4)
    return math.trunc(value * 1e4) / 1e4 if angle and abs(rounded) > math.pi >= abs(value) else rounded


def write_belief_files(folder: str | Path = PROBLEMS_DIR) -> list[Path]:
    """Write the bundled problems' belief files into `folder`."""
    paths = []
    for name in BELIEF_SEEDS:
        path = Path(folder) / f"{name}.toml"
        path.write_text(belief_text(name))
        paths.append(path)
    return paths
