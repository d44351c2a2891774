"""KitchenSim: the B21-like robot, tables and cups in a pymunk space stepped at a fixed rate (headless).

The base is a kinematic body: each physics step its [v, phidot] moves toward the (noisy) command by at most
A_MAX / ALPHA_MAX per second within V_MAX / W_MAX (unicycle model). Walls, the island and the tables are static
boxes; cups are small dynamic bodies standing on the tables (they do not collide with the table tops) that a
closed gripper carries. The arm's two joints (pan, extension) are integrated at the control rate.

Actions (Table 2.1): `navigate` (goal: a spot, ox, oy, ophi, along, dist, heading, the speed v to pass it at
(world.spot_pose), and the cruise speed: the drive's governor holds the base at most at it, world.CRUISE) plans
the shortest route round the furniture (navigation.RouteMap on the scene's furniture), follows it by pure pursuit (turning in place where the route bends sharply, slowing as it goes
whatever speed it starts with), and either (v = 0) brakes to stop at the goal position and turns in place to
the goal heading, or (v > 0, a way-point: Sec. 5.5, Fig. 5.9) routes to a point LEAD_IN behind the goal on the
goal heading's line, drives down that line braking to v and ends where it crosses the goal (the next action
starts at that speed: it overshoots where it has to turn sharply). `grip` (goal: the cup's x, y) and `put`
(goal: the put location's x, y) pan and extend the arm to the point (for grip, the cup the arm's camera finds
within CUP_SEARCH of it, seen relative to the base with the position noise; for put, the point relative to the
believed base pose) (each joint a velocity ramp within its speed and acceleration limits), close (grip) or open
(put) the gripper in GRIPPER_TIME, and tuck the arm back (pan 0, extension EXT_REST).

Outcomes (Episode.outcome), judged on the true state:
- "success": navigate within POS_TOL, HEADING_TOL of the goal pose at rest (v = 0), or crossing the goal within
  PASS_TOL, PASS_HEADING_TOL of it (v > 0); grip/put with the arm tucked;
- "off_course": navigate crossed its way-point (v > 0) farther than PASS_TOL or PASS_HEADING_TOL from it;
- "collision": the base touches a wall, the island or a table;
- "out_of_reach": the arm cannot reach the point (bearing beyond PAN_LIMIT, extension beyond EXT_MAX) or
  the base is not 40-80 cm (SPOT_DIST, +-REACH_TOLERANCE) from the serving edge of the table at the point;
- "missed": the gripper closed more than GRIP_TOLERANCE from any cup; "not_holding": put without a cup;
- "cup_dropped": put released the cup off every table;
- "timeout": TIMEOUT simulated seconds passed.
Timing: physics at PHYSICS_HZ, control at CONTROL_HZ, believed state logged at LOG_HZ.

Measures (Episode.measures, sims.episode), on the true state, none of them changing the simulation:
- "energy" (J): the work of the motors, braking as much as speeding up (nothing is recovered), of
  - the base, BASE_MASS m and BASE_MOMENT I about its centre: each physics step changes v from v0 to v1 (and
    phidot from w0 to w1) at constant acceleration, which takes the integral of |F v| = m/2 |v1^2 - v0^2|
    (m/2 (v0^2 + v1^2) where v reverses within the step), and likewise I/2 for phidot (no friction: driving at
    constant speed costs nothing, so following the noisy command costs, and driving governed below it does not);
  - the arm, a point mass m = GRIPPER_MASS (plus CUP_MASS while it holds a cup) at the gripper, r = ext
    from the shoulder, pan psi: each control period the joint rates jump from (psi'0, r'0) to (psi'1, r'1)
    (taken as a ramp at constant r: m r^2/2 |psi'1^2 - psi'0^2| for the pan, m/2 |r'1^2 - r'0^2| for the
    extension, the sum of squares where a rate reverses), then hold while r goes from r0 to r1: the pan's
    Coriolis torque 2 m r r' psi' does m psi'^2 |r1^2 - r0^2|, the extension's centripetal force m r psi'^2
    half that; the arm stops (its rates jump to 0) when it arrives or the action ends;
- "error" (m): navigate, the base centre's distance to the goal spot's position (world.spot_pose); grip and
  put, the gripper's distance to the commanded point (cx, cy) / (tx, ty) where the gripper closed / opened
  (where it stands at the action's end if it never did: out of reach, not holding, a timeout);
- "heading_error" (rad, [0, pi]): navigate, |heading - the goal spot's heading| wrapped, at the action's end.

Closed loop (Ch. 8.1): `observe(action)` and `scene()` measure the world between actions without advancing it;
a disturbance ("cup") and a variant ("slow_floor") change the world and the robot (sims.kitchen.disturbances).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from itertools import pairwise

import numpy as np
import pymunk

from tailor.errors import SimError
from tailor.sims.episode import (ENERGY, ERROR, HEADING_ERROR, ActionCall, Episode, SequenceResult,
                                 run_in_sequence)
from tailor.sims.kitchen import world as W
from tailor.sims.kitchen.disturbances import (DISTURBANCE_STREAM, DISTURBANCES, NOMINAL_LIMITS,
                                              SENSING_STREAM, SLOW_LIMITS, VARIANTS, CupDisplacement,
                                              cup_moment, displace, on_slow_floor, standing_cups)
from tailor.sims.kitchen.navigation import RouteMap, leg_distance
from tailor.sims.noise import NormalRows

PHYSICS_HZ = 100  # Hz
CONTROL_HZ = 20  # Hz (divides PHYSICS_HZ)
LOG_HZ = 10  # Hz (divides CONTROL_HZ)
DT = 1.0 / PHYSICS_HZ
DT_CONTROL = 1.0 / CONTROL_HZ
STEPS_PER_CONTROL = PHYSICS_HZ // CONTROL_HZ
CONTROLS_PER_LOG = CONTROL_HZ // LOG_HZ

POS_TOL = 0.08  # m, navigate: base centre to the goal position (success, true state)
ARRIVE_TOL = 0.05  # m, navigate stops driving when the believed position is this close
HEADING_TOL = 0.05  # rad
SPEED_TOL = 0.05  # m/s
TURN_RATE_TOL = 0.1  # rad/s
LOOKAHEAD = 0.5  # m, pure-pursuit carrot distance along the route
TURN_IN_PLACE = 0.8  # rad, heading error beyond which the base stops to turn
K_TURN = 2.5  # 1/s, commanded turn rate per rad of heading error
V_CREEP = 0.05  # m/s, slowest approach speed
BRAKE = 0.8  # fraction of A_MAX (ALPHA_MAX) planned for braking
PAN_TOL = 0.01  # rad, a joint has arrived within these tolerances ...
EXT_TOL = 0.005  # m
GRIP_TOLERANCE = 0.06  # m, gripper to cup centre for a successful grip (the open gripper's catch)
CUP_SEARCH = 0.1  # m, grip finds a cup this close to its goal point with the arm's camera
REACH_TOLERANCE = 0.05  # m, slack of the 40-80 cm precondition
TIMEOUT = 60.0  # s
LEAD_IN = 0.6  # m, navigate to a way-point (v > 0) comes down the goal heading's line from this far behind it
PASS_TOL = 0.15  # m, ... and succeeds crossing it this close
PASS_HEADING_TOL = 0.3  # rad

# what the motors move, for the energy measure only (the physics never reads them: the base is kinematic, the
# arm's joints are integrated directly)
BASE_MASS = 120.0  # kg, the B21-like robot with its arm and batteries
BASE_MOMENT = 0.5 * BASE_MASS * W.BASE_RADIUS ** 2  # kg m^2, a uniform disc of BASE_RADIUS (4.06)
GRIPPER_MASS = 1.0  # kg, the gripper with the extension's moving tube, a point mass at the arm's end

ACTIONS = ("navigate", "grip", "put")
GOAL_SIZES = {"navigate": 8, "grip": 2, "put": 2}
STATE_COLUMNS = ("ox", "oy", "ophi", "along", "dist", "heading", "v", "pan", "ext")  # believed; pose as a spot
TRAJECTORY_COLUMNS = ("t", "x", "y", "phi", "v", "pan", "ext", "gripper_x", "gripper_y")  # true state

FURNITURE, CUPS, BASE, QUERY = 0b0001, 0b0010, 0b0100, 0b1000  # collision categories
_FURNITURE_QUERY = pymunk.ShapeFilter(categories=QUERY, mask=FURNITURE)  # furniture meets only queries
_set_velocity = pymunk.Body.velocity.fset
_set_angular_velocity = pymunk.Body.angular_velocity.fset
_set_position = pymunk.Body.position.fset
_A_STEP = W.A_MAX * DT
_ALPHA_STEP = W.ALPHA_MAX * DT
# (a_step, alpha_step) of variant "slow_floor", off and on the carpet
_SLOW_STEPS = {False: (_A_STEP, _ALPHA_STEP), True: (SLOW_LIMITS[2] * DT, SLOW_LIMITS[3] * DT)}


@dataclass(frozen=True)
class Noise:
    """Seeded noise: relative on the executed motor commands (base and arm joints), and on the believed
    base pose and object positions."""

    motor: float = 0.03
    position: float = 0.01  # m
    heading: float = math.radians(1.0)  # rad

    @classmethod
    def off(cls) -> Noise:
        return cls(0.0, 0.0, 0.0)


def _ramp(q: float, qd: float, goal: float, v_max: float, a_max: float) -> float:
    """The joint velocity for the next control period: toward the goal along a velocity ramp, never past it."""
    e = goal - q
    step = a_max * DT_CONTROL
    # the fastest speed from which braking by `step` each period stops within |e| (discrete sqrt(2 a e))
    brake = step * (math.sqrt(0.25 + 2.0 * abs(e) / (step * DT_CONTROL)) - 0.5)
    want = math.copysign(min(v_max, brake, abs(e) / DT_CONTROL), e)
    return qd + max(-step, min(step, want - qd))


class KitchenSim:
    """The kitchen with the robot; `run` executes one action as an Episode, `run_sequence` several.

    `disturbance` ("cup") and `variant` ("slow_floor") name one of sims.kitchen.disturbances' DISTURBANCES and
    VARIANTS, None for none; what a disturbance did is appended to `events` (CupDisplacement)."""

    state_columns = STATE_COLUMNS

    def __init__(self, seed: int, noise: Noise = Noise(), disturbance: str | None = None,
                 variant: str | None = None):
        for kind, name, known in (("disturbance", disturbance, DISTURBANCES), ("variant", variant, VARIANTS)):
            if name is not None and name not in known:
                raise SimError(f"the kitchen has no {kind} {name!r} (known: {', '.join(known)})")
        self.noise = noise
        self.seed = int(seed)
        self.rng = np.random.default_rng(seed)
        self._noise = NormalRows(self.rng, 8)
        self._sensing = np.random.default_rng((self.seed, SENSING_STREAM))  # scene()'s cup measurements
        self.disturbance, self.variant = disturbance, variant
        self._disturbances = np.random.default_rng((self.seed, DISTURBANCE_STREAM))
        self._cup_pending = disturbance == "cup"
        self.events: list[CupDisplacement] = []
        self._slow_floor = variant == "slow_floor"
        self.space = pymunk.Space()
        self.space.damping = 0.05  # cups pushed over the floor or table come to rest
        self.fixed = [*W.walls(), W.island()]
        for box in self.fixed:
            self._add_box(box)
        self.base = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        shape = pymunk.Circle(self.base, W.BASE_RADIUS)
        shape.filter = pymunk.ShapeFilter(categories=BASE, mask=CUPS)
        self.space.add(self.base, shape)
        self.tables: dict[str, W.Box] = {}
        self._table_shapes: list[pymunk.Shape] = []
        self.cups: dict[str, pymunk.Body] = {}
        self.held: str | None = None
        self.routes = RouteMap([*self.fixed])
        self.time = 0.0
        self._xy = (0.0, 0.0)  # true base position (mirrored into the body)
        self.v = self.w = self.phi = 0.0
        self.v_cmd = self.w_cmd = 0.0
        self.pan, self.ext = 0.0, W.EXT_REST
        self._next_sample = 0.0
        # the energy measure (module doc) of the running action: the base's sums over physics steps of
        # |v1^2 - v0^2| (v0^2 + v1^2 where v reverses) and the same of phidot, and the arm's work in J
        self._speed_work = self._turn_work = self._arm_work = 0.0
        self._released_at: tuple[float, float] | None = None  # where grip / put closed / opened the gripper

    def _add_box(self, box: W.Box) -> pymunk.Shape:
        shape = pymunk.Poly(self.space.static_body, box.corners())
        shape.filter = pymunk.ShapeFilter(categories=FURNITURE, mask=QUERY)
        self.space.add(shape)
        return shape

    # --- state ------------------------------------------------------------------------------------------
    def reset(self, scene: Mapping[str, Sequence[float]]) -> None:
        """The protocol's reset: {"robot": (ox, oy, ophi, along, dist, heading) (a spot, and optionally its speed v
        straight ahead), "table NAME": (x, y, phi), "cup NAME": (x, y)}, and optionally "held NAME": () (no values:
        cup NAME in the gripper, as scene() reports it); the robot at rest unless v is given, the arm tucked, the
        gripper empty unless a cup is held."""
        if not isinstance(scene, Mapping) or "robot" not in scene:
            raise SimError("the kitchen scene needs a robot (ox, oy, ophi, along, dist, heading)")
        robot, tables, cups, held = (), {}, {}, None
        for key, values in scene.items():
            values = tuple(float(v) for v in values)
            kind, _, name = key.partition(" ")
            if key == "robot":
                if len(values) not in (6, 7):
                    raise SimError("the kitchen scene's robot is a spot (ox, oy, ophi, along, dist, heading) and "
                                   f"optionally its speed v (m/s, straight ahead), got {values}")
                robot = values
            elif kind == "table" and name and len(values) == 3:
                tables[name] = values
            elif kind == "cup" and name and len(values) == 2:
                cups[name] = values
            elif kind == "held" and name and not values and held is None:
                held = name
            else:
                raise SimError(f"unknown kitchen scene object {key!r} with {len(values)} values (expected robot, "
                               "'table NAME' (x, y, phi), 'cup NAME' (x, y), one 'held NAME' ())")
        self.place(W.spot_pose(*robot[:6]), tables, cups, held, robot[6] if len(robot) == 7 else 0.0)

    def place(self, pose: tuple[float, float, float], tables: Mapping[str, Sequence[float]],
              cups: Mapping[str, Sequence[float]], holding: str | None = None, speed: float = 0.0) -> None:
        """Base at pose (x, y, phi), driving straight ahead at `speed` (m/s, 0: at rest), tables (x, y, phi),
        cups (x, y) at rest; `holding` a cup's name puts that cup in the (tucked) gripper."""
        x, y, phi = (float(q) for q in pose)
        values = [x, y, phi, float(speed), *(float(v) for t in tables.values() for v in t),
                  *(float(v) for c in cups.values() for v in c)]
        if not all(math.isfinite(v) for v in values):
            raise SimError(f"kitchen scene values must be finite, got {values}")
        if holding is not None and holding not in cups:
            raise SimError(f"holding unknown cup {holding!r}")
        for shape in self._table_shapes:
            self.space.remove(shape)
        self.tables = {name: W.table_box(*t) for name, t in tables.items()}
        self._table_shapes = [self._add_box(box) for box in self.tables.values()]
        for body in self.cups.values():
            self.space.remove(body, *body.shapes)
        self.cups = {}
        for name, (cx, cy) in cups.items():
            body = pymunk.Body(W.CUP_MASS, pymunk.moment_for_circle(W.CUP_MASS, 0, W.CUP_RADIUS))
            body.position = (float(cx), float(cy))
            shape = pymunk.Circle(body, W.CUP_RADIUS)
            shape.filter = pymunk.ShapeFilter(categories=CUPS, mask=CUPS | BASE)
            self.space.add(body, shape)
            self.cups[name] = body
        self.routes = RouteMap([*self.fixed, *self.tables.values()])
        self.base.position, self.base.angle = (x, y), phi
        self._xy = (x, y)
        self.base.velocity, self.base.angular_velocity = (0.0, 0.0), 0.0
        self.space.reindex_shapes_for_body(self.base)
        speed = max(-W.V_MAX, min(W.V_MAX, float(speed)))
        self.phi, self.v, self.w, self.v_cmd, self.w_cmd = phi, speed, 0.0, speed, 0.0
        self.pan, self.ext, self.held = 0.0, W.EXT_REST, holding
        self._carry()
        self.time = 0.0

    def gripper(self) -> tuple[float, float]:
        """The gripper's true position."""
        x, y = self._xy
        sx, sy = x + W.SHOULDER_OFFSET * math.cos(self.phi), y + W.SHOULDER_OFFSET * math.sin(self.phi)
        a = self.phi + self.pan
        return sx + self.ext * math.cos(a), sy + self.ext * math.sin(a)

    def true_state(self) -> tuple[float, ...]:
        """(x, y, phi, v, pan, ext, gripper_x, gripper_y)."""
        x, y = self._xy
        return (x, y, W.wrap(self.phi), self.v, self.pan, self.ext, *self.gripper())

    def observe(self, action: str) -> tuple[float, ...]:
        """The observed parameters of `action` (the base pose as a spot with zero offsets: ox, oy, ophi,
        along, dist, heading; for navigate also the speed v) measured now: exactly what `run` of it logs first
        in Episode.params. It draws the noise row that run will measure its start with and keeps it for run
        (consuming nothing: a closed loop that observes stays on the open loop's noise stream); the simulation
        does not advance."""
        if action not in ACTIONS:
            raise SimError(f"unknown kitchen action {action!r}; known: {', '.join(ACTIONS)}")
        spot = (*self._believe(self.true_state(), self._noise.peek()), 0.0, 0.0, 0.0)
        return (*spot, self.v) if action == "navigate" else spot

    def scene(self) -> dict[str, tuple[float, ...]]:
        """Every scene object measured now, in reset's form: the robot as observe("navigate") measures it (a spot
        and its speed straight ahead), each table as placed (x, y, phi: the map, known exactly), each cup (x, y)
        with the position noise, and "held NAME": () for a cup in the gripper (the cup at the gripper). The cups'
        noise comes from the generator (seed, SENSING_STREAM), two draws per cup and call, never from the motor and
        sensor noise; the simulation does not advance. Not in the scene: the arm's pose (reset tucks it) and the
        base's turn rate (reset places it turning at none)."""
        out: dict[str, tuple[float, ...]] = {"robot": self.observe("navigate")}
        out.update({f"table {name}": (box.cx, box.cy, box.angle) for name, box in self.tables.items()})
        for name, body in self.cups.items():
            e = self._sensing.standard_normal(2)
            x, y = body.position
            sigma = self.noise.position
            out[f"cup {name}"] = (x + sigma * float(e[0]), y + sigma * float(e[1]))
        if self.held is not None:
            out[f"held {self.held}"] = ()
        return out

    def _believe(self, true: Sequence[float], e: Sequence[float]) -> tuple[float, float, float]:
        n = self.noise
        return true[0] + n.position * e[0], true[1] + n.position * e[1], W.wrap(true[2] + n.heading * e[2])

    def collides(self) -> bool:
        """The base overlaps a wall, the island or a table."""
        return self.space.point_query_nearest(self._xy, W.BASE_RADIUS - 1e-6, _FURNITURE_QUERY) is not None

    # --- dynamics ---------------------------------------------------------------------------------------
    def limits(self) -> tuple[float, float, float, float]:
        """The base's limits where it stands now (v, phidot, their accelerations): world's V_MAX, W_MAX,
        A_MAX, ALPHA_MAX, or SLOW_FACTOR of them on the carpet of variant "slow_floor"."""
        return SLOW_LIMITS if self._slow_floor and on_slow_floor(*self._xy) else NOMINAL_LIMITS

    def command(self, v_cmd: float, w_cmd: float, e: Sequence[float] = (0.0, 0.0),
                cruise: float = math.inf) -> None:
        """The motors' command: the controller's (v, phidot) with their relative noise, within the limits; the
        governor holds |v| at most at the running navigate's `cruise` speed after the noise (world.CRUISE)."""
        m = self.noise.motor
        v_max, w_max = self.limits()[:2]
        v_max = min(v_max, cruise)
        self.v_cmd = max(-v_max, min(v_max, v_cmd * (1.0 + m * e[0])))
        self.w_cmd = max(-w_max, min(w_max, w_cmd * (1.0 + m * e[1])))

    def _advance(self) -> None:
        """One control period of physics steps: the base accelerates toward its command within the limits.

        The base's unicycle motion is integrated here at PHYSICS_HZ; pymunk is stepped with it only while the
        base is near a free cup or a cup is sliding (contacts are possible); otherwise it only receives the base
        pose at the end of the period (stepping it would move nothing else)."""
        base = self.base
        v, w, phi = self.v, self.w, self.phi
        x, y = self._xy
        if not (v != 0.0 or w != 0.0 or self.v_cmd != 0.0 or self.w_cmd != 0.0):
            if self._contacts_possible():
                for _ in range(STEPS_PER_CONTROL):
                    self.space.step(DT)
            self.time += DT_CONTROL
            self._carry()
            return
        stepped = self._contacts_possible()
        v_cmd, w_cmd = self.v_cmd, self.w_cmd
        a_step, alpha_step = _SLOW_STEPS[self._slow_floor and on_slow_floor(x, y)]
        speed_work, turn_work = self._speed_work, self._turn_work
        for _ in range(STEPS_PER_CONTROL):
            dv, dw = v_cmd - v, w_cmd - w
            v0, w0 = v, w
            v += a_step if dv > a_step else max(dv, -a_step)
            w += alpha_step if dw > alpha_step else max(dw, -alpha_step)
            if v != v0:  # the energy measure (module doc); never read by the physics
                speed_work += abs(v * v - v0 * v0) if v * v0 >= 0.0 else v * v + v0 * v0
            if w != w0:
                turn_work += abs(w * w - w0 * w0) if w * w0 >= 0.0 else w * w + w0 * w0
            vx, vy = v * math.cos(phi), v * math.sin(phi)
            if stepped:
                _set_velocity(base, (vx, vy))
                _set_angular_velocity(base, w)
                self.space.step(DT)
            x += vx * DT
            y += vy * DT
            phi += w * DT
        if not stepped:
            _set_position(base, (x, y))
        self.v, self.w, self.phi, self._xy = v, w, phi, (x, y)
        self._speed_work, self._turn_work = speed_work, turn_work
        self.time += DT_CONTROL
        self._carry()

    def _contacts_possible(self) -> bool:
        """A free cup lies within reach of the base's next control period, or is still sliding."""
        x, y = self._xy
        reach = W.BASE_RADIUS + W.CUP_RADIUS + W.V_MAX * DT_CONTROL + 0.05
        for name, body in self.cups.items():
            if name == self.held:
                continue
            cx, cy = body.position
            if (cx - x) ** 2 + (cy - y) ** 2 <= reach * reach or body.velocity != (0.0, 0.0):
                return True
        return False

    def _carry(self) -> None:
        if self.held is not None:
            body = self.cups[self.held]
            _set_position(body, self.gripper())
            _set_velocity(body, (0.0, 0.0))

    # --- actions ----------------------------------------------------------------------------------------
    def run(self, call: ActionCall) -> Episode:
        """Execute one action from the current state until it ends; the Episode logs the believed state."""
        return self._execute(call, None)

    def run_sequence(self, calls: Sequence[ActionCall]) -> SequenceResult:
        """Dispatch actions back to back; stop at the first failure."""
        self._next_sample = self.time
        return run_in_sequence(self._execute, calls, lambda: self.time, TRAJECTORY_COLUMNS)

    def _execute(self, call: ActionCall, trajectory: list | None) -> Episode:
        goal = _check_call(call)
        self._log_t: list[float] = []
        self._log: list[tuple[float, ...]] = []
        self._ticks = 0
        self._trajectory = trajectory
        self._speed_work = self._turn_work = self._arm_work = 0.0
        self._released_at = None
        true = self.true_state()
        believed = self._believe(true, self._noise.next())
        start = (*believed, 0.0, 0.0, 0.0, self.v) if call.action == "navigate" else (*believed, 0.0, 0.0, 0.0)
        params = np.array([*start, *goal], dtype=float)
        if call.action == "navigate":
            outcome = self._go_to_pose(goal)
        else:
            outcome = self._arm(call.action, goal, believed)
        return Episode(call.action, params, np.array(self._log_t),
                       np.array(self._log, dtype=float).reshape(-1, len(STATE_COLUMNS)), STATE_COLUMNS, outcome,
                       self._ticks / CONTROL_HZ, self.seed, self._measures(call.action, goal))

    def _measures(self, action: str, goal: Sequence[float]) -> dict[str, float]:
        """The measures of the action that ends now, toward `goal` (see the module doc)."""
        energy = 0.5 * (BASE_MASS * self._speed_work + BASE_MOMENT * self._turn_work) + self._arm_work
        if action == "navigate":
            gx, gy, gphi = W.spot_pose(*goal[:6])
            x, y = self._xy
            return {ENERGY: energy, ERROR: math.hypot(x - gx, y - gy),
                    HEADING_ERROR: abs(W.wrap(self.phi - gphi))}
        px, py = self._released_at if self._released_at is not None else self.gripper()
        return {ENERGY: energy, ERROR: math.hypot(px - goal[0], py - goal[1])}

    def _tick(self) -> tuple[tuple[float, ...], list[float], tuple[float, float, float]]:
        """Record the start of a control period: trajectory sample, believed state, log row."""
        true = self.true_state()
        if self._trajectory is not None and self.time >= self._next_sample - 1e-9:
            self._trajectory.append((self.time, *true))
            self._next_sample += 1.0 / LOG_HZ
        e = self._noise.next()
        believed = self._believe(true, e)
        if self._ticks % CONTROLS_PER_LOG == 0:
            self._log_t.append(self._ticks / CONTROL_HZ)
            self._log.append((*believed, 0.0, 0.0, 0.0, true[3], true[4], true[5]))
        return true, e, believed

    def _go_to_pose(self, goal: Sequence[float]) -> str:
        gx, gy, gphi = W.spot_pose(*goal[:6])
        v_goal, cruise = goal[6], goal[7]  # (>= 0, > 0: _check_call)
        passing = v_goal > 0.0
        x0, y0 = self._xy
        path = self._route((x0, y0), (gx, gy, gphi), passing)
        lengths = [math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in pairwise(path)]
        cg, sg = math.cos(gphi), math.sin(gphi)
        k, arrived, behind = 0, False, False
        max_ticks = round(TIMEOUT * CONTROL_HZ)
        cup_moves = None  # (moment, window) of the "cup" disturbance, if it strikes during this navigate
        if self._cup_pending and standing_cups(self._cup_positions(), self.tables, self.held):
            self._cup_pending = False
            cup_moves = cup_moment(self._disturbances, math.hypot(gx - x0, gy - y0))
        while True:
            true, e, (x, y, phi) = self._tick()
            if cup_moves is not None and self._ticks >= cup_moves[0] * CONTROL_HZ:
                self._displace_cup(self._ticks / CONTROL_HZ, cup_moves[1])
                cup_moves = None
            if self.collides():
                return "collision"
            past = (x - gx) * cg + (y - gy) * sg  # believed, along the goal heading's line from the goal
            behind = behind or (past < 0.0 and abs((y - gy) * cg - (x - gx) * sg) <= LEAD_IN)  # ... and across
            if passing and past >= 0.0 and (behind or k == len(lengths) - 1):
                # crossed the way-point's line near it coming from behind, or beyond it on the route's last leg (a
                # start past it): judged on the true state
                if (math.hypot(true[0] - gx, true[1] - gy) <= PASS_TOL
                        and abs(W.wrap(true[2] - gphi)) <= PASS_HEADING_TOL):
                    return "success"
                return "off_course"
            if (not passing and arrived and math.hypot(true[0] - gx, true[1] - gy) <= POS_TOL
                    and abs(W.wrap(true[2] - gphi)) <= HEADING_TOL
                    and abs(self.v) <= SPEED_TOL and abs(self.w) <= TURN_RATE_TOL):
                return "success"
            if self._ticks >= max_ticks:
                return "timeout"
            if not passing and not arrived and math.hypot(gx - x, gy - y) <= ARRIVE_TOL:
                arrived = True
            v_max, w_max, a_max, alpha_max = self.limits()
            if arrived:
                err = W.wrap(gphi - phi)
                rate = min(w_max, K_TURN * abs(err), math.sqrt(2.0 * BRAKE * alpha_max * abs(err)))
                self.command(0.0, math.copysign(rate, err), e[3:5], cruise)
            else:
                # project onto the current leg, move on to the next leg once past this one's end or nearer the next
                # leg than this one (a corner cut short: its projection can fall back along this leg)
                while True:
                    (ax, ay), (bx, by) = path[k], path[k + 1]
                    length = lengths[k]
                    s = ((x - ax) * (bx - ax) + (y - ay) * (by - ay)) / length if length > 0 else length
                    if k < len(lengths) - 1 and (s >= length or leg_distance(path, k + 1, x, y)
                                                 <= leg_distance(path, k, x, y)):
                        k += 1
                        continue
                    break
                s = max(0.0, min(length, s))
                carrot, j = s + LOOKAHEAD, k  # the carrot's distance along leg j
                while carrot > lengths[j] and j < len(lengths) - 1:
                    carrot -= lengths[j]
                    j += 1
                (ax, ay), (bx, by) = path[j], path[j + 1]
                f = min(1.0, carrot / lengths[j]) if lengths[j] > 0 else 1.0
                cx, cy = ax + f * (bx - ax), ay + f * (by - ay)
                err = W.wrap(math.atan2(cy - y, cx - x) - phi)
                rate = max(-w_max, min(w_max, K_TURN * err))
                speed = v_max * max(0.0, 1.0 - abs(err) / TURN_IN_PLACE)
                brake = math.sqrt(v_goal * v_goal + 2.0 * BRAKE * a_max * math.hypot(gx - x, gy - y))
                speed = min(speed, max(V_CREEP, brake))
                self.command(speed, rate, e[3:5], cruise)
            self._advance()
            self._ticks += 1

    def _route(self, start: tuple[float, float], goal: tuple[float, float, float], passing: bool
               ) -> list[tuple[float, float]]:
        """The way-points navigate follows: the shortest route to the goal position, or to pass it (`passing`),
        the shortest route to the point LEAD_IN behind it on the goal heading's line, the goal, and a point
        LOOKAHEAD beyond it on that line (pure pursuit aims down the line as the base crosses). Where the lead-in
        point lies in the grown furniture or the start is already on the lead-in (within LEAD_IN behind the goal and
        PASS_TOL of the line), the route goes to the goal."""
        gx, gy, gphi = goal
        if not passing:
            return self.routes.path(start, (gx, gy))
        c, s = math.cos(gphi), math.sin(gphi)
        lead = (gx - LEAD_IN * c, gy - LEAD_IN * s)
        dx, dy = start[0] - gx, start[1] - gy
        on_lead_in = -LEAD_IN <= dx * c + dy * s <= 0.0 and abs(-dx * s + dy * c) <= PASS_TOL
        if on_lead_in or self.routes.inside(lead):
            head = self.routes.path(start, (gx, gy))
        else:
            head = [*self.routes.path(start, lead), (gx, gy)]
        return [*head, (gx + LOOKAHEAD * c, gy + LOOKAHEAD * s)]

    def _cup_positions(self) -> dict[str, tuple[float, float]]:
        return {name: tuple(body.position) for name, body in self.cups.items()}

    def _displace_cup(self, elapsed: float, window: tuple[float, float]) -> None:
        """The "cup" disturbance strikes: a standing cup slides on its table (sims.kitchen.disturbances)."""
        moved = displace(self._disturbances, self._cup_positions(), self.tables, self.held)
        if moved is None:
            return
        name, after = moved
        body = self.cups[name]
        before = tuple(body.position)
        body.position, body.velocity = after, (0.0, 0.0)
        self.space.reindex_shapes_for_body(body)
        self.events.append(CupDisplacement(name, before, after, self.time, elapsed, window))

    def _arm(self, action: str, goal: Sequence[float], base: tuple[float, float, float]) -> str:
        """grip / put: reach the point, close / open the gripper, tuck the arm."""
        e = self._noise.next()
        bx, by, bphi = base
        tx, ty = goal
        if action == "grip":  # the arm's camera sees the cup nearest the point, relative to the base
            near = [(math.hypot(b.position[0] - tx, b.position[1] - ty), b) for b in self.cups.values()]
            gap, body = min(near, default=(math.inf, None), key=lambda g: g[0])
            if gap <= CUP_SEARCH:
                bx, by, bphi = self._xy[0], self._xy[1], self.phi
                tx, ty = body.position
        tx, ty = tx + self.noise.position * e[0], ty + self.noise.position * e[1]
        sx, sy = bx + W.SHOULDER_OFFSET * math.cos(bphi), by + W.SHOULDER_OFFSET * math.sin(bphi)
        pan = W.wrap(math.atan2(ty - sy, tx - sx) - bphi)
        ext = math.hypot(tx - sx, ty - sy)
        self.command(0.0, 0.0)
        if action == "put" and self.held is None:
            return "not_holding"
        if abs(pan) > W.PAN_LIMIT or not (W.EXT_REST <= ext <= W.EXT_MAX) or not self._base_at_table(goal):
            self._tick()
            return "out_of_reach"
        outcome = self._move_arm(pan, ext)
        if outcome:
            return outcome
        for _ in range(round(W.GRIPPER_TIME * CONTROL_HZ)):
            self._tick()
            self._advance()
            self._ticks += 1
        gx, gy = self.gripper()
        self._released_at = (gx, gy)
        if action == "grip":
            near = [(math.hypot(b.position[0] - gx, b.position[1] - gy), n) for n, b in self.cups.items()]
            gap, name = min(near, default=(math.inf, None), key=lambda g: g[0])
            if gap > GRIP_TOLERANCE:
                self._tick()
                return "missed"
            self.held = name
        else:
            self.held = None
            if not any(box.contains(gx, gy) for box in self.tables.values()):
                self._tick()
                return "cup_dropped"
        return self._move_arm(0.0, W.EXT_REST) or "success"

    def _base_at_table(self, point: Sequence[float]) -> bool:
        """The grip precondition: the base SPOT_DIST from the serving edge of the table at `point`."""
        x, y = self._xy
        for box in self.tables.values():
            if box.distance(point[0], point[1]) <= W.CUP_RADIUS:
                c, s = math.cos(box.angle), math.sin(box.angle)
                edge = box.cx - c * box.hx, box.cy - s * box.hx  # middle of the serving edge
                d = c * (edge[0] - x) + s * (edge[1] - y)  # base centre in front of the edge
                return W.SPOT_DIST[0] - REACH_TOLERANCE <= d <= W.SPOT_DIST[1] + REACH_TOLERANCE
        return False

    def _move_arm(self, pan_goal: float, ext_goal: float) -> str | None:
        """Both joints along velocity ramps to the goal; None once there, "timeout" otherwise."""
        pan_rate = ext_rate = 0.0
        moved = (0.0, 0.0)  # the joint rates executed in the last control period (the energy measure's)
        max_ticks = round(TIMEOUT * CONTROL_HZ)
        try:
            while True:
                _, e, _ = self._tick()
                if (abs(self.pan - pan_goal) <= PAN_TOL and abs(self.ext - ext_goal) <= EXT_TOL
                        and abs(pan_rate) <= W.PAN_ACCELERATION * DT_CONTROL
                        and abs(ext_rate) <= W.EXT_ACCELERATION * DT_CONTROL):
                    return None
                if self._ticks >= max_ticks:
                    return "timeout"
                pan_rate = _ramp(self.pan, pan_rate, pan_goal, W.PAN_SPEED, W.PAN_ACCELERATION)
                ext_rate = _ramp(self.ext, ext_rate, ext_goal, W.EXT_SPEED, W.EXT_ACCELERATION)
                m = self.noise.motor
                pan_moved, ext_moved = pan_rate * (1.0 + m * e[5]), ext_rate * (1.0 + m * e[6])
                r0 = self.ext
                self.pan += pan_moved * DT_CONTROL
                self.ext += ext_moved * DT_CONTROL
                self._arm_work += _arm_work(self._arm_mass(), r0, self.ext, moved, (pan_moved, ext_moved))
                moved = (pan_moved, ext_moved)
                self._advance()
                self._ticks += 1
        finally:  # the arm stops
            self._arm_work += _arm_work(self._arm_mass(), self.ext, self.ext, moved, (0.0, 0.0))

    def _arm_mass(self) -> float:
        """kg the arm's joints move: the gripper, and the cup it holds."""
        return GRIPPER_MASS + (W.CUP_MASS if self.held is not None else 0.0)


def _ramp_work(before: float, after: float) -> float:
    """2/m times the work of changing a speed from `before` to `after` at constant acceleration (braking to
    rest and speeding up again where it reverses: nothing is recovered); `_advance` inlines it, per step."""
    return abs(after * after - before * before) if after * before >= 0.0 else after * after + before * before


def _arm_work(mass: float, r0: float, r1: float, before: tuple[float, float],
              after: tuple[float, float]) -> float:
    """J the arm's motors spend on a point mass at the gripper over one control period (module doc): its joint
    rates (pan, extension) jump from `before` to `after` at extension r0, then hold while it goes to r1."""
    pan, ext = after
    return (0.5 * mass * (r0 * r0 * _ramp_work(before[0], pan) + _ramp_work(before[1], ext))
            + 1.5 * mass * pan * pan * abs(r1 * r1 - r0 * r0))


def _check_call(call: ActionCall) -> tuple[float, ...]:
    if call.action not in ACTIONS:
        raise SimError(f"unknown kitchen action {call.action!r}; known: {', '.join(ACTIONS)}")
    goal = tuple(float(g) for g in call.goal)
    if len(goal) != GOAL_SIZES[call.action] or not all(math.isfinite(g) for g in goal):
        raise SimError(f"{call.action}: goal must be {GOAL_SIZES[call.action]} finite numbers, got {call.goal}")
    if call.action == "navigate" and goal[6] < 0.0:
        raise SimError(f"navigate: the speed to pass the goal at must be >= 0 m/s, got {goal[6]:g}")
    if call.action == "navigate" and goal[7] <= 0.0:
        raise SimError(f"navigate: the cruise speed must be > 0 m/s, got {goal[7]:g}")
    return goal


def simulate_sequence(pose: tuple[float, float, float], tables: Mapping[str, Sequence[float]],
                      cups: Mapping[str, Sequence[float]], calls: Sequence[ActionCall], seed: int,
                      noise: Noise | None = None, disturbance: str | None = None,
                      variant: str | None = None) -> SequenceResult:
    """Execute actions in a fresh simulator placed at (pose, tables, cups)."""
    sim = KitchenSim(seed, Noise() if noise is None else noise, disturbance, variant)
    sim.place(pose, tables, cups)
    return sim.run_sequence(list(calls))
