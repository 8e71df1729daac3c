"""Zero steps from several readings through the engine (a moving simulated robot on a real pty),
what the record and every report show of the zero, and cycle numbers that agree after a
rejected cycle."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from station.errors import StationError
from station.instruments.motion import CycleMotion
from station.instruments.protocols import get_protocol
from station.instruments.simulator import AxisModel, FixtureModel, GaugeSpec, Simulator
from station.procedures import parse_procedure
from station.run import PortSetup, Runner, SessionSetup, open_gauges
from station.session.model import load_session

PERIOD = 0.6
MAP = {"1": "x", "2": "y", "3": "z"}

ZEROED = b"""
id = "zeroed"
title = "A zero from several readings"
version = "1"
report_section = "2.6"
channels = ["x", "y", "z"]
unit = "mm"
resolution = 0.001

[cycles]
min = 2
target = 3

[limits]
tolerance = 0.5

[[steps]]
id = "zero"
kind = "zero"
title = "Zero the indicators"
readings = 4
settle = 0.1
still = 3

[[steps]]
id = "cycles"
kind = "cycles"
title = "Cycles"
prompt = "Cycle {cycle} of {count}: capture."
"""


@pytest.fixture
def moving() -> Simulator:
    """A robot that returns every PERIOD s and whose z hunts at rest (never still)."""
    model = FixtureModel(dict.fromkeys("xyz", AxisModel(noise=0.01)), GaugeSpec(0.001))
    motion = CycleMotion(PERIOD, -9.525, 0.02, hunt={"z": 0.01}, hunt_every=2)
    simulator = Simulator(get_protocol("mitutoyo"), model, seed=3, motion=motion)
    simulator.start_pty()
    yield simulator
    simulator.stop()


def _next_rest(simulator: Simulator, hunting: bool = False) -> None:
    """Sleep until the robot is next at rest (the start of a period): on a return where z
    hunts (an even cycle from 2 on) when ``hunting``, else on one where it settles."""
    elapsed = time.monotonic() - simulator.motion_t0
    cycle = max(2, int(elapsed // PERIOD) + 1)
    if (cycle % 2 == 0) != hunting:
        cycle += 1
    time.sleep(max(0.0, simulator.motion_t0 + cycle * PERIOD + 0.02 - time.monotonic()))


def _start(tmp_path: Path, url: str) -> tuple[Runner, object]:
    procedure = parse_procedure(ZEROED, tmp_path / "zeroed.toml")
    setup = SessionSetup(
        procedure=procedure,
        robot="R1",
        operator="ana",
        ports=(PortSetup(url, "mitutoyo", MAP),),
    )
    gauges = open_gauges(setup, backoff=(0.05, 0.2))
    assert gauges.wait_connected(5.0)
    return Runner.start(setup, gauges, tmp_path / "s"), gauges


def test_a_zero_is_refused_while_a_gauge_moves_naming_it_then_taken_from_several_readings(
    tmp_path: Path, moving: Simulator
) -> None:
    runner, gauges = _start(tmp_path, moving.url)
    try:
        # At rest z hunts on every second return, x and y are still: a zero then is refused
        # naming z alone, and nothing is recorded; on the next return it is taken.
        _next_rest(moving, hunting=True)
        with pytest.raises(StationError) as caught:
            runner.zero(timeout=1.0)
        assert "z moves" in caught.value.message, caught.value.message
        assert "x moves" not in caught.value.message and "y moves" not in caught.value.message
        assert runner.state().action.kind == "zero"
        _next_rest(moving)
        runner.zero(timeout=1.0)
        state = runner.state()
        assert state.action.kind == "capture"
        assert set(state.zero) == {"x", "y", "z"}
    finally:
        runner.close()
        gauges.stop()
    session = load_session(runner.path)
    (event,) = session.zeroes
    assert set(event["channels"]) == {"x", "y", "z"}
    for spec in event["channels"].values():
        assert spec["n"] > 1 and spec["method"] == "software"
        assert spec["offset"] == pytest.approx(spec["mean"], abs=0.0001)
        assert spec["spread"] <= 0.003 and len(spec["values"]) == spec["n"]
        assert 0 < spec["uncertainty"] < 0.001


def test_the_zero_shows_on_the_dashboard_the_summary_and_the_reports(
    tmp_path: Path, moving: Simulator
) -> None:
    import subprocess
    import sys

    from station.methods import analyze_session_file
    from station.tui.screens.dashboard import DashboardView
    from station.tui.screens.summary import SummaryView

    runner, gauges = _start(tmp_path, moving.url)
    try:
        _next_rest(moving)  # a return where every axis settles
        runner.zero(timeout=1.0)
        state = runner.state()
        view = DashboardView.from_live(state, None, runner.setup.header_fields())
        assert view.zero.startswith("zero x ") and view.zero.endswith("(4 readings)")
        assert runner.capture(3.0).recorded and runner.capture(3.0).recorded
        runner.finish()
    finally:
        gauges.stop()
    # The summary screen's notes, `station analyze FILE` and the filed text report.
    summary = SummaryView.from_live(runner.state(), None, runner.setup.header_fields())
    assert any(n.startswith("Zero taken: x ") and "4 readings" in n for n in summary.notes)
    report = analyze_session_file(runner.path)
    assert any(note.startswith("Zero taken: x ") for note in report.notes)
    filed = subprocess.run(
        [sys.executable, "-m", "station", "report", str(runner.path)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert filed.returncode == 0, filed.stderr
    zero_section = filed.stdout.split("ZERO TAKEN", 1)[1].split("LIMITS", 1)[0]
    assert zero_section.count("(mean of 4 readings, spread") == 3, zero_section


def test_the_prompt_names_the_cycle_the_record_will_after_a_rejected_one(tmp_path: Path) -> None:
    from .conftest import CYCLES_ONLY, make_simulator

    simulator = make_simulator()
    simulator.start_pty()
    procedure = parse_procedure(
        CYCLES_ONLY.replace(
            b'title = "Cycles"', b'title = "Cycles"\nprompt = "Cycle {cycle} of {count}."'
        ),
        tmp_path / "cycles-only.toml",
    )
    setup = SessionSetup(
        procedure=procedure,
        robot="R1",
        operator="ana",
        ports=(PortSetup(simulator.url, "mitutoyo", MAP),),
        cycles=30,
    )
    gauges = open_gauges(setup, backoff=(0.05, 0.2))
    try:
        assert gauges.wait_connected(5.0)
        runner = Runner.start(setup, gauges, tmp_path)
        while runner.state().action.kind != "capture":
            runner.confirm()
        for _ in range(4):
            assert runner.capture(3.0).recorded
        assert runner.prompt() == "Cycle 5 of 30."
        runner.reject(4, "the cube slipped")
        state = runner.state()
        assert state.action.prompt == "Cycle 5 (4 of 30 accepted)."
        from station.tui.screens.dashboard import DashboardView

        view = DashboardView.from_live(state, None, setup.header_fields())
        assert view.last == {}  # the rejected cycle is not shown as the last reading
        assert "(cycle 4 rejected)" in view.progress
        outcome = runner.capture(3.0)
        assert outcome.cycle.cycle == 5
        runner.close()
    finally:
        gauges.stop()
        simulator.stop()
