"""SoccerSim: one robot and a ball on the field, a pymunk space stepped at a fixed rate (headless).

Timing: physics at PHYSICS_HZ, the action (controller) at CONTROL_HZ holding its command in between, the
state logged at LOG_HZ (Sec. 4.1: 10 Hz). The robot is a kinematic body: each physics step its [v, phidot]
moves toward the (noisy) command by at most A_MAX / ALPHA_MAX per second, within V_MAX / W_MAX (unicycle
model of the wheel axle); pymunk resolves its contacts with the ball.

An action ends (Episode.outcome) on
- "success": ball point within POS_TOL of the goal, heading within HEADING_TOL, speed within SPEED_TOL of
  vg (goToPosition: no heading); for approachBall the untouched ball also lies within POS_TOL of the ball point, for dribbleBall the
  ball sits in the guide (within BALL_HELD_DISTANCE of the ball point);
- "collision": a ball is in the scene, the action does not dribble, and the ball moved (by more than
  BUMP_DISTANCE) before the goal pose was reached: the robot bumped it;
- "ball_moved": as "collision", but the disturbance "nudge" pushed the ball during the action: someone else
  moved it (a failure the robot's own models cannot predict, kept apart from the collisions they learn);
- "ball_lost": dribbling, the ball is further than BALL_LOST_DISTANCE from the ball point (also when a nudge
  knocked it out of the guide), or it lies at rest outside the guide while the robot stands at a goal it was
  to reach standing (nothing would move either again: without this the action waited for its timeout);
- "timeout": TIMEOUT simulated seconds passed.
An action the nudge made fail ("ball_moved", or "ball_lost" with the push during it) ends only once the
robot, braking to a stop, and the ball lie at rest (NUDGE_FAILURES). Termination is judged on the true state;
the action sees (and the Episode logs) the believed state.

Measures (Episode.measures, sims.episode), on the true state, none of them changing the simulation:
- "energy" (J): the work of the drive on the robot's body, W.ROBOT_MASS m and W.ROBOT_MOMENT I about the axle:
  each physics step changes v from v0 to v1 (and phidot from w0 to w1) at constant acceleration, which takes
  the integral of |F v| = m/2 |v1^2 - v0^2| (m/2 (v0^2 + v1^2) where v reverses within the step), and likewise
  I/2 for phidot. Rolling at constant speed costs nothing (no friction is modelled), braking costs as much as
  speeding up (nothing is recovered); the work done on the ball (pushed, dribbled) is not counted;
- "error" (m): the ball point's distance to the goal position (xg, yg) at the action's end;
- "heading_error" (rad, [0, pi]): |heading - phig| wrapped, at the action's end; absent for goToPosition (its
  goal has no heading, HEADING_FREE).

Closed-loop execution (Ch. 8.1, tailor.execution) reads between two actions what the robot measures now:
`observe(action)` (the action's observed parameters) and `scene()` (every scene object). Both read the
believed state without drawing from the noise stream: they return exactly the reading the next action starts
from (its Episode.params), and a closed loop that observes sees the same noise as an open loop that does not.

The disturbance "nudge" (`Nudge`): once in a simulator's life, at a time drawn from its seed in
W.NUDGE_WINDOW, an opponent pushes the ball (see `Nudge`). The variant "weak_motors" is a `W.Dynamics`
(W.weak_motors) passed as `dynamics`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pymunk

from tailor.sims.episode import (ENERGY, ERROR, HEADING_ERROR, ActionCall, Episode, SequenceResult,
                                 run_in_sequence)
from tailor.errors import SimError
from tailor.sims.soccer import world as W
from tailor.sims.soccer.actions import ACTION_FUNCTIONS, HEADING_FREE
from tailor.sims.soccer.world import CONTROL_HZ, LOG_HZ, PHYSICS_HZ

DT = 1.0 / PHYSICS_HZ  # s
STEPS_PER_CONTROL = PHYSICS_HZ // CONTROL_HZ
CONTROLS_PER_LOG = CONTROL_HZ // LOG_HZ

POS_TOL = 0.1  # m, ball point to goal position
HEADING_TOL = 0.2  # rad, heading to goal heading
SPEED_TOL = 0.15  # m/s, speed to vg
BALL_HELD_DISTANCE = 0.06  # m, a ball this close to the ball point is in the guide
BALL_LOST_DISTANCE = 0.15  # m, a dribbled ball further than this from the ball point is lost
BUMP_DISTANCE = 0.02  # m, a ball moved this far was bumped
TIMEOUT = 30.0  # s, simulated time an action may take

# outcomes of an action the nudge made fail (during it): the robot, which sees the ball go, brakes to a stop,
# and the episode ends (its duration counts the wait) once robot and ball are at rest, where the next action
# (or a closed loop's scene()) finds them: an approach begun while the ball still rolled failed at once as a
# collision (a closed loop completed none of 100 nudged `score` situations so, 93 with the wait)
NUDGE_FAILURES = ("ball_moved", "ball_lost")

_WALL_RADIUS = 0.02  # m, thickness of the wall segments
_GUIDE_RADIUS = 0.005  # m, thickness of the guide arms


@dataclass(frozen=True)
class Noise:
    """Seeded noise: on the motor commands (as the motors execute them) and on the believed state.

    motor: relative standard deviation of the executed v and phidot, drawn anew each control period;
    position (m), heading (rad), speed (m/s): standard deviations of the believed robot pose and ball.
    """

    motor: float = 0.03
    position: float = 0.01
    heading: float = math.radians(1.0)
    speed: float = 0.01

    @classmethod
    def off(cls) -> Noise:
        return cls(0.0, 0.0, 0.0, 0.0)


# The body properties' setters called directly: pymunk's Body routes every attribute assignment through a
# Python-level __setattr__ first, which costs as much as the physics step of the robot itself.
_set_velocity = pymunk.Body.velocity.fset
_set_angular_velocity = pymunk.Body.angular_velocity.fset
_get_velocity = pymunk.Body.velocity.fget
_A_STEP = W.A_MAX * DT  # m/s, largest change of v in one physics step
_ALPHA_STEP = W.ALPHA_MAX * DT  # rad/s, largest change of phidot in one physics step


_set_damping = pymunk.Space.damping.fset
_ROLL_DROP = W.ROLL_DECELERATION * DT  # m/s, speed a rolling ball loses in one physics step


def _ball_velocity(body: pymunk.Body, gravity: tuple[float, float], damping: float, dt: float) -> None:
    """Rolling friction: the ball's speed drops by ROLL_DECELERATION * dt each step, down to rest."""
    vx, vy = _get_velocity(body)
    speed = math.hypot(vx, vy)
    drop = W.ROLL_DECELERATION * dt
    if speed <= drop:
        _set_velocity(body, (0.0, 0.0))
    else:
        k = (speed - drop) / speed
        _set_velocity(body, (vx * k, vy * k))


def _rolling_damping(vx: float, vy: float) -> float | None:
    """The space damping with which pymunk's own velocity integration of a ball moving at (vx, vy) is
    bit-for-bit `_ball_velocity` (None if there is none): pymunk computes v * pow(damping, DT) + 0 (no
    gravity, no force), so the damping must have pow(damping, DT) == k exactly, k the friction factor
    (0 for a ball coming to rest). Python's math.pow and pymunk call the same C pow; a factor that no
    damping reaches, or a zero velocity component (whose -0.0 pymunk's + 0 would turn into +0.0), gets None.
    """
    speed = math.hypot(vx, vy)
    if speed <= _ROLL_DROP:
        return 0.0  # pow(0, DT) == 0: (+0, +0) either way
    k = (speed - _ROLL_DROP) / speed
    if vx * k == 0.0 or vy * k == 0.0:
        return None
    damping = k ** (1.0 / DT)  # pow(damping, DT) is flat: a few neighbouring dampings give each factor
    for candidate in (damping, math.nextafter(damping, 0.0), math.nextafter(damping, 1.0)):
        if math.pow(candidate, DT) == k:
            return candidate
    return None


@dataclass(frozen=True)
class Nudge:
    """The push of the disturbance "nudge", drawn from the simulator's seed (its own stream, W.NUDGE_STREAM,
    so the motor and sensor noise are those without it): at physics step `step` of the simulator's clock
    (which reset does not rewind) the ball's velocity gains `speed` in direction `direction` (rad), the speed
    at which a ball at rest rolls `roll` metres before friction stops it. A ball within BALL_LOST_DISTANCE of
    the ball point (in the guide, dribbled or just reached) is knocked out ahead of the robot: the direction,
    taken relative to the heading, is scaled into +-W.NUDGE_KNOCK_CONE (a push sideways would only press it
    against a guide arm, one backward against the robot). Without a ball in the scene then nothing happens."""

    step: int
    direction: float
    roll: float

    @property
    def time(self) -> float:
        """s of the simulator's clock at which the push comes (a whole physics step)."""
        return self.step * DT

    @property
    def speed(self) -> float:
        """m/s: rolling friction stops a ball pushed from rest at this speed after `roll` metres."""
        return math.sqrt(2.0 * W.ROLL_DECELERATION * self.roll)

    @classmethod
    def draw(cls, seed: int) -> Nudge:
        rng = np.random.default_rng([int(seed), W.NUDGE_STREAM])
        time = rng.uniform(*W.NUDGE_WINDOW)
        direction, roll = rng.uniform(-math.pi, math.pi), rng.uniform(*W.NUDGE_ROLL)
        return cls(math.ceil(time / DT - 1e-9), float(direction), float(roll))


STATE_COLUMNS = ("x", "y", "phi", "v", "ball_x", "ball_y")  # the logged believed state (ball NaN without one)
TRAJECTORY_COLUMNS = ("t", *STATE_COLUMNS)  # the true state of a dispatched sequence


class SoccerSim:
    """The soccer field with one robot and (optionally) a ball; `run` executes one action as an Episode.

    `dynamics`: the robot's motor limits (W.PIONEER, W.SPARROW, or a variant: W.weak_motors(W.PIONEER));
    `disturbance`: None or W.NUDGE (see `Nudge`).
    """

    state_columns = STATE_COLUMNS

    def __init__(self, seed: int, noise: Noise = Noise(), dynamics: W.Dynamics = W.PIONEER,
                 disturbance: str | None = None):
        if disturbance is not None and disturbance not in W.DISTURBANCES:
            raise SimError(f"the soccer simulator has no disturbance {disturbance!r} "
                           f"(known: {', '.join(W.DISTURBANCES)})")
        self.noise = noise
        self.dynamics = dynamics
        self._a_step = _A_STEP if dynamics == W.PIONEER else dynamics.a_max * DT
        self._alpha_step = _ALPHA_STEP if dynamics == W.PIONEER else dynamics.alpha_max * DT
        self.rng = np.random.default_rng(seed)
        self.seed = int(seed)
        self.space = pymunk.Space()
        self._add_walls()
        self.robot = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        hl, hw = W.ROBOT_HALF_LENGTH, W.ROBOT_HALF_WIDTH
        shapes = [pymunk.Poly(self.robot, [(-hl, -hw), (hl, -hw), (hl, hw), (-hl, hw)])]
        shapes += [pymunk.Segment(self.robot, a, b, _GUIDE_RADIUS) for a, b in W.guide_arms()]
        for shape in shapes:
            shape.friction, shape.elasticity = 0.0, 0.0
        self.space.add(self.robot, *shapes)
        self.ball = pymunk.Body(W.BALL_MASS, math.inf)
        self.ball.velocity_func = _ball_velocity
        ball_shape = pymunk.Circle(self.ball, W.BALL_RADIUS)
        ball_shape.friction, ball_shape.elasticity = 0.0, W.WALL_ELASTICITY
        self._ball_shape = ball_shape
        self._friction_callback, self._damping = True, 1.0  # how pymunk steps the ball's friction (_physics)
        self.has_ball = False
        self.time = 0.0
        self.v = self.w = 0.0  # true translational / rotational velocity
        self.phi = 0.0  # true heading (mirrors the body's angle)
        self.v_cmd = self.w_cmd = 0.0
        # sums over physics steps of |v1^2 - v0^2| (v0^2 + v1^2 where v reverses) and the same of phidot,
        # since the running action began: its energy is m/2 and I/2 times them (see the module doc)
        self._speed_work = self._turn_work = 0.0
        self.steps = 0  # physics steps in this simulator's life: the clock of a disturbance (reset keeps it)
        self.nudge = Nudge.draw(seed) if disturbance == W.NUDGE else None  # the push to come (or that came)
        self.nudged: tuple[float, float] | None = None  # where the push found the ball (NaN: none), once done

    def _add_walls(self) -> None:
        hx, hy = W.FIELD_HALF_LENGTH + W.WALL_RUNOFF, W.FIELD_HALF_WIDTH + W.WALL_RUNOFF
        corners = [(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)]
        for a, b in zip(corners, corners[1:] + corners[:1]):
            wall = pymunk.Segment(self.space.static_body, a, b, _WALL_RADIUS)
            wall.elasticity, wall.friction = W.WALL_ELASTICITY, 0.0
            self.space.add(wall)

    # --- state ------------------------------------------------------------------------------------------
    def reset(self, scene) -> None:
        """The protocol's reset: scene {"robot": (x, y, phi, v), "ball": (x, y)} (the ball is optional)."""
        if not isinstance(scene, Mapping):
            raise SimError(f"reset takes a scene mapping {{'robot': (x, y, phi, v), 'ball': (x, y)}}, not {scene!r}")
        if "robot" not in scene:
            raise SimError(f"the soccer scene needs a robot (x, y, phi, v); it has {', '.join(scene) or 'nothing'}")
        unknown = set(scene) - {"robot", "ball"}
        if unknown:
            raise SimError(f"the soccer scene has robot and ball, not {', '.join(sorted(unknown))}")
        robot, ball = scene["robot"], scene.get("ball")
        if len(robot) != 4 or (ball is not None and len(ball) != 2):
            raise SimError("the soccer scene's robot is (x, y, phi, v) and its ball (x, y)")
        self.place(tuple(robot), None if ball is None else tuple(ball))

    def place(self, robot: tuple[float, float, float, float], ball: tuple[float, float] | None = None) -> None:
        """Place the robot (ball point x, y, heading phi, speed v) and the ball (at rest) or no ball."""
        x, y, phi, v = (float(q) for q in robot)
        v_max = self.dynamics.v_max
        if self.dynamics == W.WEAK_PIONEER and W.PIONEER.v_max >= abs(v) > v_max:
            v = math.copysign(v_max, v)  # the weak robot cannot start faster than it drives
        if not all(math.isfinite(q) for q in (x, y, phi, v)) or abs(v) > v_max + 1e-9:
            raise SimError(f"invalid robot state {robot}: finite values and |v| <= {v_max} m/s required")
        _inside_walls("the robot's ball point", x, y)
        if ball is not None:
            if not all(math.isfinite(float(q)) for q in ball):
                raise SimError(f"invalid ball position {ball}: finite values required")
            _inside_walls("the ball", float(ball[0]), float(ball[1]))
        self.phi, self.v, self.w = phi, v, 0.0
        self.v_cmd, self.w_cmd = v, 0.0
        self.robot.angle = phi
        self.robot.position = (x - W.BALL_POINT_OFFSET * math.cos(phi), y - W.BALL_POINT_OFFSET * math.sin(phi))
        self.robot.velocity = (v * math.cos(phi), v * math.sin(phi))
        self.robot.angular_velocity = 0.0
        if ball is not None and not self.has_ball:
            self.space.add(self.ball, self._ball_shape)
        elif ball is None and self.has_ball:
            self.space.remove(self.ball, self._ball_shape)
        self.has_ball = ball is not None
        if ball is not None:
            self.ball.position = (float(ball[0]), float(ball[1]))
            self.ball.velocity = (0.0, 0.0)
        self.space.reindex_shapes_for_body(self.robot)
        self.time = 0.0

    def true_state(self) -> tuple[float, float, float, float, float, float]:
        """(x, y, phi, v, ball_x, ball_y) of the ball point; ball NaN without a ball."""
        px, py = self.robot.position
        c, s = math.cos(self.phi), math.sin(self.phi)
        bx, by = self.ball.position if self.has_ball else (math.nan, math.nan)
        return px + W.BALL_POINT_OFFSET * c, py + W.BALL_POINT_OFFSET * s, W.wrap(self.phi), self.v, bx, by

    def believed_state(self) -> tuple[float, float, float, float, float, float]:
        """The true state with the seeded sensing noise of `self.noise`."""
        return self._believe(self.true_state())

    def observe(self, action: str) -> tuple[float, float, float, float]:
        """What `action` measures now, its observed parameters (x, y, phi, v): exactly the first four values
        of the Episode.params of `run` called next. Advances neither the world nor the noise stream."""
        if action not in ACTION_FUNCTIONS:
            raise SimError(f"unknown soccer action {action!r}; known: {', '.join(ACTION_FUNCTIONS)}")
        return self._measure()[:4]

    def scene(self) -> dict[str, tuple[float, ...]]:
        """The scene as the robot measures it now, in the form `reset` takes: {"robot": (x, y, phi, v),
        "ball": (x, y)} (no ball without one); the same reading as `observe`. Advances neither the world nor
        the noise stream. `reset(scene())` places pose, speed and ball, not a turn rate or a rolling ball."""
        belief = self._measure()
        scene = {"robot": belief[:4]}
        if self.has_ball:
            scene["ball"] = belief[4:]
        return scene

    def _measure(self) -> tuple[float, float, float, float, float, float]:
        """The believed state the next action starts from: drawn from a copy of the noise stream's state."""
        state = self.rng.bit_generator.state
        try:
            return self.believed_state()
        finally:
            self.rng.bit_generator.state = state

    def _believe(self, true: tuple[float, float, float, float, float, float]
                 ) -> tuple[float, float, float, float, float, float]:
        x, y, phi, v, bx, by = true
        n, e = self.noise, self.rng.standard_normal(6).tolist()  # floats: numpy scalars slow the actions
        return (x + n.position * e[0], y + n.position * e[1], W.wrap(phi + n.heading * e[2]), v + n.speed * e[3],
                bx + n.position * e[4], by + n.position * e[5])

    # --- dynamics ---------------------------------------------------------------------------------------
    def command(self, v_cmd: float, w_cmd: float) -> None:
        """Send a motor command [v, phidot]; the motors execute it with noise, within the velocity limits."""
        e = self.rng.standard_normal(2).tolist() if self.noise.motor > 0.0 else (0.0, 0.0)
        v_cmd *= 1.0 + self.noise.motor * e[0]
        w_cmd *= 1.0 + self.noise.motor * e[1]
        d = self.dynamics
        self.v_cmd = max(-d.v_max, min(d.v_max, v_cmd))
        self.w_cmd = max(-d.w_max, min(d.w_max, w_cmd))

    def step(self) -> None:
        """One physics step: accelerate toward the command within the limits, move, resolve contacts."""
        try:
            self._advance(1)
        finally:
            self._restore_friction()

    def _advance(self, steps: int) -> None:
        """`steps` physics steps (see `step`); the nudge, if one is due among them, between two of them."""
        nudge = self.nudge
        due = nudge.step - self.steps if nudge is not None and self.nudged is None else -1
        if 0 <= due < steps:
            self._physics(due)
            self.steps += due
            self._push(nudge)
            steps -= due
        self._physics(steps)
        self.steps += steps

    def _push(self, nudge: Nudge) -> None:
        """The opponent's push (see `Nudge`): the ball gains nudge.speed, away from a robot that has it."""
        if not self.has_ball:
            self.nudged = (math.nan, math.nan)  # nothing to push: the nudge is spent
            return
        x, y, phi, _, bx, by = self.true_state()
        direction = nudge.direction
        if math.hypot(bx - x, by - y) <= BALL_LOST_DISTANCE:  # knocked out ahead: relative angle scaled in
            direction = phi + W.wrap(direction - phi) * (W.NUDGE_KNOCK_CONE / math.pi)
        vx, vy = self.ball.velocity
        self.ball.velocity = (vx + nudge.speed * math.cos(direction), vy + nudge.speed * math.sin(direction))
        self.nudged = (bx, by)

    def _physics(self, steps: int) -> None:
        """`steps` physics steps (see `step`), with the per-step work kept to what changes the outcome.

        Two shortcuts, both exact (the episodes are bit-for-bit those of one `space.step` after setting every
        velocity each step with the `_ball_velocity` callback installed and a damping of 1):
        - the robot's velocities are sent to pymunk only when they changed, as pymunk never alters a
          kinematic body's velocity (its inverse mass and moment are 0, so an impulse adds +-0, which can only
          turn a -0.0 into +0.0: a velocity with a zero component is sent every step);
        - the ball's rolling friction is pymunk's own velocity integration with the damping of
          `_rolling_damping`, computed from the ball's velocity before the step (pymunk integrates the
          velocities after finding the contacts, which leave them alone, and before solving them); where
          there is no such damping, the callback runs, a Python call from C that costs more than the rest of
          the step. The caller puts the callback and a damping of 1 back (`_restore_friction`) before
          anyone else can step the space.
        """
        robot, space, ball = self.robot, self.space, self.ball
        v, w, phi, time = self.v, self.w, self.phi, self.time
        v_cmd, w_cmd, a, alpha = self.v_cmd, self.w_cmd, self._a_step, self._alpha_step
        v_sent = phi_sent = w_sent = None  # what pymunk holds (None: send it again)
        has_ball, callback, damping_sent = self.has_ball, self._friction_callback, self._damping
        speed_work, turn_work = self._speed_work, self._turn_work
        try:
            for _ in range(steps):
                if has_ball:
                    damping = _rolling_damping(*_get_velocity(ball))
                    if damping is None:
                        damping = 1.0
                        if not callback:
                            ball.velocity_func, callback = _ball_velocity, True
                    elif callback:
                        ball.velocity_func, callback = pymunk.Body.update_velocity, False
                    if damping != damping_sent:
                        _set_damping(space, damping)
                        damping_sent = damping
                dv, dw = v_cmd - v, w_cmd - w
                v0, w0 = v, w
                v += a if dv > a else -a if dv < -a else dv
                w += alpha if dw > alpha else -alpha if dw < -alpha else dw
                if v != v0:  # the energy measure (module doc); never read by the physics
                    speed_work += abs(v * v - v0 * v0) if v * v0 >= 0.0 else v * v + v0 * v0
                if w != w0:
                    turn_work += abs(w * w - w0 * w0) if w * w0 >= 0.0 else w * w + w0 * w0
                if v != v_sent or phi != phi_sent:
                    vx, vy = v * math.cos(phi), v * math.sin(phi)
                    _set_velocity(robot, (vx, vy))
                    v_sent, phi_sent = (v, phi) if vx != 0.0 and vy != 0.0 else (None, None)
                if w != w_sent:
                    _set_angular_velocity(robot, w)
                    w_sent = w
                space.step(DT)
                phi += w * DT
                time += DT
        finally:
            self.v, self.w, self.phi, self.time = v, w, phi, time
            self._friction_callback, self._damping = callback, damping_sent
            self._speed_work, self._turn_work = speed_work, turn_work

    def _restore_friction(self) -> None:
        """Install the rolling-friction callback and a damping of 1 again (see `_physics`)."""
        if not self._friction_callback:
            self.ball.velocity_func = _ball_velocity
            self._friction_callback = True
        if self._damping != 1.0:
            _set_damping(self.space, 1.0)
            self._damping = 1.0

    def control_tick(self, action: str, goal: tuple[float, float, float, float]) -> None:
        """One control period of `action` toward `goal` from the believed state: how a team scene steps several
        robots side by side (each in its own simulator) instead of running one action to its end."""
        belief = self.believed_state()
        self.motor_tick(*ACTION_FUNCTIONS[action](belief[0], belief[1], belief[2], belief[3], *goal))

    def motor_tick(self, v_cmd: float, w_cmd: float) -> None:
        """One control period of the motor command [v, phidot] (e.g. turning on the spot to look around)."""
        try:
            self.command(v_cmd, w_cmd)
            self._advance(STEPS_PER_CONTROL)
            self._keep_inside()
        finally:
            self._restore_friction()

    # --- actions ----------------------------------------------------------------------------------------
    def run(self, call: ActionCall) -> Episode:
        """Execute one action from the current state until it ends; the Episode logs the believed state."""
        return self._execute(call, trajectory=None)

    def run_sequence(self, calls: list[ActionCall]) -> SequenceResult:
        """Dispatch actions one after the other without stopping between them; stop at the first failure."""
        self._next_sample = self.time
        return run_in_sequence(self._execute, calls, lambda: self.time, TRAJECTORY_COLUMNS)

    def _execute(self, call: ActionCall, trajectory: list | None) -> Episode:
        if call.action not in ACTION_FUNCTIONS:
            raise SimError(f"unknown soccer action {call.action!r}; known: {', '.join(ACTION_FUNCTIONS)}")
        if len(call.goal) != 4 or not all(math.isfinite(float(g)) for g in call.goal):
            raise SimError(f"{call.action}: goal must be 4 finite numbers (xg, yg, phig, vg), got {call.goal}")
        act = ACTION_FUNCTIONS[call.action]
        xg, yg, phig, vg = (float(g) for g in call.goal)
        _inside_walls(f"{call.action}'s goal", xg, yg)
        if abs(vg) > self.dynamics.v_max + 1e-9:
            raise SimError(f"{call.action}: goal speed {vg:g} m/s is beyond the robot's {self.dynamics.v_max:g} m/s")
        dribbling = call.action == "dribbleBall"
        if dribbling and not self.has_ball:
            raise SimError("dribbleBall needs a ball in the scene")
        ball_start = tuple(self.ball.position) if self.has_ball else None
        nudged_before = self.nudged is not None
        settling = None  # the outcome of an action the nudge ended, while robot and ball come to rest
        ticks = 0
        log_t, log_state = [], []
        params = None
        max_ticks = int(round(TIMEOUT * CONTROL_HZ))
        outcome = "timeout"
        self._speed_work = self._turn_work = 0.0
        try:
            while True:
                true = self.true_state()
                if trajectory is not None and self.time >= self._next_sample - 1e-9:
                    trajectory.append((self.time, *true))
                    self._next_sample += 1.0 / LOG_HZ
                belief = self._believe(true)
                if params is None:
                    params = np.array([*belief[:4], xg, yg, phig, vg], dtype=float)
                if ticks % CONTROLS_PER_LOG == 0:
                    log_t.append(ticks / CONTROL_HZ)
                    log_state.append(belief)
                if settling is None:
                    ended = self._judge(true, call.action, dribbling, ball_start, xg, yg, phig, vg)
                    nudged = not nudged_before and self.nudged is not None  # during this action
                    if ended == "collision" and nudged:
                        ended = "ball_moved"
                    if ended in NUDGE_FAILURES and nudged:
                        settling = outcome = ended  # the robot stops; the ball rolls out (see NUDGE_FAILURES)
                    elif ended is not None:
                        outcome = ended
                        break
                if (settling is not None and self.v == 0.0 and self.w == 0.0
                        and _get_velocity(self.ball) == (0.0, 0.0)):
                    break
                if ticks >= max_ticks:
                    break
                if settling is not None:
                    self.command(0.0, 0.0)
                else:
                    self.command(*act(belief[0], belief[1], belief[2], belief[3], xg, yg, phig, vg))
                self._advance(STEPS_PER_CONTROL)
                self._keep_inside()
                ticks += 1
        finally:
            self._restore_friction()
        return Episode(call.action, params, np.array(log_t), np.array(log_state, dtype=float).reshape(-1, 6),
                       STATE_COLUMNS, outcome, ticks / CONTROL_HZ, self.seed,
                       self._measures(call.action, xg, yg, phig))

    def _measures(self, action: str, xg: float, yg: float, phig: float) -> dict[str, float]:
        """The measures of the action that ends now, toward goal (xg, yg, phig) (see the module doc)."""
        x, y, phi = self.true_state()[:3]
        measures = {ENERGY: 0.5 * (W.ROBOT_MASS * self._speed_work + W.ROBOT_MOMENT * self._turn_work),
                    ERROR: math.hypot(x - xg, y - yg)}
        if action not in HEADING_FREE:
            measures[HEADING_ERROR] = abs(W.wrap(phi - phig))
        return measures

    def _judge(self, true: tuple[float, float, float, float, float, float], action: str, dribbling: bool,
               ball_start, xg: float, yg: float, phig: float, vg: float) -> str | None:
        """The outcome if the action has ended in the true state `true`, else None."""
        x, y, phi, v, bx, by = true
        ball_gap = math.hypot(bx - x, by - y) if self.has_ball else math.nan
        if dribbling and ball_gap > BALL_LOST_DISTANCE:
            return "ball_lost"
        at_goal = (math.hypot(x - xg, y - yg) <= POS_TOL and abs(v - vg) <= SPEED_TOL
                   and (action in HEADING_FREE or abs(W.wrap(phi - phig)) <= HEADING_TOL))
        bumped = (ball_start is not None and not dribbling
                  and math.hypot(bx - ball_start[0], by - ball_start[1]) > BUMP_DISTANCE)
        if bumped:
            return "collision"
        if at_goal:
            if dribbling and ball_gap > BALL_HELD_DISTANCE:
                resting = v == 0.0 and vg <= 0.0 and _get_velocity(self.ball) == (0.0, 0.0)
                return "ball_lost" if resting else None
            if action == "approachBall" and ball_gap > POS_TOL:
                return None
            return "success"
        return None

    def _keep_inside(self) -> None:
        """Clamp the robot inside the walls (a kinematic body is not stopped by them)."""
        px, py = self.robot.position
        hx = W.FIELD_HALF_LENGTH + W.WALL_RUNOFF - W.ROBOT_HALF_LENGTH
        hy = W.FIELD_HALF_WIDTH + W.WALL_RUNOFF - W.ROBOT_HALF_WIDTH
        if abs(px) > hx or abs(py) > hy:
            self.robot.position = (max(-hx, min(hx, px)), max(-hy, min(hy, py)))
            self.space.reindex_shapes_for_body(self.robot)


def simulate_sequence(robot: tuple[float, float, float, float], ball: tuple[float, float] | None,
                      calls: list[ActionCall], seed: int, noise: Noise | None = None) -> SequenceResult:
    """Execute a sequence of actions in a fresh simulator: reset to (robot, ball), then run_sequence."""
    sim = SoccerSim(seed, Noise() if noise is None else noise)
    sim.place(robot, ball)
    return sim.run_sequence(list(calls))


def _inside_walls(what: str, x: float, y: float) -> None:
    """A SimError unless (x, y) lies within the walls (WALL_RUNOFF beyond the lines): nothing placed or aimed
    outside the world is simulated (it would only time out)."""
    x_max, y_max = W.FIELD_HALF_LENGTH + W.WALL_RUNOFF, W.FIELD_HALF_WIDTH + W.WALL_RUNOFF
    if not (abs(x) <= x_max and abs(y) <= y_max):
        raise SimError(f"{what} ({x:g}, {y:g}) lies outside the walls (|x| <= {x_max:g}, |y| <= {y_max:g} m)")
