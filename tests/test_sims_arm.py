"""Arm simulator: ramp profiles and kinematics against hand computation, reach physics, the protocol,
outcomes, determinism, the letters and their bundled problem and belief files."""

import math
from itertools import pairwise

import numpy as np
import pytest

from tailor.sims import registry
from tailor.sims.arm import SIMULATOR, ArmSim, Noise, simulate_sequence
from tailor.sims.arm import profile as P
from tailor.sims.arm import simulator as S
from tailor.sims.arm import world as W
from tailor.sims.arm.letters import LETTERS, PROBLEMS_DIR, STROKE_STEP, letter_points, problem_files
from tailor.sims.arm.scenarios import letters, run_reach, subgoal_episode
from tailor.sims.episode import ActionCall
from tailor.errors import SimError
from tailor.sims.experience import episode_seeds, run_episode
from tailor.sims.protocol import Simulator

V, A = W.OMEGA_MAX, W.ALPHA_MAX  # 1 rad/s, 2 rad/s^2


# --- profiles ---------------------------------------------------------------------------------------------
def _ends_at(p, xg, vg, tol=1e-6):
    x, v = p.at(p.duration)
    return abs(x - xg) <= tol and abs(v - vg) <= tol


@pytest.mark.parametrize("x0, v0, xg, vg, expected", [
    (0.0, 0.0, 2.0, 0.0, 2.0 / V + V / A),  # rest to rest, d >= v^2/a: trapezoid d/v + v/a = 2.5 s
    (1.0, 0.0, -1.0, 0.0, 2.5),  # the same backwards
    (0.0, 0.0, 0.3, 0.0, 2.0 * math.sqrt(0.3 / A)),  # d < v^2/a: triangle 2 sqrt(d/a)
    (0.0, 1.0, 0.25, 0.0, 0.5),  # braking exactly: v^2/2a = 0.25 rad in v/a = 0.5 s
    (0.0, 0.0, 1.0, 1.0, 0.5 + 0.75),  # accelerate 0.5 s (0.25 rad), cruise the other 0.75 rad at v
    # moving away: brake 0.5 s to 0.25 rad, then the 0.25 rad triangle back, 2 sqrt(0.25/a)
    (0.0, 1.0, 0.0, 0.0, 0.5 + 2.0 * math.sqrt(0.25 / A)),
    # goal velocity pointing back: overshoot to 0.125 rad at peak sqrt(1/2) and return at -1 rad/s
    (0.0, 0.0, 0.0, -1.0, math.sqrt(0.5) / A + (math.sqrt(0.5) + 1.0) / A),
])
def test_optimal_ramp_durations_by_hand(x0, v0, xg, vg, expected):
    p = P.optimal(x0, v0, xg, vg, V, A)
    assert p.duration == pytest.approx(expected, abs=1e-9)
    assert _ends_at(p, xg, vg)


def test_optimal_is_no_slower_than_any_ramp_of_the_family_and_respects_the_limits():
    rng = np.random.default_rng(0)
    for _ in range(200):
        x0, xg = rng.uniform(-2.5, 2.5, 2)
        v0, vg = rng.uniform(-V, V, 2)
        p = P.optimal(x0, v0, xg, vg, V, A)
        assert _ends_at(p, xg, vg)
        grid = [q.duration for vc in np.linspace(-V, V, 201) if (q := P._make(x0, v0, xg, vg, float(vc), A))]
        assert p.duration <= min(grid) + 1e-9
        for t in np.linspace(0.0, p.duration, 50):
            assert abs(p.at(t)[1]) <= V + 1e-9
        assert abs(p.a1) == A and abs(p.a3) == A


def test_stretched_rest_to_rest_cruises_slower():
    # T = d/vc + vc/a  =>  vc = (aT - sqrt(a^2 T^2 - 4ad)) / 2
    p = P.stretched(0.0, 0.0, 1.0, 0.0, 3.0, V, A)
    assert p.duration == pytest.approx(3.0, abs=1e-9)
    assert p.vc == pytest.approx((A * 3.0 - math.sqrt(A * A * 9.0 - 4.0 * A)) / 2.0)
    assert _ends_at(p, 1.0, 0.0)


def test_stretching_into_a_gap_raises_the_common_duration():
    # moving at 1 rad/s with 0.1 rad to go and 1 rad/s at the goal: 0.1 s optimal, 0.106 s with no cruise;
    # anything slower needs a reversal at vc = -sqrt(0.8): t1 = t3 = (1 + sqrt(0.8)) / a
    assert P.stretched(0.0, 1.0, 0.1, 1.0, 1.0, V, A) is None
    reversal = 2.0 * (1.0 + math.sqrt(0.8)) / A
    assert P.feasible_after(0.0, 1.0, 0.1, 1.0, 1.0, V, A) == pytest.approx(reversal)
    pa, pb = P.synchronize([(0.0, 1.0), (0.0, 0.0)], [(0.1, 1.0), (0.5, 0.0)], V, A)  # b alone: 1.0 s
    assert pa.duration == pytest.approx(reversal) and pb.duration == pytest.approx(reversal)
    assert _ends_at(pa, 0.1, 1.0) and _ends_at(pb, 0.5, 0.0)


def test_synchronized_joints_start_and_end_together_at_their_goals():
    rng = np.random.default_rng(1)
    for _ in range(300):
        starts = [(float(rng.uniform(-2, 2)), float(rng.uniform(-V, V))) for _ in range(2)]
        goals = [(float(rng.uniform(-2, 2)), float(rng.uniform(-V, V))) for _ in range(2)]
        pa, pb = P.synchronize(starts, goals, V, A)
        slowest = max(P.optimal(*s, *g, V, A).duration for s, g in zip(starts, goals))
        assert pa.duration == pytest.approx(pb.duration, abs=1e-9) and pa.duration >= slowest - 1e-9
        assert _ends_at(pa, *goals[0]) and _ends_at(pb, *goals[1])


# --- kinematics -------------------------------------------------------------------------------------------
def test_forward_kinematics_of_known_angles():
    la, lb = W.LINK_A_LENGTH, W.LINK_B_LENGTH
    assert W.forward(0.0, 0.0) == pytest.approx((la + lb, 0.0))
    assert W.forward(math.pi / 2, 0.0) == pytest.approx((0.0, la + lb), abs=1e-12)
    assert W.forward(0.0, math.pi / 2) == pytest.approx((la, lb), abs=1e-12)
    assert W.forward(math.pi / 2, -math.pi / 2) == pytest.approx((lb, la), abs=1e-12)


def test_inverse_kinematics_round_trip_elbow_down_and_unreachable_points():
    rng = np.random.default_rng(2)
    for _ in range(200):
        a, b = float(rng.uniform(-2.0, 2.0)), float(rng.uniform(0.05, 2.5))
        x, y = W.forward(a, b)
        ia, ib = W.inverse(x, y)
        assert ib >= 0.0 and (ia, ib) == pytest.approx((a, b), abs=1e-9)
    with pytest.raises(SimError, match="cannot reach"):
        W.inverse(0.9, 0.0)
    with pytest.raises(SimError, match="cannot reach"):
        W.inverse(0.01, 0.0)


# --- reach physics ----------------------------------------------------------------------------------------
def test_one_joint_rest_to_rest_reach_takes_the_trapezoid_time():
    sim = ArmSim(0, Noise.off())
    sim.place(-1.0, 0.0, 0.5, 0.0)
    ep = sim.run(ActionCall("reach", (1.0, 0.0, 0.5, 0.0)))
    assert ep.outcome == "success"
    assert ep.duration == pytest.approx(2.0 / V + V / A, abs=0.06)
    ta, wa, tb, _, *_ = sim.true_state()
    assert abs(ta - 1.0) <= S.ANGLE_TOL and abs(tb - 0.5) <= S.ANGLE_TOL and abs(wa) <= S.SPEED_TOL


def test_both_joints_track_their_synchronized_ramps():
    call = ActionCall("reach", (2.0, 0.0, 0.5, 0.0))
    result = simulate_sequence((0.0, 0.0, 0.0, 0.0), [call], 0, Noise.off())
    assert result.succeeded and result.duration == pytest.approx(2.5, abs=0.06)
    pa, pb = P.synchronize([(0.0, 0.0), (0.0, 0.0)], [(2.0, 0.0), (0.5, 0.0)], V, A)
    assert pb.vc == pytest.approx((A * 2.5 - math.sqrt((A * 2.5) ** 2 - 4.0 * A * 0.5)) / 2.0)  # stretched
    for t, theta_a, theta_b in zip(result.column("t"), result.column("theta_a"), result.column("theta_b")):
        assert theta_a == pytest.approx(pa.at(t)[0], abs=0.01)
        assert theta_b == pytest.approx(pb.at(t)[0], abs=0.01)
    half = np.argmin(np.abs(result.column("t") - 1.25))
    assert result.column("theta_a")[half] == pytest.approx(0.95, abs=0.01)  # at 1.2 s: 0.25 + 0.7 rad
    assert np.abs(result.column("omega_a")).max() <= V + 0.05
    x, y = W.forward(result.column("theta_a")[-1], result.column("theta_b")[-1])
    assert (result.column("tip_x")[-1], result.column("tip_y")[-1]) == pytest.approx((x, y))


def test_a_reach_passes_its_goal_at_the_goal_velocity_and_the_next_starts_from_there():
    sim = ArmSim(3)
    sim.place(-0.5, 0.0, 1.0, 0.0)
    first = sim.run(ActionCall("reach", (0.3, 0.6, 1.4, -0.4)))
    second = sim.run(ActionCall("reach", (0.8, 0.0, 0.9, 0.0)))
    assert first.succeeded and second.succeeded
    assert second.params[:4] == pytest.approx([0.3, 0.6, 1.4, -0.4], abs=0.15)


def test_episode_logs_believed_state_at_10_hz_and_params_are_start_and_goal():
    sim = ArmSim(4)
    sim.place(0.2, 0.3, -0.4, 0.0)
    goal = (1.2, 0.0, 0.4, 0.5)
    ep = sim.run(ActionCall("reach", goal))
    assert ep.succeeded and ep.columns == S.STATE_COLUMNS
    np.testing.assert_allclose(ep.t, np.arange(len(ep.t)) / S.LOG_HZ)
    assert ep.t[-1] <= ep.duration < ep.t[-1] + 1.0 / S.LOG_HZ
    assert ep.params.shape == (8,) and tuple(ep.params[4:]) == goal
    np.testing.assert_allclose(ep.params[:4], (0.2, 0.3, -0.4, 0.0), atol=0.05)
    assert not np.array_equal(ep.params[:4], (0.2, 0.3, -0.4, 0.0))  # believed, with sensing noise
    np.testing.assert_array_equal(ep.state[0, :4], ep.params[:4])


# --- outcomes and errors ----------------------------------------------------------------------------------
def test_failures_are_outcomes():
    sim = ArmSim(5)
    sim.place(W.THETA_A_LIMITS[1] - 0.1, V, 0.0, 0.0)  # cannot brake within 0.1 rad from 1 rad/s
    assert sim.run(ActionCall("reach", (0.0, 0.0, 0.0, 0.0))).outcome == "joint_limit"
    calls = [ActionCall("reach", (W.THETA_A_LIMITS[1], 0.0, 0.0, 0.0)),  # at the limit: overshoots it
             ActionCall("reach", (0.0, 0.0, 0.0, 0.0))]
    result = simulate_sequence((1.0, 0.0, 0.0, 0.0), calls, 6)
    assert [r.outcome for r in result.results] == ["joint_limit"] and not result.succeeded


def test_timeout_is_an_outcome(monkeypatch):
    monkeypatch.setattr(S, "TIMEOUT", 0.5)
    sim = ArmSim(7)
    ep = sim.run(ActionCall("reach", (2.0, 0.0, 0.0, 0.0)))
    assert ep.outcome == "timeout" and ep.duration == pytest.approx(0.5)


@pytest.mark.parametrize("call, match", [
    (ActionCall("grip", (0.0, 0.0, 0.0, 0.0)), "unknown arm action"),
    (ActionCall("reach", (0.0, 0.0, 0.0)), "4 numbers"),
    (ActionCall("reach", (0.0, math.nan, 0.0, 0.0)), "finite"),
    (ActionCall("reach", (0.0, 2.0, 0.0, 0.0)), "joint speeds"),
])
def test_invalid_calls_are_sim_errors(call, match):
    with pytest.raises(SimError, match=match):
        ArmSim(0).run(call)


def test_invalid_scenes_are_sim_errors():
    sim = ArmSim(0)
    with pytest.raises(SimError, match="one object"):
        sim.reset({"robot": (0.0, 0.0, 0.0, 0.0)})
    with pytest.raises(SimError, match="theta_a, omega_a"):
        sim.reset({"arm": (0.0, 0.0)})
    with pytest.raises(SimError, match="finite"):
        sim.place(math.inf, 0.0, 0.0, 0.0)


# --- protocol, registry, determinism ------------------------------------------------------------------------
def test_follows_the_simulator_protocol_and_registers():
    registry.register(SIMULATOR, replace=True)
    entry = registry.get("arm")
    sim = entry.create(0)
    assert isinstance(sim, Simulator) and sim.state_columns == S.STATE_COLUMNS
    sim.reset({"arm": (0.0, 0.0, 1.0, 0.0)})
    assert entry.action("reach").parameters == ("theta_a", "omega_a", "theta_b", "omega_b",
                                                "theta_ga", "omega_ga", "theta_gb", "omega_gb")
    assert run_episode("arm", "reach", 12).action == "reach"
    assert set(entry.views[0]) <= set(sim.state_columns)


def test_same_seed_same_episode_bit_for_bit():
    for seed in (0, 99):
        a, b = run_reach(seed), run_reach(seed)
        assert a.outcome == b.outcome and a.duration == b.duration
        np.testing.assert_array_equal(a.params, b.params)
        np.testing.assert_array_equal(a.state, b.state)
    assert not np.array_equal(run_reach(0).params, run_reach(1).params)


def test_random_reaches_mostly_succeed_in_about_three_seconds():
    episodes = [run_reach(s) for s in episode_seeds(21, 60)]
    ok = [e.duration for e in episodes if e.succeeded]
    assert len(ok) >= 52
    assert {e.outcome for e in episodes} <= {"success", "joint_limit"}
    assert 2.0 <= np.mean(ok) <= 4.0


def test_subgoal_episode_starts_from_the_given_parameters():
    params = np.array([0.0, 0.2, 1.0, -0.2, 0.6, 0.3, 1.5, 0.0])
    ep = subgoal_episode("reach", params, 3)
    assert ep.succeeded
    np.testing.assert_allclose(ep.params, params, atol=0.05)


# --- letters ----------------------------------------------------------------------------------------------
def test_random_letters_are_within_reach():
    rng = np.random.default_rng(8)
    for _ in range(40):
        name, objects = letters(rng)
        n = len(objects)
        assert name == f"stroke-{n}" and 4 <= n <= 6 and list(objects) == [f"p{k}" for k in range(1, n + 1)]
        assert objects["p1"]["omega_a"] == 0.0 and objects["p1"]["omega_b"] == 0.0
        assert all(set(v) == {"theta_a", "theta_b"} for k, v in objects.items() if k != "p1")
        tips = [W.forward(v["theta_a"], v["theta_b"]) for v in objects.values()]
        assert all(W.within_limits(v["theta_a"], v["theta_b"], margin=0.1) for v in objects.values())
        steps = [math.dist(p, q) for p, q in pairwise(tips)]
        assert STROKE_STEP[0] - 1e-9 <= min(steps) and max(steps) <= STROKE_STEP[1] + 1e-9


def test_bundled_letters_are_drawn():
    for name in LETTERS:
        points = letter_points(name)
        joints = [W.inverse(*p) for p in points]
        assert all(W.within_limits(a, b, margin=0.1) for a, b in joints)
        calls = [ActionCall("reach", (a, 0.0, b, 0.0)) for a, b in joints[1:]]
        result = simulate_sequence((joints[0][0], 0.0, joints[0][1], 0.0), calls, 0)
        assert result.succeeded and len(result.results) == len(points) - 1, name


def test_problem_and_belief_files_are_what_letters_py_writes():
    files = problem_files()
    assert {f"{name}.{ext}" for name in LETTERS for ext in ("pddl", "toml")} <= set(files)
    assert {"stroke-4.toml", "stroke-5.toml", "stroke-6.toml"} <= set(files)
    for name, text in files.items():
        assert (PROBLEMS_DIR / name).read_text() == text, name


def test_problems_parse_with_the_domain():
    domain = PROBLEMS_DIR.parent / "domain.pddl"
    if "(rest " not in domain.read_text():
        pytest.skip("domain.pddl does not declare (rest ?p) yet")
    from unified_planning.io import PDDLReader

    for path in sorted(PROBLEMS_DIR.glob("*.pddl")):
        problem = PDDLReader().parse_problem(str(domain), str(path))
        assert len(problem.all_objects) >= 4
