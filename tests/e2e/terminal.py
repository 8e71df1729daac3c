"""A real terminal for end-to-end tests: one command in a detached tmux session, read from
its pane.

Each pane runs on a tmux server of its own (``tmux -L``): on one shared server a test that
closes the server's last session takes the server down while another test's ``new-session``
is connecting to it ("server exited unexpectedly", seen under load on two workers), and the
pane's process would start in the environment of whichever test started that server.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import time
import uuid
from pathlib import Path

import pytest

# What the pane's process takes from the test: its own home and XDG folders (its signing key,
# trust store and settings), never the developer's.
CARRIED = ("HOME", "XDG_CONFIG_HOME", "XDG_DATA_HOME", "XDG_STATE_HOME", "XDG_CACHE_HOME")


class Pane:
    """One command in a detached tmux session of ``size`` on a private tmux server; the pane
    stays after the command exits, so its exit status can be read."""

    def __init__(
        self,
        command: list[str],
        cwd: Path,
        size: tuple[int, int] = (80, 24),
        env: dict[str, str] | None = None,
    ) -> None:
        self.name = f"station-e2e-{uuid.uuid4().hex[:8]}"
        variables = {"TERM": "xterm-256color", "COLORTERM": "truecolor"}
        variables |= {name: os.environ[name] for name in CARRIED if name in os.environ}
        variables |= env or {}
        line = " ".join(f"{k}={shlex.quote(v)}" for k, v in variables.items())
        # `exec` so that the pane's process is the command itself and receives the hang-up.
        shell = f"cd {shlex.quote(str(cwd))} && {line} exec {shlex.join(command)}"
        width, height = size
        started = self._run(
            "new-session", "-d", "-s", self.name, "-x", str(width), "-y", str(height), shell
        )
        if started.returncode != 0:
            pytest.fail(f"tmux could not start the pane: {started.stderr.strip()}")
        self._tmux("set-option", "-t", self.name, "remain-on-exit", "on")
        self.pid = int(self._tmux("display-message", "-p", "-t", self.name, "#{pane_pid}"))

    def _run(self, *args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            ["tmux", "-L", self.name, *args], capture_output=True, text=True, check=False
        )

    def _tmux(self, *args: str) -> str:
        return self._run(*args).stdout.strip()

    def screen(self) -> str:
        """What the terminal shows now."""
        return self._tmux("capture-pane", "-p", "-t", self.name)

    def screen_with_escapes(self) -> str:
        """What the terminal shows now, with its colours and attributes as escape sequences."""
        return self._tmux("capture-pane", "-p", "-e", "-t", self.name)

    def tty(self) -> str:
        """The pane's terminal device (``/dev/pts/N``)."""
        return self._tmux("display-message", "-p", "-t", self.name, "#{pane_tty}")

    def send(self, *keys: str) -> None:
        """Type ``keys`` (tmux key names: ``Enter``, ``Tab``, ``F2``, or plain text)."""
        self._run("send-keys", "-t", self.name, *keys)

    def wait_for(self, pattern: str, timeout: float) -> str:
        """The screen once the regular expression ``pattern`` matches it; fails with the last
        screen after ``timeout``."""
        deadline = time.monotonic() + timeout
        screen = ""
        while time.monotonic() < deadline:
            screen = self.screen()
            if re.search(pattern, screen):
                return screen
            time.sleep(0.1)
        pytest.fail(f"{pattern!r} did not appear within {timeout} s; the screen shows:\n{screen}")

    def exit_status(self, timeout: float) -> int:
        """The command's exit status once the pane is dead."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            fields = self._tmux(
                "display-message", "-p", "-t", self.name, "#{pane_dead} #{pane_dead_status}"
            )
            dead, _, status = fields.partition(" ")
            if dead == "1" and status:
                return int(status)
            time.sleep(0.1)
        fields = self._tmux(
            "display-message",
            "-p",
            "-t",
            self.name,
            "dead=#{pane_dead} status=#{pane_dead_status} signal=#{pane_dead_signal}",
        )
        pytest.fail(f"the command did not exit within {timeout} s ({fields}):\n{self.screen()}")

    def hang_up(self) -> None:
        """Close the terminal: tmux sends SIGHUP to the pane's process (as an SSH drop does);
        the private server goes with its last session."""
        self._run("kill-session", "-t", self.name)

    def close(self) -> None:
        """Take the pane and its server down if they are still there."""
        self._run("kill-server")


def alive(pid: int) -> bool:
    """True while ``pid`` runs (a zombie child of the tmux server counts as gone)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:
        return Path(f"/proc/{pid}/stat").read_text().split()[2] != "Z"
    except OSError:
        return False
