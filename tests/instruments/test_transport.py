"""Opening ports by URL, and the sentence each failure a technician meets gets."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import tty
from pathlib import Path

import pytest

from station.errors import StationError
from station.instruments.base import SerialSettings
from station.instruments.transport import PortInfo, list_ports, open_port, url_scheme

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture
def pty_path():
    master, slave = os.openpty()
    tty.setraw(slave)
    path = os.ttyname(slave)
    yield path
    os.close(master)
    os.close(slave)


def test_a_pty_opens_with_the_settings_and_carries_bytes(pty_path: str) -> None:
    port = open_port(pty_path, SerialSettings(4800, 7, "E", 2), timeout=0.5)
    try:
        assert port.baudrate == 4800 and port.bytesize == 7 and port.parity == "E"
        assert port.stopbits == 2 and port.timeout == 0.5
    finally:
        port.close()


def test_socket_url_opens_against_a_listening_port() -> None:
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen(1)
        port = open_port(f"socket://127.0.0.1:{server.getsockname()[1]}")
        conn, _ = server.accept()
        with conn:
            conn.sendall(b"01A+0000.123\r")
            assert port.read_until(b"\r") == b"01A+0000.123\r"
        port.close()


def test_missing_device_names_the_ports_that_exist() -> None:
    with pytest.raises(StationError) as caught:
        open_port("/dev/ttyUSB_station_missing")
    message = caught.value.message
    assert message.startswith("There is no serial port /dev/ttyUSB_station_missing")
    existing = [p.device for p in list_ports()]
    if existing:
        assert existing[0] in message
    else:
        assert "lists no serial ports" in message
    assert caught.value.exit_code == 2


def test_missing_by_id_path() -> None:
    with pytest.raises(StationError, match="There is no serial port /dev/serial/by-id/usb-none"):
        open_port("/dev/serial/by-id/usb-none")


def test_busy_port_says_another_program_has_it(pty_path: str) -> None:
    first = open_port(pty_path)
    try:
        with pytest.raises(StationError) as caught:
            open_port(pty_path)
    finally:
        first.close()
    assert "is busy: another program has it open" in caught.value.message
    assert f"fuser -v {pty_path}" in caught.value.message


def test_refused_device_server() -> None:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        closed_port = probe.getsockname()[1]
    for scheme in ("socket", "rfc2217"):
        with pytest.raises(StationError) as caught:
            open_port(f"{scheme}://127.0.0.1:{closed_port}")
        assert "refused the connection" in caught.value.message
        assert "ser2net" in caught.value.message


@pytest.mark.parametrize(
    ("url", "sentence"),
    [
        ("bogus://x", "is not a port URL"),
        ("socket://127.0.0.1", "is not a usable network port"),
        ("hwgrep://ffff:fffe", "No serial port matches hwgrep://ffff:fffe"),
        ("/tmp", "is not a serial port"),
        ("", "No port given"),
    ],
)
def test_bad_urls(url: str, sentence: str) -> None:
    with pytest.raises(StationError, match=sentence):
        open_port(url)


def test_a_file_that_is_not_a_tty(tmp_path: Path) -> None:
    plain = tmp_path / "notatty"
    plain.write_text("")
    with pytest.raises(StationError, match="is not a serial port"):
        open_port(str(plain))


PERMISSION_PROBE = """
import os, sys
import serial, serial.tools.list_ports
from station.errors import StationError
from station.instruments.transport import open_port
# Imports first: the interpreter's own files may not be readable by nobody.
os.setgroups([]); os.setgid(65534); os.setuid(65534)
try:
    open_port(sys.argv[1])
except StationError as error:
    print(error.message)
"""


def test_permission_denied_names_the_dialout_group(pty_path: str) -> None:
    os.chmod(pty_path, 0o000)
    if os.geteuid() != 0:
        with pytest.raises(StationError) as caught:
            open_port(pty_path)
        message = caught.value.message
    else:
        # root ignores file modes: open the port as `nobody` in a real child process.
        result = subprocess.run(
            [sys.executable, "-c", PERMISSION_PROBE, pty_path],
            capture_output=True,
            text=True,
            cwd=REPO,
            timeout=30,
        )
        if result.returncode != 0:
            pytest.skip(f"running as root and cannot act as user nobody: {result.stderr[-200:]}")
        message = result.stdout.strip()
    assert message.startswith(f"Permission denied opening {pty_path}")
    assert "dialout" in message and "log out and in again" in message


def test_url_scheme() -> None:
    assert url_scheme("/dev/ttyUSB0") is None
    assert url_scheme("RFC2217://host:2013") == "rfc2217"
    assert url_scheme("socket://127.0.0.1:1") == "socket"


def test_list_ports_returns_port_infos() -> None:
    ports = list_ports()
    assert all(isinstance(p, PortInfo) for p in ports)
    assert [p.device for p in ports] == sorted(p.device for p in ports)
    assert not any(p.device.startswith("/dev/pts/") for p in ports)
