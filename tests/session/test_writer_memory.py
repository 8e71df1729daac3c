"""Finding 8 of issue 12: a long session's writer grew by about 5 KB per cycle (it kept every
event, every reading and every raw frame in memory). It now keeps what checking the next event
needs; the file keeps everything."""

from __future__ import annotations

import time
import tracemalloc

from station.session.journal import SessionWriter
from station.session.model import load_session

from .conftest import session_header_fields


def _reading(cycle: int) -> dict:
    return {
        channel: {
            "value": 0.0001 * cycle,
            "unit": "in",
            "raw_value": 0.0001 * cycle,
            "zero": 0.0,
            "raw": "01A+00000.0012",
            "t_wall": time.time(),
            "t_mono": time.monotonic(),
        }
        for channel in "xyz"
    }


def test_the_writer_memory_per_cycle_stays_small(tmp_path):
    writer = SessionWriter.create(tmp_path, session_header_fields(robot="R1"))
    for cycle in range(1, 101):
        writer.append("reading", cycle=cycle, step="cycles", channels=_reading(cycle))
    tracemalloc.start()
    try:
        before = tracemalloc.take_snapshot()
        for cycle in range(101, 601):
            writer.append("reading", cycle=cycle, step="cycles", channels=_reading(cycle))
        after = tracemalloc.take_snapshot()
    finally:
        tracemalloc.stop()
    per_cycle = sum(stat.size_diff for stat in after.compare_to(before, "filename")) / 500
    assert per_cycle < 1000, f"{per_cycle:.0f} bytes per cycle"
    writer.append("reject", cycle=600, reason="checked against the file's cycles")
    writer.close()
    session = load_session(writer.path)  # the file keeps every reading and raw frame
    assert len(session.cycles) == 600 and session.cycles[7].readings["x"].raw == "01A+00000.0012"
    assert session.rejected == {600: "checked against the file's cycles"}
