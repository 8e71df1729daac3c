"""Recorded alarms: a replay of a session gives exactly its live alarms; alarms are acknowledged
with a cause from the procedure's list and shown with it in the report and the JSON."""

from __future__ import annotations

import json

import numpy as np
import pytest

from station.analysis.monitor import LiveMonitor, replay_live_alarms
from station.errors import StationError
from station.methods import analyze_session_file
from station.session.alarms import (
    ack_fields,
    format_recorded_alarms,
    live_events,
    recorded_alarms,
)
from station.session.header import analysis_config
from station.session.journal import SessionWriter
from station.session.model import load_session

from .conftest import session_header_fields

RECORDED_FIELDS = ("channel", "rule", "rule_name", "points", "cycles", "text", "raised_at", "live")


def capture(folder, values, *, reject_after: int | None = None):
    """Write a session as an engine does: each reading set is journalled, then the live
    monitor's new alarms; one cycle is rejected on the way."""
    header = session_header_fields()
    config = analysis_config(header)
    channels = tuple(header["channels"])
    monitor = LiveMonitor(config, channels, freeze_after=header["freeze_after"])
    with SessionWriter.create(folder, header) as writer:
        for cycle, row in enumerate(values, start=1):
            readings = dict(zip(channels, (float(v) for v in row), strict=True))
            writer.append(
                "reading",
                cycle=cycle,
                step="cycles",
                channels={
                    c: {"value": v, "t_wall": 1.7e9 + 15.0 * cycle} for c, v in readings.items()
                },
            )
            for alarm in monitor.add_set(readings, cycle)[1]:
                writer.append("alarm", **alarm.event_fields())
            if cycle == reject_after:
                writer.append("reject", cycle=cycle - 1, reason="fixture bumped")
                monitor.reject(cycle - 1)
        return writer.path, config


def warming_robot(n: int = 36, seed: int = 2) -> np.ndarray:
    """x drifts as the robot warms up; y has outliers; z is steady."""
    rng = np.random.default_rng(seed)
    x = np.linspace(0.0, 0.0007, n) + rng.normal(0, 0.00008, n)
    y = rng.normal(0, 0.0001, n)
    y[[24, 30]] += 0.0007
    z = rng.normal(0, 0.0001, n)
    return np.round(np.column_stack([x, y, z]), 5)


def test_a_replayed_session_gives_exactly_its_recorded_live_alarms(tmp_path):
    path, config = capture(tmp_path, warming_robot(), reject_after=27)
    session = load_session(path)
    recorded = [{k: event.get(k) for k in RECORDED_FIELDS} for event in session.alarms]
    assert recorded, "the drift and the outliers raise live alarms"
    replayed = replay_live_alarms(
        live_events(session),
        analysis_config(session.header),
        session.channels,
        freeze_after=session.header["freeze_after"],
    )
    assert [alarm.event_fields() for alarm in replayed] == recorded


def test_an_acknowledged_alarm_shows_its_cause_in_the_report_and_json(tmp_path):
    path, _ = capture(tmp_path, warming_robot())
    session = load_session(path)
    first = session.alarms[0]
    writer, _ = SessionWriter.resume(path)
    with writer:
        writer.append(
            "ack",
            **ack_fields(
                first["seq"],
                "temperature",
                text="cell door open\u202e",
                action="waited 30 min for warm-up",
                by="ana",
            ),
        )
    session = load_session(path)
    (alarm, *_) = recorded_alarms(session)
    assert alarm.acknowledged and alarm.acks[-1].cause == "temperature"
    report = analyze_session_file(path)
    text = "\n".join(report.alarm_lines)
    assert "acknowledged: temperature (cell door open\\u202e); corrective action: waited" in (
        " ".join(text.split())
    )
    assert "not acknowledged" in text  # the other alarms
    document = report.document()
    (entry,) = [a for a in document["recorded_alarms"] if a["seq"] == first["seq"]]
    assert entry["acks"][0]["cause"] == "temperature" and entry["live"] is True
    json.dumps(document, allow_nan=False)


def test_acks_are_checked(tmp_path):
    path, _ = capture(tmp_path, warming_robot())
    with pytest.raises(StationError, match="not one of the procedure's causes"):
        ack_fields(1, "coffee")
    with pytest.raises(StationError, match="'other' needs a short text"):
        ack_fields(1, "other")
    assert ack_fields(5, "other", text="forklift", causes=("gauge", "other")) == {
        "alarm": 5,
        "cause": "other",
        "text": "forklift",
    }
    writer, _ = SessionWriter.resume(path)
    with writer, pytest.raises(StationError, match="not a recorded alarm"):
        writer.append("ack", alarm=1, cause="gauge")


def test_no_recorded_alarm_is_said():
    assert format_recorded_alarms(()) == [
        "ALARMS RECORDED DURING THE SESSION (live), WITH THEIR CAUSES",
        "  none",
    ]
