"""Live alarms of a real engine session: judged against frozen (phase II) limits, so the
alarm events the engine writes are exactly what a replay of the file gives (through a reject
and a resume), and an alarm is acknowledged with a cause from the procedure's list."""

from __future__ import annotations

import re

import pytest

from station.analysis.monitor import replay_live_alarms
from station.analysis.report import format_report
from station.errors import StationError
from station.methods import analyze_session_file
from station.run import Runner
from station.session.alarms import live_events, recorded_alarms
from station.session.header import analysis_config
from station.session.model import load_session

from .conftest import cycles_only_procedure, setup_for

RECORDED_FIELDS = ("channel", "rule", "rule_name", "points", "cycles", "text", "raised_at", "live")


def capture(runner: Runner, count: int) -> None:
    for _ in range(count):
        outcome = runner.capture(3.0)
        assert outcome.recorded, outcome.message


def recorded_fields(session) -> list[dict]:
    return [{k: event.get(k) for k in RECORDED_FIELDS} for event in session.alarms]


def replayed_fields(session) -> list[dict]:
    config = analysis_config(session.header)
    replayed = replay_live_alarms(
        live_events(session),
        config,
        session.channels,
        freeze_after=config.freeze_after,
        baseline=config.baseline,
    )
    return [alarm.event_fields() for alarm in replayed]


def test_engine_alarms_are_phase_two_and_a_replay_gives_them_exactly(
    warming_robot, gauges_for, tmp_path
):
    procedure = cycles_only_procedure(tmp_path)
    setup = setup_for(warming_robot.url, procedure, cycles=45)
    gauges = gauges_for(setup)
    runner = Runner.start(setup, gauges, tmp_path)
    assert runner.header["freeze_after"] == procedure.cycles_min == 25
    capture(runner, 28)
    # A cycle rejected after the limits froze: they stay frozen, raised alarms stay raised.
    runner.reject(28, "the cube slipped")
    capture(runner, 4)
    before = runner.state().alarm_list
    runner.interrupt("test: link dropped")
    runner = Runner.resume(runner.path, gauges, setup=setup)
    assert runner.state().alarm_list == before, "a resume keeps the recorded alarms"
    capture(runner, 45 - runner.state().progress.done)
    runner.confirm()
    runner.finish()

    session = load_session(runner.path, recover=False)
    recorded = recorded_fields(session)
    assert recorded, "the drift and the outliers raise live alarms"
    assert all(event["live"] is True and event["rule_name"] for event in recorded)
    # Nothing before the limits froze at cycle 25 was raised before cycle 25.
    assert min(event["raised_at"] for event in recorded) >= 25
    assert replayed_fields(session) == recorded
    # The report shows the retrospective chart's alarms, each marked, beside the live ones.
    report = analyze_session_file(runner.path)
    text = format_report(report.analysis) + "\n".join(report.alarm_lines)
    assert "retrospective chart" in text and "[live]" in text
    marks = re.findall(r"\[(live and retrospective|retrospective)\]", " ".join(text.split()))
    retrospective = sum(len(c.alarms) for c in report.analysis.channels.values())
    assert len(marks) == retrospective > 0


def test_an_alarm_is_acknowledged_with_a_cause_of_the_procedure(
    warming_robot, gauges_for, tmp_path
):
    procedure = cycles_only_procedure(tmp_path)
    setup = setup_for(warming_robot.url, procedure, cycles=40)
    runner = Runner.start(setup, gauges_for(setup), tmp_path)
    capture(runner, 40)
    alarms = runner.state().alarm_list
    assert alarms and not any(alarm.acknowledged for alarm in alarms)
    first = alarms[0]
    with pytest.raises(StationError, match="not one of the procedure's causes"):
        runner.acknowledge(first.seq, "coffee")
    with pytest.raises(StationError, match="'other' needs a short text"):
        runner.acknowledge(first.seq, "other")
    with pytest.raises(StationError, match="no alarm #99999"):
        runner.acknowledge(99999, "gauge")
    done = runner.acknowledge(
        first.seq, "temperature", text="cell door open", action="waited 30 min", by="ana"
    )
    assert done.acknowledged and done.acks[-1].cause == "temperature"
    state = runner.state()
    assert state.alarm_list[0].acks[-1].action == "waited 30 min"
    assert state.alarm_list[1:] == alarms[1:]
    runner.confirm()
    runner.finish()
    with pytest.raises(StationError, match="finished"):
        runner.acknowledge(alarms[1].seq, "gauge")
    (alarm, *_) = recorded_alarms(load_session(runner.path, recover=False))
    assert alarm.acks[-1].describe() == (
        "temperature (cell door open); corrective action: waited 30 min; by ana"
    )
