"""The sessions folder, the listing and the CSV export."""

from __future__ import annotations

import csv
import io
import subprocess
import sys
from pathlib import Path

from station.session.export import CSV_COLUMNS, export_csv
from station.session.model import load_session
from station.session.store import find_unfinished, list_sessions, sessions_folder, summarise

from .conftest import reading_fields, write_session


def test_sessions_folder_precedence(tmp_path: Path) -> None:
    cwd = tmp_path / "work"
    cwd.mkdir()
    env = {"STATION_SESSIONS": "/srv/s", "XDG_DATA_HOME": str(tmp_path / "xdg")}
    assert sessions_folder("/x", environ=env, cwd=cwd) == (Path("/x"), "from --sessions")
    assert sessions_folder(None, environ=env, cwd=cwd) == (
        Path("/srv/s"),
        "from STATION_SESSIONS",
    )
    env.pop("STATION_SESSIONS")
    folder, why = sessions_folder(None, environ=env, cwd=cwd)
    assert folder == tmp_path / "xdg" / "station" / "sessions" and why == "the user's data folder"
    (cwd / "sessions").mkdir()
    assert sessions_folder(None, environ=env, cwd=cwd)[0] == cwd / "sessions"
    folder, _ = sessions_folder(None, environ={}, cwd=tmp_path)
    assert folder == Path.home() / ".local" / "share" / "station" / "sessions"


def test_listing_sorts_by_robot_and_date_and_keeps_broken_files(tmp_path: Path) -> None:
    folder = tmp_path / "sessions"
    write_session(folder, robot="zeta", finish=True)
    unfinished = write_session(folder, robot="alpha", finish=False)
    (folder / "broken.jsonl").write_bytes(b"not a session\n")
    (folder / "notes.txt").write_text("ignored")
    summaries = list_sessions(folder)
    assert [s.robot for s in summaries] == ["alpha", "zeta", ""]
    assert summaries[0].status == "running" and summaries[0].cycles == 4
    assert summaries[0].rejected == 1 and summaries[0].cycles_target == 30
    assert summaries[1].status == "finished"
    assert summaries[2].error is not None
    assert "is not a station session file" in summaries[2].error
    assert [s.path for s in find_unfinished(folder)] == [unfinished]
    assert list_sessions(tmp_path / "missing") == []


def test_listing_is_read_only_even_with_a_torn_tail(tmp_path: Path) -> None:
    path = write_session(tmp_path, finish=False)
    damaged = path.read_bytes() + b'{"seq":'
    path.write_bytes(damaged)
    (summary,) = list_sessions(tmp_path)
    assert summary.torn and summary.resumable
    assert path.read_bytes() == damaged


def test_export_csv_is_tidy_and_marks_rejected_cycles(tmp_path: Path) -> None:
    session = load_session(write_session(tmp_path, cycles=3))
    out = io.StringIO()
    assert export_csv(session, out) == 9
    rows = list(csv.reader(io.StringIO(out.getvalue())))
    assert tuple(rows[0]) == CSV_COLUMNS
    assert rows[0][:6] == ["cycle", "channel", "value", "unit", "status", "time"]
    expected = reading_fields(2)["channels"]["y"]
    row = rows[5]
    assert row[:5] == ["2", "y", repr(expected["value"]), "in", "rejected: bumped the fixture"]
    assert row[5] == session.cycles[2].t
    assert row[6:8] == [repr(expected["raw_value"]), "0.375"]
    assert [r[4] for r in rows[1:4]] == ["ok"] * 3
    assert [(r[0], r[1]) for r in rows[1:]] == [(str(c), ch) for c in (1, 2, 3) for ch in "xyz"]


def test_listing_sessions_loads_no_numpy(tmp_path: Path) -> None:
    """The home screen lists the sessions folder as it appears: reading every header, event and
    reading of the listed files must not load numpy (the session model defers it)."""
    folder = tmp_path / "sessions"
    write_session(folder, robot="alpha", finish=False)
    write_session(folder, robot="zeta", finish=True)
    probe = (
        "import sys\n"
        "from station.session.store import find_unfinished, list_sessions, status_words\n"
        f"listed = list_sessions({str(folder)!r})\n"
        f"unfinished = find_unfinished({str(folder)!r})\n"
        "words = [status_words(summary) for summary in listed]\n"
        "print(len(listed), len(unfinished), 'numpy' in sys.modules)\n"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["2", "1", "False"]


def test_a_summary_counts_what_its_procedure_counts() -> None:
    """The home screen's resume line and the review list said "0 of 30 cycles" of a linearity
    session that had streamed its 3 strokes (it records points, not cycles), and "3 of 5
    cycles" of 3 fixture placements asked for."""
    saved = Path(__file__).resolve().parents[1] / "tui" / "snapshots" / "sessions"
    summaries = {s.procedure: s for s in map(summarise, sorted(saved.glob("*.jsonl")))}
    assert {name: s.progress for name, s in summaries.items()} == {
        "repeatability": "30 of 30 cycles",
        "linearity": "1420 points, 3 strokes asked",
        "relative_accuracy": "3 of 3 placements",
    }
    # The review list's column is narrow.
    assert {name: s.progress_brief for name, s in summaries.items()} == {
        "repeatability": "30/30 cycles",
        "linearity": "1420 points",
        "relative_accuracy": "3/3 placed",
    }
