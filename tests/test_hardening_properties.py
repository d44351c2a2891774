"""Issue 11's property: mutated belief, binding and model files (truncated, bytes flipped, NaN / huge values /
unknown keys injected) end `tailor refine` with a status from the README's table and, when it fails, exactly
one stderr line naming the broken file's folder; nothing is written. The plan is computed once (the planner
is the planner side's to harden): each example costs only the refinement side's reading and checking."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from tailor.planner_bridge.bundled import DOMAINS_DIR
from tailor.cli.main import main

EXIT_STATUSES = Path(__file__).parent.parent / "docs" / "exit-statuses.md"  # the documented table
FILES = {"belief": "problems/score.toml", "binding": "actions.toml", "model": "models/approachBall.json",
         "model2": "models/dribbleBall.json"}
NUMBER = re.compile(rb"(?<![\w.])-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?(?![\w.])")
TOML_VALUES = [b"nan", b"inf", b"-inf", b"1e308", b"-1e6", b'"x"', b"[]", b"{}", b"true"]
JSON_VALUES = [b"NaN", b"Infinity", b"1e308", b"-1e6", b"1e300", b'"x"', b"[]", b"{}", b"null", b"true"]


def documented_statuses() -> set[int]:
    return {int(m) for m in re.findall(r"^\| (\d+) \|", EXIT_STATUSES.read_text(encoding="utf-8"), re.MULTILINE)}


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    """The soccer domain copied once, and its plan computed once."""
    from tailor.planner_bridge import plan_files

    domain = tmp_path_factory.mktemp("pristine") / "soccer"
    shutil.copytree(DOMAINS_DIR / "soccer", domain, ignore=shutil.ignore_patterns("training"))
    plan = plan_files(domain / "domain.pddl", domain / "problems" / "score.pddl")
    return domain, plan


def truncate(data: bytes, where: float) -> bytes:
    return data[: int(len(data) * where)]


def flip(data: bytes, where: float, byte: int) -> bytes:
    i = min(len(data) - 1, int(len(data) * where))
    return data[:i] + bytes([data[i] ^ byte]) + data[i + 1:]


def replace_number(data: bytes, which: int, value: bytes) -> bytes:
    numbers = list(NUMBER.finditer(data))
    if not numbers:
        return data
    m = numbers[which % len(numbers)]
    return data[: m.start()] + value + data[m.end():]


def unknown_key(data: bytes, which: int, is_json: bool) -> bytes:
    if is_json:
        places = [m.end() for m in re.finditer(rb"\{", data)]
        insert = b'"zzz_unknown": 1, '
    else:
        places = [m.end() for m in re.finditer(rb"^\[[^\]\n]+\]\n", data, re.MULTILINE)]
        insert = b"zzz_unknown = 1\n"
    if not places:
        return data
    i = places[which % len(places)]
    return data[:i] + insert + data[i:]


@st.composite
def mutations(draw):
    name = draw(st.sampled_from(sorted(FILES)))
    is_json = FILES[name].endswith(".json")
    kind = draw(st.sampled_from(["truncate", "flip", "number", "key"]))
    if kind == "truncate":
        args = (draw(st.floats(0.0, 0.99)),)
    elif kind == "flip":
        args = (draw(st.floats(0.0, 1.0)), draw(st.integers(1, 255)))
    elif kind == "number":
        args = (draw(st.integers(0, 10_000)), draw(st.sampled_from(JSON_VALUES if is_json else TOML_VALUES)))
    else:
        args = (draw(st.integers(0, 10_000)), is_json)
    return name, kind, args


def mutate(data: bytes, kind: str, args) -> bytes:
    return {"truncate": truncate, "flip": flip, "number": replace_number, "key": unknown_key}[kind](data, *args)


def listing(folder: Path) -> dict[str, int]:
    return {str(p.relative_to(folder)): p.stat().st_mtime_ns for p in sorted(folder.rglob("*"))}


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture],
          derandomize=True)
@given(mutation=mutations())
def test_mutated_inputs_end_in_one_documented_line(mutation, pristine, tmp_path_factory, monkeypatch, capsys):
    source, plan = pristine
    name, kind, args = mutation
    domain = tmp_path_factory.mktemp("mutated") / "soccer"
    shutil.copytree(source, domain)
    target = domain / FILES[name]
    target.write_bytes(mutate(target.read_bytes(), kind, args))
    before = listing(domain)
    monkeypatch.setattr("tailor.refinement.pipeline.plan_pddl", lambda *a, **k: plan)
    capsys.readouterr()
    status = main(["refine", str(domain / "domain.pddl"), "score", "--json"])
    captured = capsys.readouterr()
    assert status in documented_statuses(), (mutation, captured.err)
    if status:
        lines = captured.err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("tailor refine: error: "), (mutation, captured.err)
        assert str(domain) in lines[0], (mutation, lines[0])
        assert "Traceback" not in captured.err
    else:
        assert "NaN" not in captured.out and "Infinity" not in captured.out
    assert listing(domain) == before  # nothing written
    shutil.rmtree(domain.parent)
