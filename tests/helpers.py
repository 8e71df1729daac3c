"""What several test modules share: ``station`` run in this process (:func:`run_station`, the
fast default) or as a real subprocess (:data:`STATION`, where the process boundary is what the
test is about), ``station simulate`` as a subprocess, and the small procedure files the
procedure and capture tests write, and pseudo-terminals held as another program would.

Imported as ``from helpers import ...``: pytest puts ``tests/`` on ``sys.path`` for the suite's
own ``conftest.py``.
"""

from __future__ import annotations

import contextlib
import io
import os
import signal
import subprocess
import sys
import textwrap
from collections.abc import Iterator, Mapping
from pathlib import Path

import pytest

from station.cli import main as station_main

STATION = [sys.executable, "-m", "station"]
"""The station command as this interpreter runs it, for a real process."""

_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
"""Signals a command may take over; given back to the test runner after each in-process run."""


def run_station(
    *args: str | os.PathLike[str],
    input: str | bytes | None = None,
    env: Mapping[str, str] | None = None,
    cwd: str | os.PathLike[str] | None = None,
) -> subprocess.CompletedProcess[str]:
    """``station ARGS`` run in this process by ``station.cli.main``, answered as
    ``subprocess.run([*STATION, *ARGS], capture_output=True, text=True)`` would be: the exit
    code and what the command wrote, as text (UTF-8, newlines as a pipe gives them).

    ``input``: the command's standard input (else empty; not a terminal, without a file
    descriptor, so a command that reads the terminal's descriptor needs a real process).
    ``env`` replaces the environment and ``cwd`` the working folder for the call. An exception
    the command does not handle is raised here, with its traceback, rather than turned into
    exit 1.
    """
    raw_in = input.encode("utf-8") if isinstance(input, str) else (input or b"")
    out, err = io.BytesIO(), io.BytesIO()
    stdin = io.TextIOWrapper(io.BytesIO(raw_in), encoding="utf-8")
    stdout = io.TextIOWrapper(out, encoding="utf-8", write_through=True)
    stderr = io.TextIOWrapper(err, encoding="utf-8", write_through=True)
    handlers = {number: signal.getsignal(number) for number in _SIGNALS}
    saved = sys.stdin, sys.stdout, sys.stderr
    sys.stdin, sys.stdout, sys.stderr = stdin, stdout, stderr
    try:
        with _environment(env), contextlib.chdir(cwd or os.getcwd()):
            try:
                code = station_main([os.fspath(arg) for arg in args])
            except SystemExit as stop:  # argparse's usage errors and --help
                code = stop.code if isinstance(stop.code, int) else (0 if stop.code is None else 1)
                if isinstance(stop.code, str):
                    print(stop.code, file=sys.stderr)
    finally:
        sys.stdin, sys.stdout, sys.stderr = saved
        for number, handler in handlers.items():
            signal.signal(number, handler)
    return subprocess.CompletedProcess(
        ["station", *map(os.fspath, args)], code, _as_text(out), _as_text(err)
    )


def _as_text(stream: io.BytesIO) -> str:
    # As subprocess.run(text=True) reads a pipe: UTF-8, universal newlines.
    return stream.getvalue().decode("utf-8").replace("\r\n", "\n").replace("\r", "\n")


@contextlib.contextmanager
def _environment(env: Mapping[str, str] | None) -> Iterator[None]:
    if env is None:
        yield
        return
    saved = dict(os.environ)
    os.environ.clear()
    os.environ.update(env)
    try:
        yield
    finally:
        os.environ.clear()
        os.environ.update(saved)


def start_simulator(
    *args: str, env: Mapping[str, str] | None = None
) -> tuple[subprocess.Popen, str]:
    """``station simulate ARGS`` as a subprocess, and the URL it prints as its first line. The
    test fails with the simulator's stderr when it prints none (a refused option, a crash)."""
    process = subprocess.Popen(
        [*STATION, "simulate", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    url = process.stdout.readline().strip()
    if not url:
        process.kill()
        pytest.fail(f"the simulator gave no URL: {process.communicate(timeout=10)[1]}")
    return process, url


def stop_simulator(process: subprocess.Popen, sig: int = signal.SIGTERM) -> str:
    """Send ``sig`` (SIGTERM: the simulator's orderly stop), wait for the simulator to end, and
    return what it wrote on stderr (its exit code is ``process.returncode``)."""
    process.send_signal(sig)
    _, err = process.communicate(timeout=10)
    return err


PROBE_HEAD = """
id = "probe"
title = "Probe"
version = "1"
report_section = "2.6"
channels = ["x", "y", "z"]
unit = "in"
resolution = 0.0001
"""
"""The top of a procedure file the validation tests complete with steps and settings."""

CHECK_STEP = """
[[steps]]
id = "first"
kind = "check"
title = "First"
text = "Do the first thing."
"""
"""One check step: the least a procedure file holds."""


def write_procedure(folder: Path, text: str, name: str = "probe.toml") -> Path:
    """``text`` (dedented) as the procedure file ``folder/name``."""
    path = folder / name
    path.write_text(textwrap.dedent(text))
    return path


CYCLES_ONLY = b"""
id = "cycles-only"
title = "Cycles without zeroing"
version = "1"
report_section = "2.6"
channels = ["x", "y", "z"]
unit = "in"
resolution = 0.0001
[[steps]]
id = "cycles"
kind = "cycles"
title = "Cycles"
"""
"""A procedure that is one cycles step (for tests about reading sets alone)."""


class Terminal:
    """A pseudo-terminal this test opened, as another program (an SSH login) holds one."""

    def __init__(self, master: int, slave: int) -> None:
        self.master, self.slave = master, slave
        self.path = os.ttyname(slave)

    def close(self) -> None:
        os.close(self.slave)
        os.close(self.master)


def open_terminal(terminals: list[Terminal]) -> Terminal:
    terminal = Terminal(*os.openpty())
    terminals.append(terminal)
    return terminal


def reopen_number(path: str, terminals: list[Terminal]) -> Terminal:
    """A new pseudo-terminal at ``path`` (closed just before): the kernel gives the lowest
    free number, so the next ones opened get it back (those below it are held meanwhile)."""
    held: list[Terminal] = []
    try:
        for _ in range(64):
            terminal = Terminal(*os.openpty())
            if terminal.path == path:
                terminals.append(terminal)
                return terminal
            held.append(terminal)
        raise AssertionError(f"another program took {path} before this test could")
    finally:
        for terminal in held:
            terminal.close()
