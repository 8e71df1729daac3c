"""The gauge register: record checks, then passed / failed / overdue / none for a session."""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path

import numpy as np
import pytest

from station.analysis.gauge_check import gauge_check
from station.errors import StationError
from station.session.gauge_register import (
    coverage,
    coverage_lines,
    gauge_status,
    load_register,
    record_check,
    register_path,
    session_gauges,
)

TODAY = dt.date(2026, 11, 29)
GOOD = gauge_check(
    1.0 + np.random.default_rng(0).normal(0, 0.00005, 30), 1.0, 0.01, resolution=0.0001
)
BIASED = gauge_check(1.0008 + np.random.default_rng(0).normal(0, 0.0001, 30), 1.0, 0.01)


def test_register_path_follows_xdg_and_the_override(tmp_path: Path):
    assert register_path({"XDG_DATA_HOME": str(tmp_path)}) == tmp_path / "station" / "gauges.json"
    assert register_path({"STATION_GAUGES": "/x/g.json"}) == Path("/x/g.json")


def test_passed_failed_overdue_none(tmp_path: Path):
    path = tmp_path / "data" / "station" / "gauges.json"  # folders created on first write
    assert GOOD.capable is True and BIASED.capable is False
    record_check(path, "G-1", GOOD, when=dt.date(2026, 11, 2), calibration_due="2027-05-01")
    record_check(path, "G-2", BIASED, when=dt.date(2026, 11, 20))
    record_check(path, "G-3", GOOD, when=dt.date(2026, 1, 5))  # older than six months
    record_check(path, "G-4", GOOD, when=dt.date(2026, 11, 1), calibration_due="2026-11-15")
    statuses = coverage(
        {"x": "G-1", "y": "G-2", "z": "G-3", "a": "G-4", "b": "G-9", "c": ""}, TODAY, path=path
    )
    assert {ch: s.state for ch, s in statuses.items()} == {
        "x": "passed",
        "y": "failed",
        "z": "overdue",
        "a": "overdue",
        "b": "none",
        "c": "none",
    }
    lines = coverage_lines(statuses)
    assert lines[0] == "x: gauge G-1: gauge check passed on 2026-11-02, calibration due 2027-05-01"
    assert lines[1].startswith("y: WARNING: gauge G-2: its last gauge check (2026-11-20) failed")
    assert "is 328 days old (over 183)" in lines[2]
    assert "calibration was due on 2026-11-15" in lines[3]
    assert "no gauge check on record" in lines[4]
    # A snapshot recorded in a session gives the same lines later.
    snapshot = json.loads(json.dumps({ch: s.as_json() for ch, s in statuses.items()}))
    assert coverage_lines(snapshot) == lines


def test_a_new_passed_check_replaces_a_failed_one(tmp_path: Path):
    path = tmp_path / "gauges.json"
    record_check(path, "G-2", BIASED, when=dt.date(2026, 11, 20))
    record_check(path, "G-2", GOOD, when=dt.date(2026, 11, 28))
    status = gauge_status(load_register(path), "G-2", TODAY)
    assert status.state == "passed" and status.checked == dt.date(2026, 11, 28)
    assert len(load_register(path)["gauges"]["G-2"]["checks"]) == 2


def test_no_gauges_named_is_a_warning():
    assert "names no gauges" in coverage_lines({})[0]
    assert session_gauges({"gauges": {"x": "G-1"}}) == {"x": "G-1"}
    assert session_gauges({}) == {}


def test_symlinked_register_is_refused_and_its_target_untouched(tmp_path: Path):
    target = tmp_path / "elsewhere.json"
    target.write_text("keep")
    link = tmp_path / "gauges.json"
    link.symlink_to(target)
    with pytest.raises(StationError, match="symbolic link"):
        record_check(link, "G-1", GOOD, when=TODAY)
    assert target.read_text() == "keep"


def test_damaged_register_and_bad_dates_are_sentences(tmp_path: Path):
    path = tmp_path / "gauges.json"
    path.write_text("{not json")
    with pytest.raises(StationError, match="damaged"):
        load_register(path)
    with pytest.raises(StationError, match="YYYY-MM-DD"):
        record_check(tmp_path / "new.json", "G-1", GOOD, when=TODAY, calibration_due="next May")
    assert not (tmp_path / "new.json").exists()


def test_a_repeatability_sessions_verdict_shows_its_gauge_check(tmp_path: Path):
    from datetime import UTC, datetime

    from station.session.gauge_register import verdict_lines
    from station.session.journal import SessionWriter
    from station.session.model import load_session
    from tests.session.conftest import session_header_fields

    register = tmp_path / "gauges.json"
    record_check(register, "G-1", GOOD, when=dt.date(2026, 11, 2))
    record_check(register, "G-2", BIASED, when=dt.date(2026, 11, 20))
    # A header that records gauge ids but no snapshot (the register is read when judged).
    plain = {k: v for k, v in session_header_fields().items() if not k.startswith("gauge")}
    header = plain | {"gauges": {"x": "G-1", "y": "G-2", "z": "G-3"}}
    moment = datetime(2026, 11, 23, 12, 0, 0, tzinfo=UTC)
    with SessionWriter.create(tmp_path / "sessions", header, now=moment) as writer:
        path = writer.path
    session = load_session(path)
    lines = verdict_lines(session.header, TODAY, path=register)
    assert lines == [
        "x: gauge G-1: gauge check passed on 2026-11-02",
        "y: WARNING: gauge G-2: its last gauge check (2026-11-20) failed "
        f"(Cg {BIASED.cg:.2f}, Cgk {BIASED.cgk:.2f}); the verdict rests on a gauge that is not "
        "capable",
        "z: WARNING: gauge G-3: no gauge check on record; run the gauge_check procedure",
    ]
    # A snapshot recorded at the start wins over the register's later state.
    statuses = coverage(header["gauges"], TODAY, path=register)
    snapshot = {channel: status.as_json() for channel, status in statuses.items()}
    record_check(register, "G-2", GOOD, when=dt.date(2026, 11, 28))
    assert verdict_lines(header | {"gauge_checks": snapshot}, TODAY, path=register) == lines
    assert verdict_lines(header, TODAY, path=register)[1].startswith("y: gauge G-2: gauge check")
    assert "names no gauges" in verdict_lines(plain, TODAY, path=register)[0]


def test_a_new_session_records_the_gauge_checks_of_its_line(tmp_path: Path, monkeypatch):
    """At the start a session looks each channel's gauge up: the one named at set-up, else the
    one last checked on the same line and device channel; the snapshot goes into the header
    and its verdict block (wrapped to the report's width)."""
    from station.session.gauge_register import coverage_fields, gauge_block
    from tests.session.conftest import session_header_fields

    today = dt.date.today()  # the header looks the gauges up on the day the session starts
    register = tmp_path / "gauges.json"
    monkeypatch.setenv("STATION_GAUGES", str(register))
    record_check(register, "G-1", GOOD, when=today, port={"url": "loop://", "device": "1"})
    record_check(register, "G-2", BIASED, when=today, port={"url": "loop://", "device": "2"})
    record_check(register, "G-9", GOOD, when=today, port={"url": "other://", "device": "3"})
    header = session_header_fields(gauges={"y": "G-1"})
    assert header["gauges"] == {"x": "G-1", "y": "G-1"}  # named wins over the line's
    assert [header["gauge_checks"][c]["state"] for c in "xyz"] == ["passed", "passed", "none"]
    fields = coverage_fields(header, today)
    assert fields["gauge_checks"] == header["gauge_checks"]
    block = gauge_block(header, width=60)[0]
    assert block[1] == f"  x: gauge G-1: gauge check passed on {today.isoformat()}"
    assert max(len(line) for line in block) <= 60
    assert any(line.startswith("  z: WARNING: no gauge check covers") for line in block)
    # A damaged register: the session starts all the same, its verdict warns.
    register.write_text("{not json")
    damaged = coverage_fields(header, today)["gauge_checks"]["x"]["sentence"]
    assert damaged.startswith("WARNING: the gauge register cannot be read")


def test_a_gauge_checks_report_says_where_it_stands_in_the_register(tmp_path: Path):
    from station.session.gauge_register import filed_line

    register = tmp_path / "gauges.json"
    assert "not filed" in filed_line("s-1", register)
    record_check(register, "G-1", GOOD, when=TODAY, session="s-1")
    assert filed_line("s-1", register) == "gauge register: G-1, passed on 2026-11-29"
    assert "not filed" in filed_line("s-2", register)
    register.write_text("[]")
    assert filed_line("s-1", register).startswith("gauge register: cannot be read")
