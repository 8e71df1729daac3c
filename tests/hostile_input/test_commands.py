"""Issue 12, findings 1 and 2: the hostile corpus through every command, as real processes.

Each command gets the corpus where it takes text from outside (a session header, notes and
reject reasons, CSV column names, procedure titles, gauge frames, file names, option values);
its output must hold no raw control character, no bidi override, and show the text instead.
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest
from helpers import run_station
from hostile import (
    HOSTILE_PROCEDURE,
    LONG,
    MARKUP_CLOSE,
    OSC_TITLE,
    SHORT_HOSTILE,
    hostile_session,
    raw_controls,
)

from station.instruments.protocols import get_protocol

REPO = Path(__file__).resolve().parents[2]


def station(*args: str | Path, env: dict | None = None, timeout: float = 60):
    """``station ARGS`` in this process, with ``env`` added to the environment."""
    return run_station(*args, cwd=REPO, env={**os.environ, **(env or {})})


def assert_plain(result: subprocess.CompletedProcess[str]) -> None:
    for stream in (result.stdout, result.stderr):
        assert raw_controls(stream) == [], stream[-2000:]
        assert "Traceback" not in stream, stream[-2000:]


@pytest.fixture(scope="module")
def session(tmp_path_factory) -> Path:
    return hostile_session(tmp_path_factory.mktemp("hostile-sessions"))


def test_analyze_shows_a_hostile_session_header_as_text(session: Path) -> None:
    result = station("analyze", session)
    assert result.returncode == 0, result.stderr
    assert_plain(result)
    # The escapes are visible, the markup is text.
    assert "\\x1b]0;pwned\\x07" in result.stdout or "\\x1b]0;pwned\\x07" in result.stderr
    json_result = station("analyze", session, "--json")
    assert json_result.returncode == 0 and raw_controls(json_result.stdout) == []


def test_analyze_shows_hostile_csv_column_names_as_text(tmp_path: Path) -> None:
    table = tmp_path / "t.csv"
    name = OSC_TITLE + MARKUP_CLOSE + "\u202e"
    table.write_text(f'"{name}"\n' + "".join(f"{v / 10000}\n" for v in range(-5, 25)))
    result = station("analyze", table)
    assert result.returncode == 0, result.stderr
    assert_plain(result)
    assert "\\x1b]0;pwned\\x07[/]\\u202e" in result.stdout


def test_verify_and_export_show_a_hostile_file_name_and_reasons(tmp_path: Path, session) -> None:
    hostile_name = tmp_path / f"s{OSC_TITLE}\u202e.jsonl"
    hostile_name.write_bytes(session.read_bytes())
    # The module's session was recorded with another test's key: another station's, untrusted.
    verify = station("verify", "--trust-any", hostile_name)
    assert verify.returncode == 0, verify.stdout + verify.stderr
    assert_plain(verify)
    assert "\\x1b]0;pwned" in verify.stdout
    export = station("export", hostile_name, "--csv")
    assert export.returncode == 0, export.stderr
    assert_plain(export)
    assert "rejected: [/] KR16 [cell 3]" in export.stdout


def test_procedures_lists_a_hostile_title_as_text(tmp_path: Path) -> None:
    folder = tmp_path / "procedures"
    folder.mkdir()
    (folder / "hostile.toml").write_text(HOSTILE_PROCEDURE)
    result = station("procedures", "--procedures", folder)
    assert result.returncode == 0, result.stdout + result.stderr
    assert_plain(result)
    assert "hostile" in result.stdout and "\\x1b[2J" in result.stdout


def test_capture_and_simulate_messages_carry_hostile_values_as_text(tmp_path: Path) -> None:
    capture = station(
        "capture", "--procedure", "repeatability", "--port", f"/nonexistent/{OSC_TITLE}",
        "--protocol", "mitutoyo", "--robot", SHORT_HOSTILE, "--sessions", tmp_path,
        "--timeout", "0.5",
    )  # fmt: skip
    assert capture.returncode != 0
    assert_plain(capture)
    simulator = subprocess.Popen(
        [sys.executable, "-m", "station", "simulate", "--protocol", "mitutoyo",
         "--channels", f"x,{OSC_TITLE}"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=REPO,
    )  # fmt: skip
    try:
        first = simulator.stderr.readline()
    finally:
        simulator.terminate()
        out, rest = simulator.communicate(timeout=20)
    assert "simulating" in first and "\\x1b]0;pwned" in first
    assert_plain(subprocess.CompletedProcess([], 0, out, first + rest))
    ports = station("ports")
    assert_plain(ports)


@pytest.fixture
def hostile_gauge() -> Iterator[str]:
    """A TCP 'gauge' that sends hostile lines between real Mitutoyo frames."""
    protocol = get_protocol("mitutoyo")
    frame = protocol.encode(protocol.channels[0], 0.0012, 0.0001, "in")
    server = socket.create_server(("127.0.0.1", 0))
    stop = threading.Event()

    def serve() -> None:
        server.settimeout(5)
        try:
            connection, _ = server.accept()
        except OSError:
            return
        with connection:
            connection.settimeout(0.05)
            while not stop.is_set():
                try:
                    connection.sendall(
                        (OSC_TITLE + "\x1b[2J\u202e[/]\r\n").encode() + frame + b"\r\n"
                    )
                    connection.recv(100)
                except TimeoutError:
                    continue
                except OSError:
                    return

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    yield f"socket://127.0.0.1:{server.getsockname()[1]}"
    stop.set()
    server.close()
    thread.join(2)


def test_read_prints_rejected_hostile_frames_as_text(hostile_gauge: str) -> None:
    result = station(
        "read", "--port", hostile_gauge, "--protocol", "mitutoyo", "--trigger", "push",
        "--count", "2", timeout=30,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert_plain(result)
    assert "\\x1b]0;pwned" in result.stdout


def test_a_100k_character_robot_name_is_analyzed_without_trouble(tmp_path: Path) -> None:
    path = hostile_session(tmp_path, robot=LONG + OSC_TITLE)
    result = station("analyze", path)
    assert result.returncode == 0, result.stderr
    assert_plain(result)
