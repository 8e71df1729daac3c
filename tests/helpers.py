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
import re
import signal
import subprocess
import sys
import textwrap
from collections.abc import Iterator, Mapping
from pathlib import Path

import pytest

from station.cli import main as station_main
from station.text import figure_decimals

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


FIGURE = re.compile(r"(?<![\w.-])[-+]?\d+\.(\d+)(?![\w.%-])")
"""A number with decimals, standing alone (not a percent, nor part of a hash, a date, a uuid or
a file name)."""
SCIENTIFIC = re.compile(r"(?<![\w.-])[-+]?\d+(?:\.\d+)?[eE][-+]?\d+(?![\w.-])")
SIGNED_SPREAD = re.compile(r"\b(?:σ|SIGMA:?|sigma|RANGE:?|range|spread)\s+[-+]\d")
UNSIGNED_POSITION = re.compile(
    r"(?:(?<!MR )\b(?:UCL|LCL|CENTER|centre|center|LSL|USL|MEAN|AVERAGE|average|offset|"
    r"nominal|NOMINAL|bias|EWMA|limit|line)\b:?\s*\(?|=)\d+\.\d"
)
"""A position (a limit, a control line, a mean, an offset, a reading after ``=``) written
without its sign (a moving range's ``MR UCL`` is a spread)."""
DIMENSIONLESS = re.compile(
    r"(?:\b(?:p|r|a1|t|W|statistic|T²|F|Cp|Cpk|Cpu|Cpl|Pp|Ppk|ratio|lambda|SKEWNESS a1:|bounds)"
    r"\s*[=<]?\s*"
    r"|CI )$"
)
"""What stands just before a number that is no figure in the unit (a p-value, a statistic,
an index, a σ ratio's interval)."""


def odd_figures(text: str, resolution: float | None = 0.0001) -> list[str]:
    """The figures in ``text`` that break the one number format (empty when there are none): a
    number in scientific notation, a signed spread, an unsigned position, or a figure with more
    than two decimals (an index or a percent has two) but other than the figures' decimals at
    ``resolution``, unless a dimensionless label stands before it (``p = 0.003``). Each is
    given with the text around it."""

    def around(match: re.Match[str], line: str) -> str:
        start, end = max(0, match.start() - 40), match.end() + 20
        return f"{match.group(0)!r} in {line[start:end]!r}"

    decimals = figure_decimals(resolution)
    odd = [around(match, text) for match in SCIENTIFIC.finditer(text)]
    odd += [around(match, text) for match in SIGNED_SPREAD.finditer(text)]
    odd += [around(match, text) for match in UNSIGNED_POSITION.finditer(text)]
    lines = text.splitlines()
    # The teach pendant's coordinates are typed as the pendant shows them (its own decimals).
    pendant = next((i for i, line in enumerate(lines) if "PENDANT" in line), None)
    if pendant is not None:
        end = next((i for i in range(pendant, len(lines)) if not lines[i].strip()), len(lines))
        lines = lines[:pendant] + lines[end:]
    for line in lines:
        for match in FIGURE.finditer(line):
            places = len(match.group(1))
            if DIMENSIONLESS.search(line[: match.start()]):
                continue
            # Two decimals: an index (Cp, Cpk, a₁, a percent); anything longer is a figure.
            if places > 2 and places != decimals:
                odd.append(around(match, line))
    return odd
