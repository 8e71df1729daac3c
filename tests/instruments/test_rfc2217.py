"""RFC 2217 end to end: a real ser2net bridges a simulator pty to a loopback port.

``station read --port rfc2217://127.0.0.1:PORT`` must print the simulator's values. The URL
carries ``?ign_set_control``: ser2net cannot set DTR/RTS on a pseudo-terminal and then never
confirms the modem-line request, which pyserial would otherwise wait for (a real serial port
behind ser2net answers it).
"""

from __future__ import annotations

import json
import os
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from station.instruments.protocols import get_protocol
from station.instruments.simulator import AxisModel, Simulator, fixture_model

SER2NET = shutil.which("ser2net") or (
    "/usr/sbin/ser2net" if os.path.exists("/usr/sbin/ser2net") else None
)

pytestmark = pytest.mark.skipif(
    SER2NET is None, reason="ser2net is not installed (apt-get install -y ser2net)"
)


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _wait_listening(port: int, process: subprocess.Popen, timeout: float = 10.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if process.poll() is not None:
            pytest.fail(f"ser2net exited: {process.communicate()[0]}")
        # /proc/net/tcp lists listening sockets without opening a connection to ser2net.
        table = Path("/proc/net/tcp").read_text()
        if f":{port:04X} 00000000:0000 0A" in table:
            return
        time.sleep(0.05)
    pytest.fail(f"ser2net did not listen on {port}")


@pytest.fixture
def bridged(tmp_path: Path):
    sim = Simulator(
        get_protocol("mitutoyo"),
        fixture_model(["x", "y", "z"], axis=AxisModel(bias=0.05, noise=0.01)),
        seed=21,
    )
    pty = sim.start_pty()
    port = _free_port()
    config = tmp_path / "ser2net.yaml"
    config.write_text(
        "connection: &gauges\n"
        f"  accepter: telnet(rfc2217),tcp,127.0.0.1,{port}\n"
        f"  connector: serialdev,{pty},9600n81,local\n"
    )
    # -n: foreground; -u: no UUCP lock files; -c: this config only.
    process = subprocess.Popen(
        [SER2NET, "-n", "-u", "-c", str(config)],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        _wait_listening(port, process)
        yield sim, port
    finally:
        process.terminate()
        try:
            process.communicate(timeout=5)
        except subprocess.TimeoutExpired:
            process.kill()
            process.communicate()
        sim.stop()


def test_station_read_through_ser2net(bridged) -> None:
    sim, port = bridged
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "station",
            "read",
            "--port",
            f"rfc2217://127.0.0.1:{port}?ign_set_control",
            "--protocol",
            "mitutoyo",
            "--map",
            "1=x,2=y,3=z",
            "--count",
            "6",
            "--jsonl",
            "--interval",
            "0.05",
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    lines = [json.loads(line) for line in result.stdout.splitlines()]
    assert len(lines) == 6
    assert [line["channel"] for line in lines] == ["x", "y", "z", "x", "y", "z"]
    for index, line in enumerate(lines):
        expected = sim.expected(line["channel"], index // 3)
        assert line["value"] == pytest.approx(expected)
        assert line["unit"] == "mm"
        assert line["raw"].startswith(f"0{index % 3 + 1}A")
    assert "Traceback" not in result.stderr
