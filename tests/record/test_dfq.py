"""Issue 22, item 4: ``station export FILE --dfq``, a session as a Q-DAS AQDEF transfer file,
read back with an independent reader (``aqdefreader``) value for value."""

from __future__ import annotations

import itertools
import re
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest
from helpers import run_station

from station.record.dfq import dfq_number, dfq_time
from station.session import journal
from station.session.journal import SessionWriter
from station.session.model import load_session
from station.text import figure_decimals

from .conftest import WHEN, _reading, header_fields, write_linearity

aqdefreader = pytest.importorskip("aqdefreader")

VALUES = [
    {"x": 0.00103, "y": -0.00004, "z": 2e-05},
    {"x": -0.00098, "y": 0.0, "z": 0.00012},
    {"x": 0.00041, "y": 0.00017, "z": -0.00131},
    {"x": 0.00002, "y": -0.00026, "z": 0.00005},
]
"""Readings after a zero taken as a mean: no whole gauge steps, one beyond the limits, one
that ``repr`` writes as ``2e-05``."""
GAUGES = {"x": "MIT-0042", "y": "MIT 0043"}


@pytest.fixture
def session_file(sessions: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A finished repeatability session of four cycles (the second rejected), gauges named
    on x and y, every event a second after the last from 23 Nov 2026 12:00:00 UTC (a day no
    reader can take for a month)."""
    seconds = itertools.count()
    monkeypatch.setattr(
        journal,
        "utc_now_iso",
        lambda moment=None: (WHEN + timedelta(seconds=next(seconds))).strftime(
            "%Y-%m-%dT%H:%M:%S.%fZ"
        ),
    )
    header = header_fields("repeatability", robot="KSC-7", gauges=GAUGES)
    with SessionWriter.create(sessions, header, now=WHEN) as writer:
        for cycle, values in enumerate(VALUES, start=1):
            writer.append(
                "reading", cycle=cycle, step="cycles", channels=_reading(values, "in"), by="op"
            )
        writer.append("reject", cycle=2, reason="bumped the fixture", by="operator")
        writer.append("finish", by="operator", complete=True)
    return writer.path


def _export(path: Path, out: Path) -> None:
    done = run_station("export", path, "--dfq", "-o", out)
    assert done.returncode == 0, done.stderr
    assert done.stderr == f"wrote 12 values to {out}\n"


def test_the_dfq_file_reads_back_value_for_value(session_file, tmp_path):
    out = tmp_path / "session.dfq"
    _export(session_file, out)
    session = load_session(session_file)
    dfq = aqdefreader.read_dfq_file(str(out))
    (part,) = dfq.get_parts()
    assert part.get_part_no() == "KSC-7"
    assert part.get_data("K1002") == (f"repeatability version 1.0, session {session.session_id}")
    characteristics = part.get_characteristics()
    assert [c.get_data("K2001") for c in characteristics] == ["x", "y", "z"]
    for channel, characteristic in zip("xyz", characteristics, strict=True):
        limits = session.header["limits"][channel]
        assert characteristic.get_data("K2002") == f"{channel} (repeatability)"
        assert characteristic.get_data("K2022") == figure_decimals(0.0001) == 5
        assert characteristic.get_data("K2142") == "in"
        # The reader takes a number with a point (or a sign) for text: compared as numbers.
        assert float(characteristic.get_data("K2101")) == limits["nominal"]
        assert float(characteristic.get_data("K2110")) == limits["lsl"]
        assert float(characteristic.get_data("K2111")) == limits["usl"]
        measurements = characteristic.get_measurements()
        assert len(measurements) == len(VALUES)
        for number, measurement in enumerate(measurements, start=1):
            cycle = session.cycles[number]
            assert float(measurement.value) == cycle.readings[channel].value
            assert measurement.attribute == (255 if number == 2 else 0)
            when = datetime.fromisoformat(cycle.t.replace("Z", "+00:00")).replace(
                microsecond=0, tzinfo=None
            )
            assert measurement.datetime == when


def test_the_gauge_of_each_value_and_every_number_in_plain_decimals(session_file, tmp_path):
    """The reader leaves K0012 out, so the file is read here: every value of x and y names
    its gauge, z names none, and no number is written as 2e-05."""
    out = tmp_path / "session.dfq"
    _export(session_file, out)
    lines = out.read_text().splitlines()
    assert lines[0] == "K0100 3" and lines[1] == "K1001/1 KSC-7"
    for index, channel in enumerate("xyz", start=1):
        gauges = [line.split(" ", 1)[1] for line in lines if line.startswith(f"K0012/{index} ")]
        assert gauges == [GAUGES[channel]] * len(VALUES) if channel in GAUGES else gauges == []
    numbers = [line.split(" ", 1)[1] for line in lines if line[:5] in ("K0001", "K2110", "K2111")]
    assert "K0001/3 0.00002" in lines
    assert all(re.fullmatch(r"-?\d+(?:\.\d+)?", number) for number in numbers), numbers


def test_number_and_time_fields_follow_the_format():
    assert dfq_number(2e-05) == "0.00002" and dfq_number(-0.00131) == "-0.00131"
    assert dfq_number(-0.0) == "0" and dfq_number(0.1 + 0.2) == "0.30000000000000004"
    # dd.mm.yyyy/hh:mm:ss, the day first (3 December, not 12 March).
    assert dfq_time("2026-12-03T07:13:08.016273Z") == "03.12.2026/07:13:08"
    assert dfq_time(datetime(2026, 1, 2, tzinfo=UTC).isoformat()) == "02.01.2026/00:00:00"


def test_a_session_without_cycles_and_a_csv_layout_are_refused(sessions, tmp_path):
    path = write_linearity(sessions, strokes=2, points=20)
    done = run_station("export", path, "--dfq")
    assert done.returncode == 2 and "no cycles of readings to export as DFQ" in done.stderr
    assert "use --csv" in done.stderr
    done = run_station("export", path, "--dfq", "--layout", "wide")
    assert done.returncode == 2 and "--layout is a CSV layout" in done.stderr
    done = run_station("export", path, "--csv", "--dfq")
    assert done.returncode == 2 and "not allowed with" in done.stderr


def test_text_from_outside_stays_on_its_line(sessions, tmp_path):
    header = header_fields("repeatability", robot="KSC\n7\x1b[2J", gauges={"x": "G\r\nK0001/1 9"})
    with SessionWriter.create(sessions, header, now=WHEN) as writer:
        writer.append(
            "reading", cycle=1, step="cycles", channels=_reading(VALUES[0], "in"), by="op"
        )
        writer.append("finish", by="operator", complete=True)
    text = run_station("export", writer.path, "--dfq").stdout
    assert "K1001/1 KSC\\n7\\x1b[2J" in text.splitlines()
    assert "K0012/1 G\\r\\nK0001/1 9" in text.splitlines()
    assert [line for line in text.splitlines() if line.startswith("K0001/1 ")] == [
        "K0001/1 0.00103"
    ]
