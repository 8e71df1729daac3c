"""The gauge check, per-joint troubleshooting and gain schedule end to end: ``station capture``
against ``station simulate`` (real processes on a real pty), then the session file analysed
(``station analyze FILE --json``) and the gauge check filed in the gauge register."""

from __future__ import annotations

import datetime as dt
import json
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from station.session.gauge_register import coverage, coverage_lines
from station.session.method_reports import (
    gauge_check_from_session,
    joints_from_session,
    method_count,
    record_gauge_check,
)
from station.session.model import load_session

STATION = [sys.executable, "-m", "station"]


def simulate(*args: str, protocol: str = "idh") -> tuple[subprocess.Popen, str]:
    process = subprocess.Popen(
        [*STATION, "simulate", "--protocol", protocol, *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    url = process.stdout.readline().strip()
    if not url:
        process.kill()
        pytest.fail(f"the simulator gave no URL: {process.communicate()[1]}")
    return process, url


def capture(url: str, folder: Path, procedure: str, *extra: str, protocol: str = "idh") -> Path:
    done = subprocess.run(
        [
            *STATION,
            "capture",
            "--every",
            "0.01",
            "--procedure",
            procedure,
            "--port",
            url,
            "--protocol",
            protocol,
            "--robot",
            "KSC-7",
            "--sessions",
            str(folder),
            *extra,
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    return next(folder.glob("*.jsonl"))


def analyze_json(path: Path) -> dict:
    result = subprocess.run(
        [*STATION, "analyze", str(path), "--json"], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


# idh zeroes the indicator itself; mitutoyo has no zero command, so the station zeroes in
# software by reading the plate once.
@pytest.mark.parametrize(
    ("bias", "capable", "protocol"), [(0.0, True, "idh"), (0.0003, False, "mitutoyo")]
)
def test_gauge_check_session_is_analysed_and_filed(
    tmp_path: Path, bias: float, capable: bool, protocol: str
):
    simulator, url = simulate(
        "--model",
        "gauge-bench",
        "--reference",
        "0.1",
        "--bias",
        str(bias),
        "--noise",
        "0.00005",
        protocol=protocol,
    )
    try:
        path = capture(
            url,
            tmp_path / "sessions",
            "gauge_check",
            "--cycles",
            "25",
            "--input",
            "gauge=MIT-0042",
            "--input",
            "reference=0.1",
            "--input",
            "tolerance=0.004",
            "--input",
            "calibration_due=2099-01-01",
            protocol=protocol,
        )
    finally:
        simulator.send_signal(signal.SIGTERM)
        simulator.communicate(timeout=10)
    study = analyze_json(path)["gauge_check"]
    assert study["n"] == 25 and study["capable"] is capable
    # A software zero reads the plate once: that reading's own error (noise, and the display's
    # 0.0001 in step) is in every later reading, so the bias is known to about one step.
    assert study["bias"] == pytest.approx(bias, abs=0.00003 if protocol == "idh" else 0.00015)
    session = load_session(path)
    register = tmp_path / "gauges.json"
    record_gauge_check(session, gauge_check_from_session(session), register=register)
    status = coverage({"x": "MIT-0042"}, dt.date.fromisoformat(session.created[:10]), path=register)
    assert status["x"].state == ("passed" if capable else "failed")
    line = coverage_lines(status)[0]
    assert ("gauge check passed on" in line) is capable
    assert method_count("gauge_check", gauge_check_from_session(session)) == "25 readings"


@pytest.mark.parametrize("protocol", ["idh", "mitutoyo"])
def test_joint_troubleshooting_session_names_the_faulty_joint(tmp_path: Path, protocol: str):
    simulator, url = simulate(
        "--model",
        "joints",
        "--faulty-joint",
        "2",
        "--joint-fault",
        "backlash",
        "--seed",
        "5",
        protocol=protocol,
    )
    try:
        path = capture(
            url,
            tmp_path / "sessions",
            "joint_troubleshooting",
            "--placements",
            "3",
            "--input",
            "1:lever=31.177",
            "--input",
            "2:lever=31.241",
            "--input",
            "3:lever=16",
            protocol=protocol,
        )
    finally:
        simulator.send_signal(signal.SIGTERM)
        _, shown = simulator.communicate(timeout=10)
    assert "joint 3: move only joint 3" in shown
    document = analyze_json(path)
    assert document["procedure"] == "joint_troubleshooting"
    assert document["suspect"] == 2 and document["cause"] == "backlash"
    assert all(j["n"] == 25 and j["lever_arm"] for j in document["joints"])
    result = joints_from_session(load_session(path))
    assert method_count("joint_troubleshooting", result) == "3 joints"


def test_gain_schedule_session_from_typed_gains(tmp_path: Path):
    inputs = tmp_path / "gains.csv"
    rows = ["placement,q,kp,ki,kd"]
    for number in range(1, 10):
        q = -30 + 18.75 * (number - 1)
        kp = 2 - 0.03 * q + 4e-4 * q**2 - 1e-6 * q**3
        rows.append(f"{number},{q},{kp},{0.4 + 0.001 * q},{0.07}")
    inputs.write_text("\n".join(rows) + "\n")
    simulator, url = simulate("--channels", "q")
    try:
        path = capture(
            url,
            tmp_path / "sessions",
            "gain_schedule",
            "--map",
            "1=q",
            "--placements",
            "9",
            "--inputs",
            str(inputs),
        )
    finally:
        simulator.send_signal(signal.SIGTERM)
        simulator.communicate(timeout=10)
    document = analyze_json(path)
    assert list(document["gains"]) == ["kp", "ki", "kd"]
    assert document["gains"]["kp"]["order"] == 3
    assert document["gains"]["kp"]["coefficients"] == pytest.approx(
        [2, -0.03, 4e-4, -1e-6], rel=1e-6
    )
    assert document["gains"]["kd"]["order"] == 0
    assert len(document["positions"]) == 9
