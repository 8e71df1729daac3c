"""Review finding 14: every help text of these commands reads on an 80-column terminal."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest


@pytest.mark.parametrize("command", ["simulate", "analyze", "read", "verify", "export", "capture"])
def test_help_fits_80_columns(command: str) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "station", command, "--help"],
        capture_output=True,
        text=True,
        timeout=30,
        env={**os.environ, "COLUMNS": "80"},
    )
    assert result.returncode == 0, result.stderr
    wide = [line for line in result.stdout.splitlines() if len(line) > 79]
    assert wide == [], "\n".join(wide)


def test_capture_help_states_its_exit_codes() -> None:
    """The exit codes the README listed for `station capture` are in its own help (issue 26,
    item 7: long command detail moved to the command)."""
    result = subprocess.run(
        [sys.executable, "-m", "station", "capture", "--help"],
        capture_output=True,
        text=True,
        timeout=30,
        env={**os.environ, "COLUMNS": "80"},
    )
    assert result.returncode == 0, result.stderr
    text = " ".join(result.stdout.split())
    for words in ("0 finished", "2 an error", "70 station capture itself failed", "129/130/143"):
        assert words in text, words
