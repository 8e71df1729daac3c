"""The operator's terminal, for real: ``station`` in tmux, signals sent to its process, the exit
status read back from the dead pane (issue 13: the TUI exited 0 after SIGHUP/SIGTERM)."""

from __future__ import annotations

import os
import shlex
import shutil
import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path

import pytest

pytestmark = pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")


def _tmux(*args: str) -> str:
    return subprocess.run(["tmux", *args], capture_output=True, text=True, check=False).stdout


class Pane:
    """One detached tmux session that stays after its command exits (to read the status)."""

    def __init__(self, command: list[str], cwd: Path, size: tuple[int, int] = (80, 24)) -> None:
        self.name = f"station-op-{uuid.uuid4().hex[:8]}"
        env = f"TERM=xterm-256color XDG_CONFIG_HOME={shlex.quote(os.environ['XDG_CONFIG_HOME'])}"
        shell = f"cd {shlex.quote(str(cwd))} && {env} exec {shlex.join(command)}"
        subprocess.run(
            ["tmux", "new-session", "-d", "-s", self.name, "-x", str(size[0]), "-y", str(size[1])]
            + [shell],
            check=True,
        )
        _tmux("set-option", "-t", self.name, "remain-on-exit", "on")
        self.pid = int(_tmux("display-message", "-p", "-t", self.name, "#{pane_pid}").strip())

    def screen(self) -> str:
        return _tmux("capture-pane", "-p", "-t", self.name)

    def wait_for(self, text: str, timeout: float) -> str:
        deadline = time.monotonic() + timeout
        screen = ""
        while time.monotonic() < deadline:
            screen = self.screen()
            if text in screen:
                return screen
            time.sleep(0.1)
        pytest.fail(f"{text!r} did not appear within {timeout} s; the screen shows:\n{screen}")

    def exit_status(self, timeout: float) -> int:
        """The command's exit status once the pane is dead."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            fields = _tmux(
                "display-message", "-p", "-t", self.name, "#{pane_dead} #{pane_dead_status}"
            )
            dead, _, status = fields.strip().partition(" ")
            if dead == "1" and status:
                return int(status)
            time.sleep(0.1)
        pytest.fail(f"station did not exit within {timeout} s:\n{self.screen()}")

    def close(self) -> None:
        subprocess.run(["tmux", "kill-session", "-t", self.name], capture_output=True, check=False)


@pytest.mark.parametrize(
    ("signum", "code"), [(signal.SIGHUP, 129), (signal.SIGTERM, 143)], ids=["SIGHUP", "SIGTERM"]
)
def test_the_tui_exits_128_plus_the_signal(tmp_path: Path, signum: int, code: int) -> None:
    pane = Pane([sys.executable, "-m", "station", "--sessions", str(tmp_path)], tmp_path)
    try:
        pane.wait_for("New session", timeout=30)
        os.kill(pane.pid, signum)
        assert pane.exit_status(timeout=20) == code
    finally:
        pane.close()
