"""A zero is taken only with the robot at the fixture, from any phase of its loop (issue 27,
finding 0).

Headless, the README's own example zeroed the indicators at their free-travel stop in 1 of 6
runs (``zeroed x -0.37500 (7 readings, spread 0.00000)``): plungers resting at their stop are
perfectly still. Every later "cycle" was then taken at the stop (+0.0000, σ 0, Cpk 6.50): a
robot never measured. Here the engine zeroes a simulated robot that leaves and returns by
itself, starting at ten phases of its cycle (each simulator's clock is set so the session
starts at that phase), and a real ``station capture`` process starts while the robot is away.
"""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from station.instruments.motion import CycleMotion
from station.instruments.protocols import get_protocol
from station.instruments.simulator import AxisModel, GaugeSpec, Simulator, fixture_model
from station.procedures import discover_procedures
from station.run import PortSetup, Runner, SessionSetup, open_gauges
from station.session.model import load_session

PERIOD = 1.5
FREE = -0.375
INDICATOR = GaugeSpec(0.0001, -0.5, 1.0, "in", noise=0.00003)


def moving_robot(phase: float) -> Simulator:
    """A fixture robot on its loop, its clock set so that it is ``phase`` into its cycle."""
    model = fixture_model("xyz", axis=AxisModel(noise=0.0003), gauge=INDICATOR)
    simulator = Simulator(
        get_protocol("mitutoyo"), model, seed=11, motion=CycleMotion(PERIOD, FREE, 0.002)
    )
    simulator.start_pty()
    simulator.motion_t0 = time.monotonic() - phase * PERIOD
    return simulator


def setup_on(simulator: Simulator) -> SessionSetup:
    return SessionSetup(
        procedure=discover_procedures(use_env=False).get("repeatability"),
        robot="KSC-7",
        operator="tester",
        ports=(PortSetup(simulator.url, "mitutoyo", dict(simulator.channel_map)),),
        trigger="arrival",
        cycles=2,
    )


def capture_command(simulator: Simulator, folder: Path, *extra: str) -> list[str]:
    """``station capture`` of the repeatability procedure on ``simulator``'s line."""
    return [
        *(sys.executable, "-m", "station", "capture", "--procedure", "repeatability"),
        *("--port", simulator.url, "--protocol", "mitutoyo", "--robot", "R1"),
        *("--sessions", str(folder), *extra),
    ]


def zero_of(simulator: Simulator, folder: Path, outcome: dict) -> None:
    """Walk the session to its zero and zero (the engine's own wait), then take one cycle."""
    gauges = open_gauges(setup_on(simulator), backoff=(0.05, 0.2))
    try:
        assert gauges.wait_connected(5.0)
        runner = Runner.start(setup_on(simulator), gauges, folder)
        try:
            while runner.state().action.kind == "confirm":
                runner.confirm()
            assert runner.state().action.kind == "zero"
            runner.zero(timeout=4 * PERIOD)
            while runner.state().action.kind == "confirm":
                runner.confirm()
            outcome["cycle"] = runner.capture(4 * PERIOD)
        finally:
            runner.close()
        outcome["zero"] = load_session(runner.path).zeroes[-1]
    except BaseException as error:  # reported by the test thread
        outcome["error"] = error
    finally:
        gauges.stop()


def test_the_engine_zeroes_at_the_fixture_from_ten_phases_of_the_robots_cycle(
    tmp_path: Path,
) -> None:
    phases = [k / 10 for k in range(10)]
    outcomes: list[dict] = [{} for _ in phases]
    # Five sessions at a time: each reads its gauges ten times a second, and ten of them in
    # one process on two cores would starve the readings the rests are judged from.
    for batch in (range(0, 5), range(5, 10)):
        simulators = {k: moving_robot(phases[k]) for k in batch}
        threads = [
            threading.Thread(target=zero_of, args=(sim, tmp_path / f"p{k}", outcomes[k]))
            for k, sim in simulators.items()
        ]
        try:
            for thread in threads:
                thread.start()
            for thread in threads:
                thread.join(60.0)
        finally:
            for simulator in simulators.values():
                simulator.stop()
    for phase, outcome in zip(phases, outcomes, strict=True):
        assert "error" not in outcome, (phase, outcome.get("error"))
        for channel, entry in outcome["zero"]["channels"].items():
            # At the fixture the indicators read within a few thousandths of their zero;
            # at the stop -0.375.
            assert abs(entry["mean"]) < 0.01, (phase, channel, entry)
            assert entry["n"] > 1
        cycle = outcome["cycle"]
        assert cycle.recorded, (phase, cycle.message)
        assert all(abs(v) < 0.01 for v in cycle.cycle.values.values()), (phase, cycle.cycle)


def test_a_headless_capture_started_while_the_robot_is_away_measures_the_robot(
    tmp_path: Path,
) -> None:
    """The README's headless example as a real process, started with the robot away."""
    stage_away = 0.55  # of the period: the indicators at their stop (dwell 0.35, depart 0.1)
    simulator = moving_robot(stage_away)
    try:
        done = subprocess.run(
            capture_command(simulator, tmp_path, "--cycles", "3"),
            capture_output=True,
            text=True,
            timeout=60,
            stdin=subprocess.DEVNULL,
        )
    finally:
        simulator.stop()
    assert done.returncode == 0, done.stderr
    session = load_session(next(tmp_path.glob("*.jsonl")))
    zero = session.zeroes[-1]
    assert all(abs(entry["mean"]) < 0.01 for entry in zero["channels"].values()), zero
    cycles = [e for e in session.events if e["type"] == "reading"]
    assert len(cycles) == 3
    # The robot's own spread (0.0003 in) shows: not a perfect robot read at the plungers' stop.
    spread = {c: {e["channels"][c]["value"] for e in cycles} for c in "xyz"}
    assert any(len(values) > 1 for values in spread.values()), spread


@pytest.mark.parametrize("trigger", ["poll"])
def test_a_polled_set_at_a_known_stop_is_no_cycle(tmp_path: Path, trigger: str) -> None:
    """Once the stop is known (stated by the procedure here), a set read there is refused
    with a sentence naming the channels, under every trigger."""
    from dataclasses import replace

    model = fixture_model("xyz", axis=AxisModel(noise=0.0003), gauge=INDICATOR)
    simulator = Simulator(get_protocol("mitutoyo"), model, seed=11)
    simulator.start_pty()
    procedure = discover_procedures(use_env=False).get("repeatability")
    stated = replace(procedure.arrival, free_travel=dict.fromkeys("xyz", 0.0))
    setup = replace(setup_on(simulator), procedure=replace(procedure, arrival=stated))
    setup = replace(setup, trigger=trigger)
    gauges = open_gauges(setup, backoff=(0.05, 0.2))
    try:
        assert gauges.wait_connected(5.0)
        result = gauges.capture(3.0)
    finally:
        gauges.stop()
        simulator.stop()
    assert result.at_stop == ("x", "y", "z")
    assert "read their free-travel stop: the robot is away from the fixture" in result.message


def test_a_capture_that_takes_nothing_says_so_and_what_to_check(tmp_path: Path) -> None:
    """A robot standing still (its stop never seen): the zero waits for it as the cycles do,
    and after --idle-report seconds the capture says what the gauges see and what to check,
    again and again, instead of waiting in silence (it was killed in the finding)."""
    import signal

    model = fixture_model("xyz", axis=AxisModel(noise=0.0003), gauge=INDICATOR)
    simulator = Simulator(get_protocol("mitutoyo"), model, seed=11)
    simulator.start_pty()
    process = subprocess.Popen(
        capture_command(simulator, tmp_path, "--idle-report", "1", "--timeout", "1"),
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    lines: list[str] = []
    try:
        assert process.stderr is not None
        while sum("nothing taken for" in line for line in lines) < 2:
            line = process.stderr.readline()
            assert line, f"capture ended: {lines}"
            lines.append(line)
    finally:
        process.send_signal(signal.SIGTERM)
        process.communicate(timeout=30)
        simulator.stop()
    waiting = next(line for line in lines if line.startswith("station: waiting: "))
    assert "free-travel stop is not known yet" in waiting
    report = next(line for line in lines if "nothing taken for" in line)
    assert "(step 'Zero the indicators')" in report
    assert "move it away and back to the taught point" in report
    assert "check that the robot's playback loop runs" in report
    assert process.returncode == 143
    assert not load_session(next(tmp_path.glob("*.jsonl"))).zeroes  # nothing was zeroed
