"""Stabilisation time and overshoot end to end, headless: ``station capture`` of the shipped
``stabilisation`` procedure (a real process) against ``station simulate --settling`` (a real
process on a real pty, its robot ringing on arrival with a known overshoot and decay), then
``station analyze`` of the session file, recomputed from the traces it keeps."""

from __future__ import annotations

import json
import math
import subprocess
from pathlib import Path

import pytest
from helpers import STATION, run_station, start_simulator, stop_simulator

from station.instruments.motion import CycleMotion, Settling, default_free_travel

PERIOD = 1.5
SWING = {"x": 0.03, "y": 0.04, "z": 0.0}
"""Each axis's first swing past its rest position (mm): an overshoot of 0.05 as a distance."""
RINGING = Settling(SWING, period=0.1, decay=0.05)
BAND = 0.01
"""The band stated to the analysis (mm): wide enough that 100 points a second see the robot
cross it (a band narrower than the move between two points is said to be doubtful)."""
PUSH_RATE = 100.0


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """Three returns captured under the arrival trigger, each trace kept."""
    folder = tmp_path_factory.mktemp("sessions")
    swings = ",".join(f"{c}={v}" for c, v in SWING.items())
    process, url = start_simulator(
        "--protocol", "mitutoyo", "--cycle-period", str(PERIOD), "--settling", swings,
        "--settling-period", str(RINGING.period), "--settling-decay", str(RINGING.decay),
        "--push-rate", str(PUSH_RATE), "--noise", "0.002", "--seed", "4",
    )  # fmt: skip
    try:
        done = subprocess.run(
            [
                *STATION,
                "capture",
                "--procedure",
                "stabilisation",
                "--port",
                url,
                "--protocol",
                "mitutoyo",
                "--map",
                "1=x,2=y,3=z",
                "--robot",
                "R1",
                "--sessions",
                str(folder),
                "--timeout",
                "5",
            ],  # fmt: skip
            capture_output=True,
            text=True,
            timeout=120,
            stdin=subprocess.DEVNULL,
        )
    finally:
        stop_simulator(process)
    assert done.returncode == 0, done.stderr
    return next(folder.glob("*.jsonl")), done.stdout


def analyze_json(*args: str | Path) -> dict:
    done = run_station("analyze", *map(str, args), "--json")
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def test_the_injected_overshoot_and_stabilisation_time_are_recovered(session) -> None:
    path, summary = session
    found = analyze_json(path, "--band", str(BAND))["stabilisation"]
    assert found["band"] == BAND and found["band_stated"] is True
    assert [r["cycle"] for r in found["returns"]] == [1, 2, 3]
    # The truth, in closed form: the approach (about 9.525 mm on each axis) comes within the
    # band a few ms before it ends, and the ringing's distance leaves it for the last time when
    # its envelope has decayed enough.
    travel = abs(default_free_travel("mm")) * math.sqrt(3)
    motion = CycleMotion(PERIOD, default_free_travel("mm"), 0.0, settling=RINGING)
    truth = motion.stabilisation_time(BAND, travel, "xyz")
    for r in found["returns"]:
        interval = r["sampling_interval"]
        assert interval == pytest.approx(1 / PUSH_RATE, rel=0.2)
        assert r["settled"]
        # Each end of the time is found within one sampling interval; the gauges' own noise
        # (a third of a 0.001 step) and the step itself move the crossings by a hair more.
        assert r["time"] == pytest.approx(truth, abs=2 * interval + 0.002)
        # Where the approach moved more than the band between two points near it, the report
        # says the time may be longer, up to a bound that holds the truth.
        if r["time_max"] is not None:
            assert truth <= r["time_max"] + 2 * interval
        # The peak is seen to within what the ringing moves in half an interval (a point
        # falls within that of it) and two gauge steps of rounding and noise.
        slack = 0.05 * (1 - math.cos(math.pi * interval / RINGING.period)) + 0.002
        assert RINGING.overshoot_distance("xyz") - slack <= r["overshoot"]
        assert r["overshoot"] <= RINGING.overshoot_distance("xyz") + 0.002
        for axis, past in zip("xyz", r["overshoot_axes"], strict=True):
            assert past == pytest.approx(SWING[axis], abs=slack)
    assert found["mean_time"] == pytest.approx(truth, abs=2 * found["sampling_interval"] + 0.002)
    assert found["max_overshoot"] <= RINGING.overshoot_distance("xyz") + 0.002
    # The capture's own report says it, with the band from the noise and its basis.
    text = " ".join(summary.split())
    assert "ISO 9283 POSITION STABILISATION TIME AND OVERSHOOT" in text
    assert "5 × the indicators' noise at rest" in text


def test_the_session_keeps_each_returns_trace_bounded(session) -> None:
    path, _ = session
    traces = [
        json.loads(line)
        for line in path.read_text().splitlines()
        if json.loads(line).get("type") == "trace"
    ]
    assert [t["cycle"] for t in traces] == [1, 2, 3]
    for trace in traces:
        assert trace["channels"] == ["x", "y", "z"] and len(trace["values"]) <= 400
        # From the approach (before the first arrival, t < 0) to the rest.
        assert trace["times"][0] < 0 < trace["times"][-1]
