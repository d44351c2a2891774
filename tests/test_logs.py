"""Logs of executed actions (tailor.action_log/1, docs/logs.md): episodes written as CSV or Parquet read back
exactly, so a model trained from an exported log equals the one trained from the episodes themselves; every
bad row is one line naming file:row and the column, and nothing is trained or written."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from tailor.cli.main import main
from tailor.errors import DataError
from tailor.refinement.learning.duration_protocol import train_duration_model
from tailor.refinement.learning.logs import FORMAT, episode_rows, read_logs, write_log
from tailor.sims import registry
from tailor.sims.experience import gather

SIMULATOR = "soccer"
ACTION = "goToPosition"  # the quickest episodes of the bundled robots


@pytest.fixture(scope="module")
def episodes():
    return gather(SIMULATOR, ACTION, 40, seed=5, progress=False)


def write(tmp_path: Path, episodes, kind: str = "csv") -> Path:
    columns, rows = episode_rows(episodes, registry.get(SIMULATOR), run="r1", source="test")
    path = tmp_path / f"log.{kind}"
    write_log(path, columns, rows, kind)
    return path


def same(a, b) -> bool:
    return (a.action == b.action and np.array_equal(a.params, b.params) and np.array_equal(a.t, b.t)
            and np.array_equal(a.state, b.state, equal_nan=True) and a.columns == b.columns
            and a.outcome == b.outcome and a.duration == b.duration and a.seed == b.seed)


@pytest.mark.parametrize("kind", ["csv", "parquet"])
def test_episodes_read_back_exactly_and_train_the_same_model(tmp_path, episodes, kind):
    if kind == "parquet":
        pytest.importorskip("pyarrow")
    path = write(tmp_path, episodes, kind)
    read = read_logs([path], registry.get(SIMULATOR), [ACTION])[ACTION]
    assert len(read) == len(episodes) and all(same(a, b) for a, b in zip(read, episodes))
    observed = registry.get(SIMULATOR).action(ACTION).observed
    kwargs = dict(n_i_candidates=(1, 3), episode_fractions=(1.0,))
    a = train_duration_model(ACTION, episodes, 0, "position", observed, **kwargs).model
    b = train_duration_model(ACTION, read, 0, "position", observed, **kwargs).model
    assert json.dumps(a.to_json()) == json.dumps(b.to_json())


def test_a_log_states_its_format_and_units_in_every_row_and_header(tmp_path, episodes):
    path = write(tmp_path, episodes[:2])
    rows = list(csv.reader(path.read_text().splitlines()))
    assert rows[0][:8] == ["log_format", "action", "run", "source", "execution", "t [s]", "duration [s]", "outcome"]
    assert {"x [m]", "phi [rad]", "v [m/s]", "xg [m]", "state.ball_x [m]"} <= set(rows[0])
    assert all(row[0] == FORMAT for row in rows[1:])
    assert rows[1][5] == "" and rows[2][5] == "0.0"  # an execution row, then its state rows


def test_a_log_without_state_rows_gives_each_start_as_its_example(tmp_path):
    path = tmp_path / "robot.csv"
    header = "log_format,action,run,source,duration [s],outcome,x [m],v [m/s],xg [m],vg [m/s]"
    path.write_text(header + "\n" + f"{FORMAT},move,lab,robot 1,2.5,success,0.0,0.0,1.0,0.0\n")
    from tailor.sims.protocol import ActionSpec, Quantity, SimulatorEntry

    entry = SimulatorEntry("rail", {"move": ActionSpec("move", "rail", ("x", "v"), ("xg", "vg"), ("x", "v"),
                                                       ("x", "v"))}, create=lambda seed, noise=None: None,
                           units={"x": Quantity("m"), "v": Quantity("m/s")})
    (episode,) = read_logs([path], entry, ["move"])["move"]
    assert list(episode.params) == [0.0, 0.0, 1.0, 0.0] and episode.duration == 2.5
    assert list(episode.t) == [0.0] and list(episode.state[0]) == [0.0, 0.0] and episode.columns == ("x", "v")


def _edit(path: Path, row: int, column: str, value: str) -> None:
    rows = list(csv.reader(path.read_text().splitlines()))
    rows[row - 1][rows[0].index(column)] = value
    with open(path, "w", newline="") as f:
        csv.writer(f).writerows(rows)


def _rename(path: Path, old: str, new: str) -> None:
    rows = list(csv.reader(path.read_text().splitlines()))
    rows[0][rows[0].index(old)] = new
    with open(path, "w", newline="") as f:
        csv.writer(f).writerows(rows)


BAD = [
    (lambda p: _edit(p, 2, "action", "fly"), ":2: column 'action': 'fly' is no action of simulator 'soccer'"),
    (lambda p: _edit(p, 2, "x [m]", ""), ":2: column 'x [m]': missing value"),
    (lambda p: _edit(p, 2, "xg [m]", "nan"), ":2: column 'xg [m]': not a finite number: 'nan'"),
    (lambda p: _edit(p, 4, "v [m/s]", "inf"), ":4: column 'v [m/s]': not a finite number: 'inf'"),
    (lambda p: _edit(p, 2, "duration [s]", "-1.0"), ":2: column 'duration [s]': negative duration"),
    (lambda p: _edit(p, 2, "duration [s]", "soon"), ":2: column 'duration [s]': not a number: 'soon'"),
    (lambda p: _rename(p, "phi [rad]", "phi [deg]"), ":1: column 'phi [deg]': unit 'deg', simulator 'soccer' "
                                                     "declares 'rad' for phi"),
    (lambda p: _rename(p, "x [m]", "x"), ":1: column 'x': unit 'none', simulator 'soccer' declares 'm'"),
    (lambda p: _rename(p, "state.ball_x [m]", "theta_a [rad]"), ":1: column 'theta_a [rad]': is no parameter of an "
                                                                "action of simulator 'soccer' (another domain's log?)"),
    (lambda p: _edit(p, 2, "log_format", "tailor.action_log/9"), ":2: column 'log_format': 'tailor.action_log/9'"),
    (lambda p: _edit(p, 3, "execution", "12"), ":3: column 't [s]': a state row must follow the row of the "
                                               "execution it belongs to"),
    (lambda p: _rename(p, "outcome", "result"), ":1: column 'result': is no parameter"),
]


@pytest.mark.parametrize("spoil, message", BAD)
def test_a_bad_row_is_one_line_naming_file_row_and_column(tmp_path, episodes, spoil, message):
    path = write(tmp_path, episodes[:3])
    spoil(path)
    with pytest.raises(DataError) as caught:
        read_logs([path], registry.get(SIMULATOR), [ACTION])
    text = str(caught.value)
    assert text.startswith(str(path) + ":") and message in text and "\n" not in text


def test_a_bad_parquet_row_names_its_row(tmp_path, episodes):
    pa = pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq

    path = write(tmp_path, episodes[:2], "parquet")
    table = pq.read_table(path).to_pydict()
    table["duration [s]"][0] = float("inf")  # the first execution row: row 2, as if the header were row 1
    pq.write_table(pa.table(table), path)
    with pytest.raises(DataError, match=r"log\.parquet:2: column 'duration \[s\]': not a finite number"):
        read_logs([path], registry.get(SIMULATOR), [ACTION])


def test_train_from_a_bad_log_trains_nothing_and_writes_nothing(tmp_path, episodes, capsys):
    path = write(tmp_path, episodes)
    _edit(path, 40, "v [m/s]", "fast")
    out = tmp_path / "out"
    assert main(["train", "soccer", "--log", str(path), "--only", ACTION, "--out", str(out)]) == 14
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{path}:40: column 'v [m/s]': not a number: 'fast'" in err
    assert not (out / "models").exists()


def test_gather_exports_a_log_that_trains_the_model_of_the_shards(tmp_path, capsys):
    """tailor gather --format csv, then tailor train --log: the model equals tailor train's from the shards."""
    experience = tmp_path / "experience"
    assert main(["gather", "soccer", "--seeds", "0:30", "--scenario", ACTION, "--seed", "2", "--out", str(experience),
                 "--format", "csv", "-q"]) == 0
    log = experience / f"{ACTION}.seed2.0-30.csv"
    assert log.is_file()
    common = ["--only", ACTION, "--n-i", "1,3", "--seed", "2", "--no-compare", "-q"]
    assert main(["train", "soccer", "--log", str(log), "--out", str(tmp_path / "logged"), *common]) == 0
    assert main(["train", "soccer", "--episodes", "30", "--experience", str(experience),
                 "--out", str(tmp_path / "simulated"), *common]) == 0
    logged = json.loads((tmp_path / "logged" / "models" / f"{ACTION}.json").read_text())
    simulated = json.loads((tmp_path / "simulated" / "models" / f"{ACTION}.json").read_text())
    for model in (logged, simulated):
        for key in ("selection_seconds", "protocol_seconds"):
            model["report"].pop(key, None)
    assert logged == simulated
