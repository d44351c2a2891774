"""ArmSim: the planar PowerCube-like arm in a pymunk space stepped at a fixed rate (headless).

The two links are dynamic bodies: link A hangs on the static base by a PivotJoint at the shoulder, link B on
link A by a PivotJoint at the elbow. A SimpleMotor per joint (torque limited) drives the joint at the rate
the controller commands; the motors execute each command with seeded relative noise, saturated at OMEGA_HARD.

The reach action (App. A.4) plans synchronized ramp profiles (`profile.synchronize`) from the believed start
state to the goal and tracks them: each control tick a PID per joint commands the profile's velocity over the
next tick plus corrections of the position error (P, I) and the velocity error (D, the position error's
derivative). If the profile has ended REPLAN_AFTER s ago and the goal is not reached, it plans anew from the
believed state. Timing: physics at PHYSICS_HZ, control at CONTROL_HZ, the believed state logged at LOG_HZ.

A reach ends (Episode.outcome), judged on the true state at each control tick, with
- "success": both joint angles within ANGLE_TOL of the goal angles and both joint velocities within
  SPEED_TOL of the goal velocities (with a moving goal the arm passes it: a sequence goes on from there);
- "joint_limit": a joint angle is outside its limits (world.THETA_A_LIMITS, THETA_B_LIMITS);
- "timeout": TIMEOUT simulated seconds passed.

Measures (Episode.measures, sims.episode), on the true state, none of them changing the simulation:
- "energy" (J): the work of the two joint motors on the links (the physics' bodies: world.LINK_A_MASS and
  LINK_B_MASS, each a rod of moment m l^2 / 12 about its centre). Each physics step motor k applies the
  angular impulse j_k (pymunk's SimpleMotor: torque j_k / DT) while its joint's rate goes from w0 to w1: the
  work |j_k| |w0 + w1| / 2 (for one body exactly its change of kinetic energy), summed over both joints and
  the action's steps. Braking costs as much as speeding up (nothing is recovered); the bump's kick is not the
  motors' work. No gravity acts (the plane is horizontal), so an arm at rest costs nothing;
- "error" (m): the distance between the tip at the action's end and the tip at the goal angles
  (world.forward(theta_ga, theta_gb)): where the pen is against where it was sent. The goal velocities are not
  part of it, and a reach has no heading.

Closed loop (Ch. 8.1): `observe("reach")` and `scene()` measure the arm between reaches without advancing it;
the disturbance "bump" kicks the joints once, the variant "payload" lowers the ramps' acceleration (both in
sims.arm.disturbances).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pymunk

from tailor.sims.arm import world as W
from tailor.sims.arm.disturbances import (BUMP_WINDOW, DISTURBANCE_STREAM, DISTURBANCES, PAYLOAD_FACTOR,
                                          VARIANTS, Bump, bump_kick)
from tailor.sims.arm.profile import synchronize
from tailor.sims.episode import ENERGY, ERROR, ActionCall, Episode, SequenceResult, run_in_sequence
from tailor.sims.noise import NormalRows
from tailor.errors import SimError

PHYSICS_HZ = 100  # Hz, fixed physics step
CONTROL_HZ = 50  # Hz, PID rate (must divide PHYSICS_HZ)
LOG_HZ = 10  # Hz, logging rate (must divide CONTROL_HZ)
DT = 1.0 / PHYSICS_HZ  # s
DT_CONTROL = 1.0 / CONTROL_HZ  # s
STEPS_PER_CONTROL = PHYSICS_HZ // CONTROL_HZ
CONTROLS_PER_LOG = CONTROL_HZ // LOG_HZ

ANGLE_TOL = 0.02  # rad, each joint angle to its goal angle
SPEED_TOL = 0.1  # rad/s, each joint velocity to its goal velocity
TIMEOUT = 20.0  # s, simulated time a reach may take
REPLAN_AFTER = 0.2  # s after the profile's end without success: plan a new profile from the believed state

KP = 8.0  # 1/s, rad/s commanded per rad of position error
KI = 2.0  # 1/s^2, rad/s commanded per rad s of integrated position error
KD = 0.2  # rad/s commanded per rad/s of velocity error
INTEGRAL_LIMIT = 0.05  # rad s, anti-windup bound of the integrated position error

_impulse = pymunk.Constraint.impulse.fget  # (the getters called directly: cheaper than the attributes)
_angular_velocity = pymunk.Body.angular_velocity.fget

ACTIONS = ("reach",)
STATE_COLUMNS = ("theta_a", "omega_a", "theta_b", "omega_b", "tip_x", "tip_y")  # logged believed state
TRAJECTORY_COLUMNS = ("t", *STATE_COLUMNS)  # the true state of a dispatched sequence


@dataclass(frozen=True)
class Noise:
    """Seeded noise: on the motor commands (as the motors execute them) and on the measured joint state.

    motor: relative standard deviation of each executed joint rate, drawn anew each control tick;
    angle (rad), velocity (rad/s): standard deviations of the measured joint angles and velocities.
    """

    motor: float = 0.03
    angle: float = 0.002
    velocity: float = 0.01

    @classmethod
    def off(cls) -> Noise:
        return cls(0.0, 0.0, 0.0)


class ArmSim:
    """The arm on its base; `run` executes one reach as an Episode, `run_sequence` several back to back.

    `disturbance` ("bump") and `variant` ("payload") name one of sims.arm.disturbances' DISTURBANCES and
    VARIANTS, None for none; what a disturbance did is appended to `events` (Bump)."""

    state_columns = STATE_COLUMNS

    def __init__(self, seed: int, noise: Noise = Noise(), disturbance: str | None = None,
                 variant: str | None = None):
        for kind, name, known in (("disturbance", disturbance, DISTURBANCES), ("variant", variant, VARIANTS)):
            if name is not None and name not in known:
                raise SimError(f"the arm has no {kind} {name!r} (known: {', '.join(known)})")
        self.noise = noise
        self.seed = int(seed)
        self.rng = np.random.default_rng(seed)
        self._noise = NormalRows(self.rng, 6)  # 4 sensing + 2 motor values per control tick
        self.disturbance, self.variant = disturbance, variant
        # the ramps' acceleration limit: the payload's is lower (the speed limit stays)
        self.alpha_max = W.ALPHA_MAX if variant != "payload" else PAYLOAD_FACTOR * W.ALPHA_MAX
        self.events: list[Bump] = []
        self._reach_ticks = 0  # control ticks spent reaching, over every reach of this simulator
        self._bump: tuple[int, float, tuple[float, float]] | None = None  # (tick, moment, kick) still to come
        if disturbance == "bump":
            moment, kick = bump_kick(np.random.default_rng((self.seed, DISTURBANCE_STREAM)))
            self._bump = (math.ceil(moment * CONTROL_HZ - 1e-9), moment, kick)
        self.time = 0.0
        self.place(0.0, 0.0, 0.0, 0.0)

    # --- state ------------------------------------------------------------------------------------------
    def reset(self, scene: Mapping[str, Sequence[float]]) -> None:
        """The protocol's reset: scene {"arm": (theta_a, omega_a, theta_b, omega_b)}."""
        if set(scene) != {"arm"}:
            raise SimError(f"the arm scene has one object, arm (theta_a, omega_a, theta_b, omega_b); "
                           f"it has {', '.join(scene) or 'nothing'}")
        arm = tuple(scene["arm"])
        if len(arm) != 4:
            raise SimError(f"the arm scene's arm is (theta_a, omega_a, theta_b, omega_b), got {arm}")
        self.place(*arm)

    def place(self, theta_a: float, omega_a: float, theta_b: float, omega_b: float) -> None:
        """Put the arm at joint angles (rad) moving at joint velocities (rad/s), in a fresh space."""
        q = tuple(float(v) for v in (theta_a, omega_a, theta_b, omega_b))
        if not all(math.isfinite(v) for v in q) or max(abs(q[1]), abs(q[3])) > W.OMEGA_HARD:
            raise SimError(f"invalid arm state {q}: finite values and joint speeds <= {W.OMEGA_HARD} rad/s")
        theta_a, omega_a, theta_b, omega_b = q
        self.space = space = pymunk.Space()
        la, lb = W.LINK_A_LENGTH, W.LINK_B_LENGTH
        self.link_a = a = pymunk.Body(W.LINK_A_MASS, W.LINK_A_MASS * la * la / 12.0)
        self.link_b = b = pymunk.Body(W.LINK_B_MASS, W.LINK_B_MASS * lb * lb / 12.0)
        ex, ey = W.elbow(theta_a)
        phi_b, w_b = theta_a + theta_b, omega_a + omega_b
        a.angle, a.angular_velocity = theta_a, omega_a
        a.position = (0.5 * ex, 0.5 * ey)
        a.velocity = (-omega_a * 0.5 * ey, omega_a * 0.5 * ex)
        rbx, rby = 0.5 * lb * math.cos(phi_b), 0.5 * lb * math.sin(phi_b)
        b.angle, b.angular_velocity = phi_b, w_b
        b.position = (ex + rbx, ey + rby)
        b.velocity = (-omega_a * ey - w_b * rby, omega_a * ex + w_b * rbx)
        # SimpleMotor(p, q, rate) holds p.w - q.w = rate, so a joint turning at omega needs rate -omega
        self.motor_a = pymunk.SimpleMotor(space.static_body, a, -omega_a)
        self.motor_b = pymunk.SimpleMotor(a, b, -omega_b)
        self.motor_a.max_force, self.motor_b.max_force = W.TORQUE_A_MAX, W.TORQUE_B_MAX
        space.add(a, b, self.motor_a, self.motor_b,
                  pymunk.PivotJoint(space.static_body, a, (0.0, 0.0), (-0.5 * la, 0.0)),
                  pymunk.PivotJoint(a, b, (0.5 * la, 0.0), (-0.5 * lb, 0.0)))
        self.time = 0.0

    def true_state(self) -> tuple[float, float, float, float, float, float]:
        """(theta_a, omega_a, theta_b, omega_b, tip_x, tip_y) of the arm as it is."""
        a, b = self.link_a, self.link_b
        theta_a, omega_a = a.angle, a.angular_velocity
        theta_b, omega_b = b.angle - theta_a, b.angular_velocity - omega_a
        return (theta_a, omega_a, theta_b, omega_b, *W.forward(theta_a, theta_b))

    def observe(self, action: str) -> tuple[float, float, float, float]:
        """The observed parameters of `action` (theta_a, omega_a, theta_b, omega_b) measured now: exactly what
        `run` of it logs first in Episode.params. It draws the noise row that run will measure its start with
        and keeps it for run (consuming nothing: a closed loop that observes stays on the open loop's noise
        stream); the simulation does not advance."""
        if action not in ACTIONS:
            raise SimError(f"unknown arm action {action!r}; known: {', '.join(ACTIONS)}")
        return self._believe(self.true_state(), self._noise.peek())

    def scene(self) -> dict[str, tuple[float, ...]]:
        """The scene measured now, in reset's form: {"arm": observe("reach")} (no further draw)."""
        return {"arm": self.observe("reach")}

    def _kick(self, kick: tuple[float, float]) -> None:
        """Add joint velocities (rad/s) to the links, keeping them rigid about the shoulder and the elbow."""
        a, b = self.link_a, self.link_b
        ka, kb = kick
        ex, ey = W.elbow(a.angle)
        (ax, ay), (bx, by) = a.position, b.position
        a.angular_velocity += ka
        a.velocity += (-ka * ay, ka * ax)
        b.angular_velocity += ka + kb
        b.velocity += (-ka * by - kb * (by - ey), ka * bx + kb * (bx - ex))

    def _strike(self, ticks: int) -> None:
        """The "bump" disturbance strikes now, `ticks` control periods into the running reach."""
        _, moment, kick = self._bump
        self._bump = None
        self._kick(kick)
        self.events.append(Bump(kick, self.time, ticks / CONTROL_HZ, self._reach_ticks / CONTROL_HZ, moment,
                                BUMP_WINDOW))

    def _believe(self, true: Sequence[float], e: Sequence[float]) -> tuple[float, float, float, float]:
        n = self.noise
        return (true[0] + n.angle * e[0], true[1] + n.velocity * e[1], true[2] + n.angle * e[2],
                true[3] + n.velocity * e[3])

    def believed_state(self) -> tuple[float, float, float, float, float, float]:
        """The true state with the seeded sensing noise of `self.noise` (the tip from the believed angles)."""
        q = self._believe(self.true_state(), self._noise.next())
        return (*q, *W.forward(q[0], q[2]))

    # --- dynamics ---------------------------------------------------------------------------------------
    def command(self, omega_a: float, omega_b: float, e: Sequence[float] = (0.0, 0.0)) -> None:
        """Send joint rates (rad/s); the motors execute them with relative noise e * motor, saturated."""
        m, hard = self.noise.motor, W.OMEGA_HARD
        self.motor_a.rate = -max(-hard, min(hard, omega_a * (1.0 + m * e[0])))
        self.motor_b.rate = -max(-hard, min(hard, omega_b * (1.0 + m * e[1])))

    def step(self) -> None:
        """One physics step."""
        self.space.step(DT)
        self.time += DT

    # --- actions ----------------------------------------------------------------------------------------
    def run(self, call: ActionCall) -> Episode:
        """Execute one reach from the current state until it ends; the Episode logs the believed state."""
        return self._execute(call, None)

    def run_sequence(self, calls: Sequence[ActionCall]) -> SequenceResult:
        """Dispatch reaches back to back without stopping (each passes its way-point at the goal velocities);
        stop at the first failure."""
        self._next_sample = self.time
        return run_in_sequence(self._execute, calls, lambda: self.time, TRAJECTORY_COLUMNS)

    def _execute(self, call: ActionCall, trajectory: list | None) -> Episode:
        goal = _check_call(call)
        ga, gwa, gb, gwb = goal
        lo_a, hi_a = W.THETA_A_LIMITS
        lo_b, hi_b = W.THETA_B_LIMITS
        ticks, max_ticks = 0, round(TIMEOUT * CONTROL_HZ)
        log_t, log_state = [], []
        params = None
        outcome = "timeout"
        plan_tick, pa, pb = 0, None, None
        ia = ib = 0.0  # integrated position errors
        work = 0.0  # twice the motors' work so far (the energy measure, module doc)
        while True:
            true = self.true_state()
            if trajectory is not None and self.time >= self._next_sample - 1e-9:
                trajectory.append((self.time, *true))
                self._next_sample += 1.0 / LOG_HZ
            e = self._noise.next()
            ta, wa, tb, wb = self._believe(true, e)
            if params is None:
                params = np.array([ta, wa, tb, wb, *goal], dtype=float)
            if ticks % CONTROLS_PER_LOG == 0:
                log_t.append(ticks / CONTROL_HZ)
                log_state.append((ta, wa, tb, wb, *W.forward(ta, tb)))
            if not (lo_a <= true[0] <= hi_a and lo_b <= true[2] <= hi_b):
                outcome = "joint_limit"
                break
            if (abs(true[0] - ga) <= ANGLE_TOL and abs(true[2] - gb) <= ANGLE_TOL
                    and abs(true[1] - gwa) <= SPEED_TOL and abs(true[3] - gwb) <= SPEED_TOL):
                outcome = "success"
                break
            if ticks >= max_ticks:
                break
            t = (ticks - plan_tick) * DT_CONTROL
            if pa is None or t > pa.duration + REPLAN_AFTER:
                pa, pb = synchronize(((ta, wa), (tb, wb)), ((ga, gwa), (gb, gwb)), W.OMEGA_MAX,
                                     self.alpha_max)
                plan_tick, t, ia, ib = ticks, 0.0, 0.0, 0.0
            ra, rwa = pa.at(t)
            rb, rwb = pb.at(t)
            na, nb = pa.at(t + DT_CONTROL)[0], pb.at(t + DT_CONTROL)[0]
            ea, eb = ra - ta, rb - tb
            ia = max(-INTEGRAL_LIMIT, min(INTEGRAL_LIMIT, ia + ea * DT_CONTROL))
            ib = max(-INTEGRAL_LIMIT, min(INTEGRAL_LIMIT, ib + eb * DT_CONTROL))
            self.command((na - ra) * CONTROL_HZ + KP * ea + KI * ia + KD * (rwa - wa),
                         (nb - rb) * CONTROL_HZ + KP * eb + KI * ib + KD * (rwb - wb), e[4:])
            if self._bump is not None and self._reach_ticks >= self._bump[0]:  # during this control period
                self._strike(ticks)
            self._reach_ticks += 1
            work += self._steps(STEPS_PER_CONTROL)
            self.time += DT_CONTROL
            ticks += 1
        x, y = self.true_state()[4:]
        gx, gy = W.forward(ga, gb)
        measures = {ENERGY: 0.5 * work, ERROR: math.hypot(x - gx, y - gy)}
        return Episode(call.action, params, np.array(log_t), np.array(log_state, dtype=float).reshape(-1, 6),
                       STATE_COLUMNS, outcome, ticks / CONTROL_HZ, self.seed, measures)

    def _steps(self, steps: int) -> float:
        """`steps` physics steps; twice the joint motors' work in them, sum of |j| |w0 + w1| (module doc)."""
        a, b, motor_a, motor_b, space = self.link_a, self.link_b, self.motor_a, self.motor_b, self.space
        work = 0.0
        wa0 = _angular_velocity(a)
        wb0 = _angular_velocity(b) - wa0
        for _ in range(steps):
            space.step(DT)
            wa1 = _angular_velocity(a)
            wb1 = _angular_velocity(b) - wa1
            work += abs(_impulse(motor_a) * (wa0 + wa1)) + abs(_impulse(motor_b) * (wb0 + wb1))
            wa0, wb0 = wa1, wb1
        return work


def _check_call(call: ActionCall) -> tuple[float, float, float, float]:
    """The goal of a reach call as 4 floats; a SimError for an unknown action or an invalid goal."""
    if call.action not in ACTIONS:
        raise SimError(f"unknown arm action {call.action!r}; known: {', '.join(ACTIONS)}")
    if len(call.goal) != 4:
        raise SimError(f"reach: goal must be 4 numbers (theta_ga, omega_ga, theta_gb, omega_gb), "
                       f"got {call.goal}")
    goal = tuple(float(g) for g in call.goal)
    if not all(math.isfinite(g) for g in goal):
        raise SimError(f"reach: goal must be finite, got {call.goal}")
    if max(abs(goal[1]), abs(goal[3])) > W.OMEGA_MAX + 1e-6:
        raise SimError(f"reach: goal joint speeds must be <= {W.OMEGA_MAX} rad/s, got {call.goal}")
    return goal  # type: ignore[return-value]


def simulate_sequence(arm: tuple[float, float, float, float], calls: Sequence[ActionCall], seed: int,
                      noise: Noise | None = None, disturbance: str | None = None,
                      variant: str | None = None) -> SequenceResult:
    """Execute reaches in a fresh simulator: place the arm at `arm`, then run_sequence."""
    sim = ArmSim(seed, Noise() if noise is None else noise, disturbance, variant)
    sim.place(*arm)
    return sim.run_sequence(list(calls))
