"""Issue 33, items 3, 7, 11 and 12: hostile inputs end in one line with the README's status, within seconds and
with nothing written; the API raises a TailorError for them. Every read is bounded (regular files only, checked
before opening; size; nesting; digits; the sizes an array declares before it is allocated); PDDL that
unified-planning reads but no installed planner supports is "unsupported", a cyclic type hierarchy is named
at its place; control characters in a message are escaped.

Cases that hung or filled the memory before run in a child process with a time and an address-space limit."""

from __future__ import annotations

import contextlib
import io
import os
import re
import resource
import shutil
import subprocess
import sys
import threading
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

import tailor
from tailor.cli.main import main
from tailor.errors import BeliefError, PDDLSemanticError, PlannerUnavailableError
from tailor.planner_bridge.bundled import DOMAINS_DIR

SOCCER = DOMAINS_DIR / "soccer"
ONE_ERROR_LINE = re.compile(r"^tailor \w+: error: [^\x00-\x1f\x7f]+$")
LIMIT_S = 5.0
FIFO = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes")


def one_line(err: str) -> str:
    """The single line of stderr that is not a note: a `tailor CMD: error: ...` line without control characters."""
    lines = [line for line in err.strip().splitlines() if ": note: " not in line]
    assert len(lines) == 1 and ONE_ERROR_LINE.match(lines[0]), err
    return lines[0]


def _limits() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (4 * 2**30, 4 * 2**30))  # an unbounded read ends in MemoryError


def run_tailor(*args: str, timeout: float = 30) -> tuple[int, str, float]:
    """Status, stderr and seconds of `tailor ARGS` in a child process (4 GB of address space at most)."""
    started = time.monotonic()
    try:
        done = subprocess.run([sys.executable, "-m", "tailor.cli", *map(str, args)], capture_output=True, text=True,
                              timeout=timeout, preexec_fn=_limits, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        pytest.fail(f"`tailor {' '.join(map(str, args))}` still ran after {timeout} s")
    return done.returncode, done.stderr, time.monotonic() - started


@contextlib.contextmanager
def bounded_memory():
    """At most 2 GB more address space for this process within the block: where a read is unbounded (as it was
    before issue 33), the block fails the test with MemoryError instead of taking the machine's memory."""
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    size = int(Path("/proc/self/status").read_text().split("VmSize:")[1].split()[0]) * 1024
    bound = size + 2 * 2**30 if hard == resource.RLIM_INFINITY else min(hard, size + 2 * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (bound, hard))
    try:
        yield
    except MemoryError:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))
        pytest.fail("the read is unbounded: MemoryError")
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


@pytest.fixture
def soccer(tmp_path) -> Path:
    domain = tmp_path / "soccer"
    shutil.copytree(SOCCER, domain, ignore=shutil.ignore_patterns("training"))
    return domain


# --- 3. TOML: nesting, dotted keys, digits, numbers no float holds -------------------------------------------
HOSTILE_TOML = {
    "lists nested 100,000 deep": ("[objects.pos1]\nx = " + "[" * 100_000 + "]" * 100_000 + "\n",
                                  "nested deeper than 32 levels"),
    "inline tables nested 100,000 deep": ("[objects.pos1]\nx = " + "{a = " * 100_000 + "1" + "}" * 100_000 + "\n",
                                          "nested deeper than 32 levels"),
    "a dotted key of 100,000 parts": ("objects" + ".a" * 100_000 + " = 1\n", "a dotted key of more than 32 parts"),
    "a 5,000-digit integer": ("[objects.pos1]\nx = " + "9" * 5000 + "\n", "outside TOML's 64-bit range"),
    "10**400": ("[objects.pos1]\nx = 1" + "0" * 400 + "\n", "objects.pos1.x is an integer outside TOML's 64-bit"),
}


@pytest.mark.parametrize("case", sorted(HOSTILE_TOML))
def test_a_hostile_belief_file_is_one_line(case, tmp_path, capsys):
    text, said = HOSTILE_TOML[case]
    belief = tmp_path / "belief.toml"
    belief.write_text(text)
    started = time.monotonic()
    with bounded_memory():
        status = main(["refine", "soccer", "score", "--belief", str(belief)])
    assert status == 10 and time.monotonic() - started < LIMIT_S
    line = one_line(capsys.readouterr().err)
    assert line.startswith(f"tailor refine: error: {belief}") and said in line
    with bounded_memory(), pytest.raises(BeliefError, match=re.escape(said)):  # the API: a TailorError
        tailor.refine("soccer", "score", belief=belief)


@pytest.mark.parametrize("case", sorted(HOSTILE_TOML))
def test_a_hostile_binding_is_one_line(case, soccer, capsys):
    text, said = HOSTILE_TOML[case]
    binding = soccer / "actions.toml"
    binding.write_text(binding.read_text() + "\n[hostile]\n" + text.replace("[objects.pos1]\n", ""))
    with bounded_memory():
        status = main(["refine", str(soccer / "domain.pddl"), "score"])
    assert status == 11
    line = one_line(capsys.readouterr().err)
    assert line.startswith(f"tailor refine: error: {binding}") and said.split(".")[-1].split()[0] in line


def test_a_toml_file_of_ordinary_nesting_still_reads(tmp_path):
    from tailor.refinement.binding import read_toml

    text = ('a.b.c = [1, [2, [3, {d = 4, e = "[[[{{{..."}]]]\n'
            's = """x.y.z [[[ \\""" {{{"""\n'
            "t = '''a.b.c.d ]]]'''\n"
            'big = 9223372036854775807\nsmall = -9223372036854775808\nf = 1.5e300\n# [[[[ . . . \n')
    (tmp_path / "ok.toml").write_text(text)
    data = read_toml(tmp_path / "ok.toml", BeliefError, "belief state")
    assert data["a"]["b"]["c"] == [1, [2, [3, {"d": 4, "e": "[[[{{{..."}]]] and data["big"] == 2**63 - 1


def test_a_belief_value_no_float_holds_is_a_belief_error():
    table = {"pos1": {"x": 10**400, "y": 1.0}}
    with pytest.raises(BeliefError, match=r"<belief argument>: \[objects.pos1\] x = an integer of \d+ bits is not a "
                                          r"finite number"):
        tailor.refine("soccer", "score", belief=table)
    with pytest.raises(BeliefError, match="integer of"):  # (Python will not even print 10**5000)
        tailor.refine("soccer", "score", belief={"pos1": {"x": 10**5000}})
    with pytest.raises(tailor.ArgumentValueError, match="timeout"):
        tailor.plan("soccer", "score", timeout=10**400)


# --- 3 and 7: regular files only, of bounded size; a FIFO or /dev/zero never blocks --------------------------
@FIFO
def test_a_belief_fifo_or_dev_zero_is_one_line_at_once(tmp_path):
    fifo = tmp_path / "belief.toml"
    os.mkfifo(fifo)
    for belief in (fifo, Path("/dev/zero")):
        status, err, seconds = run_tailor("refine", "soccer", "score", "--belief", belief)
        assert status == 10 and seconds < LIMIT_S + 5  # (the child's start-up included)
        assert one_line(err) == (f"tailor refine: error: {belief}: not a regular file ("
                                 f"{'a named pipe' if belief == fifo else 'a device'}): inputs are read from "
                                 "regular files only")


@FIFO
def test_a_fifo_named_like_a_model_file_is_one_line_at_once(tmp_path):
    models = tmp_path / "models"
    shutil.copytree(SOCCER / "models", models)
    os.mkfifo(models / "waiting.json")
    status, err, _ = run_tailor("refine", "soccer", "score", "--models", models)
    assert status == 12
    assert one_line(err).startswith(f"tailor refine: error: {models / 'waiting.json'}: not a regular file")


@FIFO
def test_a_pddl_fifo_and_a_huge_pddl_file_are_input_errors(tmp_path, capsys):
    fifo = tmp_path / "domain.pddl"
    os.mkfifo(fifo)
    huge = tmp_path / "problem.pddl"
    with open(huge, "wb") as file:  # sparse: 100 MB that take no room
        file.truncate(100 * 2**20)
    for args, said in (([fifo, SOCCER / "problems" / "score.pddl"], f"{fifo}: not a "),
                       ([SOCCER / "domain.pddl", huge], f"{huge}: too large to read ({100 * 2**20} bytes; at most")):
        started = time.monotonic()
        assert main(["plan", *map(str, args)]) == 3
        assert time.monotonic() - started < LIMIT_S
        assert one_line(capsys.readouterr().err).startswith(f"tailor plan: error: {said}")


def _member(array: np.ndarray, shape: tuple | None = None) -> bytes:
    """An .npy member holding `array`, its header declaring `shape` (default: the array's own)."""
    data = io.BytesIO()
    np.lib.format.write_array_header_1_0(data, {"descr": array.dtype.str, "fortran_order": False,
                                                 "shape": array.shape if shape is None else shape})
    return data.getvalue() + array.tobytes()


def test_an_episode_file_declaring_ten_billion_values_is_a_data_error(tmp_path):
    """Its header claims 10**10 values (numpy would first allocate 75 GiB): exit 14 before anything is allocated."""
    experience, out = tmp_path / "experience", tmp_path / "out"
    experience.mkdir()
    arrays = dict(schema=np.array(3), action=np.array(["goToPosition"]), params=np.zeros((1, 3)),
                  outcome=np.array(["success"]), duration=np.ones(1), seed=np.zeros(1, np.int64),
                  offsets=np.array([0, 2], np.int64), t=np.zeros(2), state=np.zeros((2, 1)), columns=np.array(["x"]))
    shard = experience / "goToPosition.seed0.0-8.npz"
    with zipfile.ZipFile(shard, "w", zipfile.ZIP_DEFLATED) as archive:
        for key, array in arrays.items():
            archive.writestr(f"{key}.npy", _member(array, (10**10,) if key == "t" else None))
    status, err, _ = run_tailor("train", "soccer", "--only", "goToPosition", "--episodes", "8", "--jobs", "1",
                                "--experience", experience, "--out", out)
    assert status == 14
    assert one_line(err) == (f"tailor train: error: {shard}: its t.npy declares 10000000000 values of 8 bytes, but "
                             "holds 16 bytes")
    assert not (out / "models").exists()


def _unblock(fifo: Path) -> None:
    """Open and close the named pipe's writing end: a reader waiting on it reads the end of the file."""
    try:
        os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
    except OSError:  # no reader (any more)
        pass


@FIFO
def test_a_fifo_in_an_experience_folder_is_a_data_error_at_once(tmp_path):
    from tailor.errors import DataError
    from tailor.sims.experience import read_origin

    fifo = tmp_path / "goToPosition.seed0.0-8.npz"
    os.mkfifo(fifo)
    watchdog = threading.Timer(LIMIT_S, _unblock, (fifo,))
    watchdog.daemon = True
    watchdog.start()
    started = time.monotonic()
    try:
        with pytest.raises(DataError, match="not a regular file"):
            read_origin(fifo)
    finally:
        watchdog.cancel()
    assert time.monotonic() - started < LIMIT_S


# --- 11. PDDL that no installed planner supports, a cyclic type hierarchy ------------------------------------
DOORS = """(define (domain doors)
  (:requirements :strips :typing :timed-initial-literals)
  (:types room)
  (:predicates (open) (in ?r - room))
  (:action go :parameters (?a ?b - room) :precondition (and (in ?a) (open)) :effect (and (in ?b) (not (in ?a)))))
"""


def test_a_timed_initial_literal_is_unsupported_not_undefined(tmp_path, capsys):
    (tmp_path / "domain.pddl").write_text(DOORS)
    (tmp_path / "problem.pddl").write_text("(define (problem p) (:domain doors) (:objects a b - room)\n"
                                           "  (:init (in a) (open) (at 10 (not (open))))\n  (:goal (in b)))\n")
    assert main(["plan", str(tmp_path / "domain.pddl"), str(tmp_path / "problem.pddl")]) == 8
    line = one_line(capsys.readouterr().err)
    assert "cannot solve this problem" in line and "TIMED_EFFECTS" in line
    (tmp_path / "problem.pddl").write_text("(define (problem p) (:domain doors) (:objects a b - room)\n"
                                           "  (:init (in a) (open) (at 10 (not (shut))))\n  (:goal (in b)))\n")
    assert main(["plan", str(tmp_path / "domain.pddl"), str(tmp_path / "problem.pddl")]) == 5  # still checked
    assert "undefined predicate 'shut'" in one_line(capsys.readouterr().err)


@pytest.mark.parametrize("types, cycle", [("a - b b - c c - a", "a - b - c - a"), ("a - a", "a - a"),
                                          ("x - object a - b b - a", "a - b - a")])
def test_a_cyclic_type_hierarchy_is_named_at_its_place(types, cycle, tmp_path, capsys):
    domain = tmp_path / "domain.pddl"
    domain.write_text(f"(define (domain cyc)\n  (:requirements :strips :typing)\n  (:types {types})\n"
                      "  (:predicates (p ?x - a))\n  (:action go :parameters (?x - a) :precondition (p ?x) "
                      ":effect (not (p ?x))))\n")
    (tmp_path / "problem.pddl").write_text("(define (problem q) (:domain cyc) (:objects o - a) (:init (p o)) "
                                           "(:goal (not (p o))))\n")
    assert main(["plan", str(domain), str(tmp_path / "problem.pddl")]) == 5
    column = 11 + types.index(cycle[0] + " - ")
    assert one_line(capsys.readouterr().err) == (f"tailor plan: error: {domain}:3:{column}: the type hierarchy is "
                                                 f"cyclic: {cycle} (each a subtype of the next)")
    with pytest.raises(PDDLSemanticError, match="cyclic"):
        tailor.plan(domain, tmp_path / "problem.pddl")


def test_an_unsupported_problem_object_says_unsupported():
    from unified_planning.io import PDDLReader

    with pytest.raises(PlannerUnavailableError):
        tailor.plan(PDDLReader().parse_problem_string(DOORS, "(define (problem p) (:domain doors) (:objects a b - "
                                                      "room) (:init (in a) (open) (at 10 (not (open)))) "
                                                      "(:goal (in b)))"))


# --- 12. control characters in a message are escaped ---------------------------------------------------------
@pytest.mark.parametrize("name, shown", [("sc\nore", "sc\\nore"), ("sc\x1b[2Jore", "sc\\x1b[2Jore"),
                                         ("sc\u202eore", "sc\\u202eore")])
def test_control_characters_in_a_name_are_escaped(name, shown, capsys):
    assert main(["plan", "soccer", name]) == 3
    assert one_line(capsys.readouterr().err).startswith(f"tailor plan: error: {shown}: ")


def test_an_error_of_the_api_is_one_line_whatever_it_names():
    from unified_planning.shortcuts import BoolType, Fluent, Not, Problem

    problem = Problem("two\nlines\x1b[31m")
    fact = Fluent("fact", BoolType())
    problem.add_fluent(fact, default_initial_value=False)
    problem.add_goal(fact)
    problem.add_goal(Not(fact))
    with pytest.raises(tailor.TailorError) as caught:
        tailor.plan(problem)
    assert "\n" not in str(caught.value) and "\x1b" not in str(caught.value)
    assert str(caught.value).startswith("<problem two\\nlines\\x1b[31m>: ")
    assert caught.value.file == "<problem two\nlines\x1b[31m>"  # the fields keep what they name
