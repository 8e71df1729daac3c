"""What several test modules share: ``station simulate`` as a real subprocess, and the small
procedure files the procedure and capture tests write.

Imported as ``from helpers import ...``: pytest puts ``tests/`` on ``sys.path`` for the suite's
own ``conftest.py``.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap
from collections.abc import Mapping
from pathlib import Path

import pytest

STATION = [sys.executable, "-m", "station"]
"""The station command as this interpreter runs it."""


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
