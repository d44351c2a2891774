"""Issue 33, items 1 and 4: the Python API from any thread. The session's planner process lives as long as the
Python process, not as long as the thread that started it; calls from several threads at once are served in
turn by that one process (serialised) and give what serial calls give; `tailor.plan(up_problem, timeout=...)`
keeps its timeout."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import tailor
from tailor.errors import NoPlanError, PlannerTimeoutError
from tailor.refinement import api

GOLDEN = Path(__file__).parent / "golden" / "plan"


def _golden(domain: str, problem: str) -> dict:
    data = json.loads((GOLDEN / domain / f"{problem}.json").read_text())
    return {k: v for k, v in data.items() if k not in ("schema", "units")}


def _live_children() -> set[int]:
    """This process's live (not zombie) child processes."""
    found = set()
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                state, ppid = (entry / "stat").read_text().rsplit(")", 1)[1].split()[:2]
            except OSError:
                continue
            if int(ppid) == os.getpid() and state != "Z":
                found.add(int(entry.name))
    return found


@pytest.fixture
def fresh_planner():
    """The session's planner process closed, so that the next call starts one (from the thread calling)."""
    if api._PLANNER is not None:
        api._PLANNER.close()
    yield


# --- 1. the planner process lives with the process, whichever thread started it -------------------------------
def test_threads_one_after_the_other_share_one_planner_process(fresh_planner):
    """Each thread plans and ends; the planner process the first one started serves all four (it died with
    the first thread: PR_SET_PDEATHSIG fires when the forking *thread* ends)."""
    results, pids = [], []

    def plan():
        results.append(tailor.plan("soccer", "score").to_json())
        pids.append(api._PLANNER._child.pid)

    for _ in range(4):
        thread = threading.Thread(target=plan)
        thread.start()
        thread.join()
    assert results == [_golden("soccer", "score")] * 4
    assert len(set(pids)) == 1


def test_threads_at_once_are_served_in_turn(fresh_planner):
    with ThreadPoolExecutor(4) as pool:
        plans = list(pool.map(lambda pair: tailor.plan(*pair).to_json(), [("soccer", "score"), ("arm", "letter-s")] * 3))
    assert plans == [_golden("soccer", "score"), _golden("arm", "letter-s")] * 3


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_the_planner_process_ends_with_the_python_process_not_with_a_thread(tmp_path):
    """A program plans in a thread that ends, plans again from its main thread (the same planner process),
    then is killed with SIGKILL (no handler, no atexit): its planner process goes too, within seconds."""
    script = textwrap.dedent("""
        import sys, threading, tailor
        from tailor.refinement import api
        thread = threading.Thread(target=lambda: tailor.plan("soccer", "score"))
        thread.start(); thread.join()
        first = api._PLANNER._child.pid
        tailor.plan("arm", "letter-s")
        print(first, api._PLANNER._child.pid, flush=True)
        sys.stdin.read()
    """)
    program = subprocess.Popen([sys.executable, "-c", script], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    try:
        line = program.stdout.readline()
        assert line, program.stderr.read()
        first, second = map(int, line.split())
        assert first == second
        program.kill()
        program.wait(10)
        deadline = time.monotonic() + 5
        while Path(f"/proc/{first}").exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not Path(f"/proc/{first}").exists() or "Z" in Path(f"/proc/{first}/stat").read_text().split()[2]
    finally:
        if program.poll() is None:
            program.kill()
            program.wait()


# --- the floor: N threads x M calls equal the serial results ---------------------------------------------------
CALLS = st.lists(st.one_of(st.tuples(st.just("plan"), st.sampled_from([("soccer", "score"), ("arm", "letter-s")])),
                           st.tuples(st.just("refine"), st.integers(0, 2**31))), min_size=2, max_size=4)


def _call(call):
    kind, argument = call
    if kind == "plan":
        return tailor.plan(*argument).to_json()
    # the genetic algorithm: its random draws are what threads could mix up (auto certifies this window,
    # deterministically and, on soccer's bounds, four times slower)
    refined = tailor.refine("soccer", "score", seed=argument, optimizer="ga")
    return refined.chosen, refined.predicted_total, refined.sequence.to_json()


@settings(max_examples=3, deadline=None)
@given(calls=CALLS, threads=st.integers(2, 3))
def test_threads_calling_plan_and_refine_at_once_give_the_serial_results(calls, threads):
    """The calls one after the other in a thread that then ends (it starts the session's planner process),
    then each of them `threads` times, from `threads` threads at once: the same results, no planner error."""
    if api._PLANNER is not None:
        api._PLANNER.close()
    with ThreadPoolExecutor(1) as one:
        serial = list(one.map(_call, calls))
    with ThreadPoolExecutor(threads) as pool:
        concurrent = list(pool.map(_call, calls * threads))
    assert concurrent == serial * threads


# --- 4. a unified-planning Problem under a timeout -------------------------------------------------------------
def _corridor(rooms: int):
    """A unified-planning Problem of `rooms` rooms in a row: unified-planning alone takes minutes over its
    kind (every fluent over every pair of rooms) before any engine starts."""
    from unified_planning.shortcuts import BoolType, Fluent, InstantaneousAction, Object, Problem, UserType

    room = UserType("room")
    at, door = Fluent("at", BoolType(), r=room), Fluent("door", BoolType(), a=room, b=room)
    go = InstantaneousAction("go", a=room, b=room)
    a, b = go.parameters
    go.add_precondition(at(a))
    go.add_precondition(door(a, b))
    go.add_effect(at(a), False)
    go.add_effect(at(b), True)
    problem = Problem("corridor")
    problem.add_fluent(at, default_initial_value=False)
    problem.add_fluent(door, default_initial_value=False)
    problem.add_action(go)
    objects = [Object(f"r{i}", room) for i in range(rooms)]
    problem.add_objects(objects)
    for here, there in zip(objects, objects[1:]):
        problem.set_initial_value(door(here, there), True)
    problem.set_initial_value(at(objects[0]), True)
    problem.add_goal(at(objects[3]))
    return problem


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_a_unified_planning_problem_keeps_its_timeout():
    problem = _corridor(5000)
    before = _live_children()
    started = time.monotonic()
    with pytest.raises(PlannerTimeoutError, match=r"<problem corridor>: .*within the timeout of 1 s"):
        tailor.plan(problem, timeout=1)
    assert time.monotonic() - started < 3
    assert _live_children() <= before  # the forked planner is gone


def test_a_timeout_plans_a_unified_planning_problem_as_without_one():
    small = _corridor(6)
    assert tailor.plan(small, timeout=30).to_json(facts=True) == tailor.plan(small).to_json(facts=True)
    with pytest.raises(tailor.TailorError, match="timeout"):
        tailor.plan(small, timeout=float("inf"))


def test_a_planner_error_under_a_timeout_is_the_planners_error():
    from unified_planning.shortcuts import Not

    problem = _corridor(4)
    problem.add_goal(Not(problem.fluent("at")(problem.object("r3"))))  # contradicts the goal at(r3)
    with pytest.raises(NoPlanError, match="no plan exists"):
        tailor.plan(problem, timeout=30)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_ctrl_c_while_a_problem_is_planned_under_a_timeout_leaves_no_process():
    problem = _corridor(5000)
    before = _live_children()
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            tailor.plan(problem, timeout=30)
    finally:
        timer.cancel()
    assert _live_children() <= before
