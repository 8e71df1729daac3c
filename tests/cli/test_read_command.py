"""``station read`` as a real subprocess against the simulator on a real pty."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys

import pytest

from station.instruments.protocols import get_protocol
from station.instruments.simulator import AxisModel, Faults, Simulator, fixture_model

STATION = [sys.executable, "-m", "station"]


def station(*args: str, timeout: float = 30) -> subprocess.CompletedProcess:
    return subprocess.run([*STATION, *args], capture_output=True, text=True, timeout=timeout)


def make_sim(name: str = "mitutoyo", faults: Faults | None = None, **kwargs) -> Simulator:
    channels = ["x", "y", "z"] if name in ("mitutoyo", "uwave") else ["x"]
    model = fixture_model(channels, axis=AxisModel(bias=0.03, noise=0.01))
    return Simulator(get_protocol(name), model, faults, seed=13, **kwargs)


def test_count_jsonl_prints_the_simulators_values() -> None:
    sim = make_sim()
    url = sim.start_pty()
    try:
        result = station(
            "read",
            "--port",
            url,
            "--protocol",
            "mitutoyo",
            "--map",
            "1=x,2=y,3=z",
            "--count",
            "5",
            "--jsonl",
            "--interval",
            "0.02",
        )
    finally:
        sim.stop()
    assert result.returncode == 0, result.stderr
    lines = [json.loads(line) for line in result.stdout.splitlines()]
    assert len(lines) == 5
    channels = ["x", "y", "z", "x", "y"]
    assert [line["channel"] for line in lines] == channels
    for index, line in enumerate(lines):
        assert set(line) == {"channel", "value", "unit", "raw"}
        assert line["value"] == pytest.approx(sim.expected(channels[index], index // 3))
        assert line["unit"] == "mm"
        assert line["raw"] == sim.sent[channels[index]][index // 3].frame.decode().strip()


def test_a_rejected_frame_gets_its_line() -> None:
    sim = make_sim("sylvac", Faults(error_rate=0.5))
    # Two ports: some kernels refuse a second open of a pty at Sylvac's 7E2 (see transport).
    url = sim.start_pty()
    try:
        jsonl = station(
            "read",
            "--port",
            url,
            "--protocol",
            "sylvac",
            "--count",
            "4",
            "--jsonl",
            "--interval",
            "0.02",
        )
    finally:
        sim.stop()
    url = sim.start_tcp(0)
    try:
        text = station(
            "read",
            "--port",
            url,
            "--protocol",
            "sylvac",
            "--count",
            "3",
            "--interval",
            "0.02",
        )
    finally:
        sim.stop()
    assert jsonl.returncode == 0, jsonl.stderr
    lines = [json.loads(line) for line in jsonl.stdout.splitlines()]
    rejected = [line for line in lines if "rejected" in line]
    readings = [line for line in lines if "channel" in line]
    assert rejected and all(r == {"rejected": "error", "raw": "ERR0"} for r in rejected)
    assert [r["value"] for r in readings] == pytest.approx(sim.sent_values("x")[:4])
    assert text.returncode == 0, text.stderr
    assert "rejected (error): " in text.stdout and "[ERR0]" in text.stdout
    assert f"{sim.sent_values('x')[4]:+.3f} mm" in text.stdout


def test_push_protocol_prints_readings_as_they_arrive() -> None:
    sim = make_sim("uwave", push_rate=40)
    url = sim.start_tcp(0)
    try:
        result = station("read", "--port", url, "--protocol", "uwave", "--count", "6")
    finally:
        sim.stop()
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert len(lines) == 6
    # Unmapped: the device's own channel numbers, each line with value, unit and raw frame.
    assert lines[0].split()[0] in {"1", "2", "3"}
    assert all(" mm  DT1" in line for line in lines)
    # Review finding 14: every value at the resolution's decimals ("+0.000", never "+0").
    assert all(re.fullmatch(r"[+-]\d+\.\d{3}", line.split()[1]) for line in lines), lines


def test_a_zero_reading_keeps_its_decimals() -> None:
    """Review finding 14: {value:+.6g} printed "+0 mm" beside "-0.001 mm"."""
    model = fixture_model(["x", "y", "z"], axis=AxisModel(bias=0.0, noise=0.0))
    sim = Simulator(get_protocol("uwave"), model, None, seed=13, push_rate=40)
    url = sim.start_tcp(0)
    try:
        result = station("read", "--port", url, "--protocol", "uwave", "--count", "3")
    finally:
        sim.stop()
    assert result.returncode == 0, result.stderr
    assert [line.split()[1:3] for line in result.stdout.splitlines()] == [["+0.000", "mm"]] * 3


def test_values_are_shown_at_the_resolutions_decimals() -> None:
    from station.commands.read import value_text

    assert value_text(0.0, 0.001) == "+0.000"
    assert value_text(-0.001, 0.001) == "-0.001"
    assert value_text(0.0001, 0.0001) == "+0.0001"
    assert value_text(12.5, 0.01) == "+12.50"
    # A gauge finer than --resolution keeps its digits rather than being rounded.
    assert value_text(0.0012, 0.001) == "+0.0012"


@pytest.mark.parametrize(
    ("args", "sentence"),
    [
        (
            ["--port", "/dev/ttyUSB_station_none"],
            "There is no serial port /dev/ttyUSB_station_none",
        ),
        (["--port", "socket://127.0.0.1:1"], "refused the connection"),
        (["--port", "/dev/null", "--map", "1x"], "--map: '1x' is not DEVICE=CHANNEL"),
        (["--port", "/dev/null", "--count", "zero"], "--count 'zero' is not a number"),
    ],
)
def test_bad_input_exits_2_with_one_sentence(args: list[str], sentence: str) -> None:
    result = station("read", "--protocol", "mitutoyo", *args)
    assert result.returncode == 2
    assert result.stderr.startswith("station: ")
    assert sentence in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
    assert result.stdout == ""


def test_ctrl_c_exits_cleanly() -> None:
    sim = make_sim("uwave")  # push on demand only: the reader waits
    url = sim.start_pty()
    process = subprocess.Popen(
        [*STATION, "read", "--port", url, "--protocol", "uwave"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        # Wait until the reader says it reads (frames pushed before that are flushed on open).
        banner = ""
        while "Ctrl-C stops" not in banner:
            banner = process.stderr.readline()
            assert banner, "station read ended before reading"
        sim.push()
        first = process.stdout.readline()
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=10)
    finally:
        if process.poll() is None:
            process.kill()
        sim.stop()
    out = first + out
    assert process.returncode in (0, 130)
    assert "Traceback" not in err
    assert "DT1" in out
