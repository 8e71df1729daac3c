"""The session index (issue 23, item 6): ``station history`` reads each file's figures from a
SQLite cache in the station's data folder while the file is unchanged, and ``history --all``
gives one line per robot. The files stay the truth: every test compares with reading them."""

from __future__ import annotations

import json
import os
import sqlite3
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest

import station.record.history as history_module
import station.record.index as index_module
from station.cli import main
from station.errors import StationError
from station.record.baseline import store_baseline
from station.record.history import fleet_history, robot_history
from station.record.index import SessionIndex, index_path

from .conftest import write_repeatability

START = datetime(2026, 1, 5, 9, 0, tzinfo=UTC)


def robot_sessions(folder: Path, robot: str, count: int, *, wear: float = 0.0, seed: int = 100):
    """``count`` sessions of ``robot`` 30 days apart, x's bias growing by ``wear`` each."""
    return [
        write_repeatability(
            folder,
            robot=robot,
            seed=seed + k,
            bias={"x": wear * k},
            created=START + timedelta(days=30 * k),
            reject=None,
            alarm=False,
        )
        for k in range(count)
    ]


def no_file_read(path, **_):
    raise AssertionError(f"{path.name} was read though the index holds it unchanged")


def test_the_index_gives_the_history_the_files_give_and_then_reads_none(sessions, monkeypatch):
    paths = robot_sessions(sessions, "KSC-7", 5, wear=0.0001)
    robot_sessions(sessions, "other", 2, seed=7)
    (sessions / "garbage.jsonl").write_bytes(b"\x00\xffnot a session\n")
    from_files = robot_history(sessions, "KSC-7")
    with SessionIndex.open() as index:
        cold = robot_history(sessions, "KSC-7", index=index)
        monkeypatch.setattr(index_module, "session_figures", no_file_read)
        warm = robot_history(sessions, "KSC-7", index=index)
        assert index.warnings == []
    assert cold == from_files and warm == from_files
    assert [e.path for e in warm.entries] == paths and warm.trends
    assert [p.name for p, _ in warm.skipped] == ["garbage.jsonl"]
    # The baseline is the robot's, not the file's: marked on reading, after the index has it.
    # A baseline must be shown CAPABLE (an INCONCLUSIVE session is refused): the first that is.
    chosen = None
    for number, candidate in enumerate(paths):
        try:
            store_baseline("KSC-7", candidate)
        except StationError:
            continue
        chosen = number
        break
    assert chosen is not None, "no generated session is shown CAPABLE"
    with SessionIndex.open() as index:
        marked = robot_history(sessions, "KSC-7", index=index)
    assert [e.baseline for e in marked.entries] == [i == chosen for i in range(len(paths))]
    assert marked == robot_history(sessions, "KSC-7")


def test_another_robots_sessions_are_analysed_only_when_asked_for(sessions, monkeypatch):
    robot_sessions(sessions, "KSC-7", 3)
    robot_sessions(sessions, "other", 3, seed=7)
    analysed: list[str] = []
    original = history_module.analyse_loaded

    def counted(session):
        analysed.append(session.robot)
        return original(session)

    monkeypatch.setattr(history_module, "analyse_loaded", counted)
    with SessionIndex.open() as index:
        robot_history(sessions, "KSC-7", index=index)
        assert analysed == ["KSC-7"] * 3  # the others' files are loaded, not analysed
        other = robot_history(sessions, "other", index=index)
        assert analysed == ["KSC-7"] * 3 + ["other"] * 3
        fleet = fleet_history(sessions, index=index)
        assert len(analysed) == 6  # every file's figures are in the index now
    assert other == robot_history(sessions, "other") and fleet == fleet_history(sessions)


def test_a_changed_added_or_deleted_file_is_noticed(sessions):
    paths = robot_sessions(sessions, "KSC-7", 4)
    with SessionIndex.open() as index:
        robot_history(sessions, "KSC-7", index=index)
    # An edit that keeps the file's size and modification time (a byte of a reading changed,
    # the time set back) is still noticed: its change time moved.
    edited = paths[1]
    before = os.stat(edited)
    data = bytearray(edited.read_bytes())
    at = data.index(b'"value":0.') + len(b'"value":0.')
    data[at] = ord("9") if data[at] != ord("9") else ord("8")
    edited.write_bytes(bytes(data))
    os.utime(edited, ns=(before.st_atime_ns, before.st_mtime_ns))
    assert os.stat(edited).st_size == before.st_size
    paths[2].unlink()
    added = write_repeatability(sessions, seed=50, created=START + timedelta(days=200))
    with SessionIndex.open() as index:
        history = robot_history(sessions, "KSC-7", index=index)
    assert [e.path for e in history.entries] == [paths[0], paths[3], added]
    assert [p for p, _ in history.skipped] == [edited]
    assert "edited" in dict(history.skipped)[edited]
    assert history == robot_history(sessions, "KSC-7")
    rows = sqlite3.connect(index_path()).execute("SELECT name FROM files").fetchall()
    assert sorted(name for (name,) in rows) == sorted(p.name for p in sessions.glob("*.jsonl"))


def test_a_damaged_index_is_built_again_with_a_warning(sessions, capsys):
    robot_sessions(sessions, "KSC-7", 3)
    assert main(["history", "KSC-7", "--sessions", str(sessions)]) == 0
    expected = capsys.readouterr().out
    index_path().write_bytes(b"this is not SQLite\x00" * 300)
    assert main(["history", "KSC-7", "--sessions", str(sessions)]) == 0
    out, err = capsys.readouterr()
    assert out == expected
    assert f"the session index {index_path()} was damaged" in err
    assert "built again from the session files" in err
    rows = sqlite3.connect(index_path()).execute("SELECT count(*) FROM files").fetchone()
    assert rows == (3,)
    assert main(["history", "KSC-7", "--sessions", str(sessions)]) == 0
    assert capsys.readouterr() == (expected, f"sessions folder: {sessions} (from --sessions)\n")


def test_an_index_that_cannot_be_kept_is_done_without(sessions, capsys):
    robot_sessions(sessions, "KSC-7", 2)
    expected = robot_history(sessions, "KSC-7")
    folder = index_path().parent
    folder.parent.mkdir(parents=True, exist_ok=True)
    folder.write_text("a file where the station's data folder should be\n")
    assert main(["history", "KSC-7", "--sessions", str(sessions)]) == 0
    out, err = capsys.readouterr()
    assert "the session index" in err and "the session files are read instead" in err
    assert "History of robot KSC-7 (2 sessions)" in out
    with SessionIndex.open() as index:
        assert robot_history(sessions, "KSC-7", index=index) == expected


@pytest.mark.parametrize("where", ["a folder at its name", "a data folder it cannot make"])
def test_an_index_that_cannot_be_opened_is_done_without(sessions, monkeypatch, where):
    robot_sessions(sessions, "KSC-7", 2)
    expected = robot_history(sessions, "KSC-7")
    if where == "a folder at its name":
        index_path().mkdir(parents=True)
        why = "unable to open database file"
    else:

        def read_only(folder):
            raise PermissionError(13, "Permission denied", str(folder))

        monkeypatch.setattr(index_module, "make_folders", read_only)
        why = "cannot be made (Permission denied)"
    with SessionIndex.open() as index:
        assert robot_history(sessions, "KSC-7", index=index) == expected
        (warning,) = index.warnings
    assert why in warning and "the session files are read instead" in warning


def test_a_second_writer_holding_the_index_is_waited_for_then_done_without(sessions, monkeypatch):
    robot_sessions(sessions, "KSC-7", 2)
    with SessionIndex.open() as first:
        robot_history(sessions, "KSC-7", index=first)
    robot_sessions(sessions, "KSC-7", 1, seed=60)  # a file the next reader must write
    expected = robot_history(sessions, "KSC-7")
    other = sqlite3.connect(index_path(), isolation_level=None)
    other.execute("BEGIN EXCLUSIVE")  # another station command in the middle of its write
    monkeypatch.setattr(index_module, "BUSY_SECONDS", 0.05)
    try:
        with SessionIndex.open() as second:
            assert robot_history(sessions, "KSC-7", index=second) == expected
            (warning,) = second.warnings
    finally:
        other.execute("ROLLBACK")
        other.close()
    assert "database is locked" in warning and "read instead" in warning


def test_history_all_gives_one_line_per_robot(sessions, capsys):
    robot_sessions(sessions, "KSC-7", 5, wear=0.0001)  # x's Cpk falls: wear
    robot_sessions(sessions, "ABB-2", 4, seed=300)
    write_repeatability(sessions, robot="Fanuc 1", seed=9, created=START + timedelta(days=3))
    (sessions / "garbage.jsonl").write_bytes(b"\x00\xffnot a session\n")

    assert main(["history", "--all", "--sessions", str(sessions)]) == 0
    out = capsys.readouterr().out
    assert "Robots in the sessions folder: 3 (10 sessions)" in out
    rows = [line for line in out.splitlines() if line[:6] in ("KSC-7 ", "ABB-2 ", "Fanuc ")]
    assert [row.split()[0] for row in rows] == ["ABB-2", "Fanuc", "KSC-7"]
    assert all(len(line) <= 80 for line in rows)
    ksc = rows[2].split()
    assert ksc[1] == (START + timedelta(days=120)).strftime("%Y-%m-%d") and ksc[-1] == "falling"
    assert rows[1].split()[-1] == "-"  # one session: no trend
    assert "Left out (1 files that could not be read):" in out and "garbage.jsonl: " in out

    assert main(["history", "--all", "--sessions", str(sessions), "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    fleet = fleet_history(sessions)
    assert [r["robot"] for r in document["robots"]] == ["ABB-2", "Fanuc 1", "KSC-7"]
    for row, line in zip(document["robots"], fleet.robots, strict=True):
        history = robot_history(sessions, line.robot)
        latest = history.entries[-1]
        assert row["sessions"] == len(history.entries) and row["file"] == latest.path.name
        assert row["verdict"] == latest.verdict and row["rp"] == pytest.approx(latest.rp)
        lowest = min(c.cpk for c in latest.channels.values())
        assert row["cpk"] == pytest.approx(lowest)
    assert document["robots"][2]["trend"] == "falling"
    assert [s["file"] for s in document["skipped"]] == ["garbage.jsonl"]
    with SessionIndex.open() as index:
        assert fleet_history(sessions, index=index) == fleet


def test_history_needs_a_robot_or_all_not_both(sessions, capsys):
    write_repeatability(sessions, robot="R1")
    assert main(["history", "--sessions", str(sessions)]) == 2
    assert "name the robot" in capsys.readouterr().err
    assert main(["history", "R1", "--all", "--sessions", str(sessions)]) == 2
    assert "not both" in capsys.readouterr().err
