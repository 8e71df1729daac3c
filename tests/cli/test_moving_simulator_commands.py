"""``station simulate --cycle-period`` and ``station read --trigger arrival`` as subprocesses."""

from __future__ import annotations

import json
import subprocess

import pytest
from helpers import STATION, start_simulator, stop_simulator

from station.instruments.simulator import AxisModel, FixtureModel, GaugeSpec


def test_read_prints_one_set_per_round_trip_and_what_the_frames_say() -> None:
    simulator, url = start_simulator(
        "--protocol", "mitutoyo", "--cycle-period", "0.5", "--noise", "0.01", "--seed", "9"
    )
    try:
        result = subprocess.run(
            [*STATION, "read", "--port", url, "--protocol", "mitutoyo", "--map", "1=x,2=y,3=z"]
            + ["--trigger", "arrival", "--interval", "0.02", "--settle", "0.08"]
            + ["--count", "6", "--jsonl"],
            capture_output=True,
            text=True,
            timeout=30,
        )
    finally:
        simulator_err = stop_simulator(simulator)
    assert result.returncode == 0, result.stderr
    assert "returns every 0.5 s" in simulator_err
    lines = [json.loads(line) for line in result.stdout.splitlines()]
    assert [line["channel"] for line in lines] == ["x", "y", "z", "x", "y", "z"]
    model = FixtureModel(dict.fromkeys("xyz", AxisModel(noise=0.01)), GaugeSpec(0.001))
    rests = [{c: model.value(c, k, 9) for c in "xyz"} for k in range(40)]
    sets = [{line["channel"]: line["value"] for line in lines[i : i + 3]} for i in (0, 3)]
    # Two rest positions, one per round trip (within the count the settling swing may leave):
    # the next one, or a later one where a loaded machine starved the reader through a trip.
    found = [
        next(k for k, rest in enumerate(rests) if all(abs(s[c] - rest[c]) < 0.0011 for c in s))
        for s in sets
    ]
    assert found[0] < found[1] <= found[0] + 3, found
    assert "station: the robot left the fixture" in result.stderr
    assert "station: x, y, z send steps of 0.001, which is mm on this protocol" in result.stderr
    assert "station: x sends" not in result.stderr  # one line once every channel has spoken


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--free-travel", "-1"], "--free-travel needs --cycle-period"),
        (["--cycle-period", "0"], "--cycle-period"),
        (["--cycle-period", "1", "--model", "bar"], "moves where its procedure's steps take it"),
        (["--cycle-period", "1", "--hunt-every", "0"], "--hunt-every"),
        (["--settling", "0.01"], "--settling needs --cycle-period"),
        (["--cycle-period", "1", "--settling", "0.01", "--overshoot", "0.01"], "give one of them"),
        (["--cycle-period", "1", "--settling", "0.01", "--settling-decay", "0"], "decay"),
    ],
)
def test_motion_options_that_cannot_work_are_one_line_errors(args, message) -> None:
    result = subprocess.run(
        [*STATION, "simulate", "--protocol", "mitutoyo", *args],
        capture_output=True,
        text=True,
        timeout=20,
    )
    assert result.returncode == 2
    assert message in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
