"""``station simulate --model joints``: the arm's per-joint returns on a real pty."""

from __future__ import annotations

import subprocess

import pytest
from helpers import STATION, start_simulator, stop_simulator

from station.instruments.joint_model import faulty_arm
from station.instruments.protocols import get_protocol
from station.instruments.simulator import GaugeSpec
from station.instruments.transport import open_port


def test_joints_model_serves_the_faulty_arm_and_names_the_joint_to_move() -> None:
    process, url = start_simulator(
        "--protocol",
        "idh",
        "--model",
        "joints",
        "--faulty-joint",
        "1",
        "--joint-fault",
        "backlash",
        "--fault-size",
        "8e-5",
        "--cycles-per-joint",
        "4",
        "--seed",
        "7",
    )
    try:
        protocol = get_protocol("idh")
        port = open_port(url, protocol.settings, timeout=2.0)
        try:
            values = []
            for _ in range(4):
                port.write(protocol.request("1"))
                values.append(protocol.parse(port.read_until(protocol.terminator).strip()).value)
        finally:
            port.close()
    finally:
        err = stop_simulator(process)
    arm = faulty_arm(1, "backlash", size=8e-5, cycles=4, gauge=GaugeSpec(0.0001, -0.5, 0.5, "in"))
    assert values == pytest.approx([arm.value("x", k, 7) for k in range(4)], abs=1e-9)
    # Backlash of 8e-5 rad, x seeing 17.9 in per radian of joint 1: x alternates by 0.0014 in.
    assert abs((values[0] + values[2]) - (values[1] + values[3])) / 2 > 0.001
    assert "joint 1: move only joint 1 away and back (lever arm 31.177 in)" in err
    assert process.returncode == 0


def test_a_faulty_joint_out_of_range_is_a_sentence() -> None:
    result = subprocess.run(
        [*STATION, "simulate", "--protocol", "idh", "--model", "joints", "--faulty-joint", "4"],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert result.returncode == 2
    assert "the faulty joint is 1, 2 or 3, not 4" in result.stderr
