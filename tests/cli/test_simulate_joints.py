"""``station simulate --model joints``: the arm's per-joint returns on a real pty."""

from __future__ import annotations

import subprocess

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
        "--gauge-noise",
        "0",
    )
    try:
        protocol = get_protocol("idh")
        port = open_port(url, protocol.settings, timeout=2.0)
        try:
            values = []
            for _ in range(3):  # the taught position, however often it is read
                port.write(protocol.request("1"))
                values.append(protocol.parse(port.read_until(protocol.terminator).strip()).value)
        finally:
            port.close()
    finally:
        err = stop_simulator(process)
    inch = GaugeSpec(0.0001, -0.5, 0.5, "in")
    arm = faulty_arm(1, "backlash", size=8e-5, cycles=4, home_readings=1, gauge=inch)
    # The still arm stands at the taught position (its first rest): no angular error there.
    assert values == [0.0, 0.0, 0.0]
    # Its returns, rest by rest (what the simulator shows as the arm leaves and comes back):
    # backlash of 8e-5 rad, x seeing 17.9 in per radian of joint 1, alternates by 0.0014 in.
    returns = [arm.value("x", k, 7) for k in range(1, 5)]
    assert abs((returns[0] + returns[2]) - (returns[1] + returns[3])) / 2 > 0.001
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
