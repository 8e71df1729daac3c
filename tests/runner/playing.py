"""The operator at the simulated robot, for a headless ``station capture``: the simulator runs in
the test's process on a real pty, ``station capture`` in its own; the player reads what capture
prints as it happens and moves the still robot where the next step needs it, as a technician
moves the robot between cycles.

The robot's rests come in blocks: a rest where the station zeroes (home at the first fixture,
the taught position before a joint's returns, the surface plate), then ``returns`` rests, one
per cycle. After the z-th ``zeroed`` line the robot goes to the block's first return; after
each ``cycle`` line to the next return, or after the block's last one home for the next zero.
``--every S`` leaves the player S seconds after each line before the station reads again (a
zero started before the robot is home is refused as moving and tried again)."""

from __future__ import annotations

import subprocess
from collections.abc import Sequence
from dataclasses import dataclass, field

from station.instruments.simulator import Simulator


@dataclass
class Player:
    """Moves ``simulator``'s robot through blocks of one zeroing rest and ``returns`` rests."""

    simulator: Simulator
    returns: int
    zeros: int = 0
    cycles: int = 0
    lines: list[str] = field(default_factory=list)

    def heard(self, line: str) -> None:
        """React to one line ``station capture`` printed."""
        self.lines.append(line)
        block = 1 + self.returns
        if line.startswith("zeroed "):
            self.zeros += 1
            self.cycles = 0
            self.simulator.move_to_rest((self.zeros - 1) * block + 1)
        elif line.startswith("cycle "):
            self.cycles += 1
            start = (self.zeros - 1) * block
            rest = start + 1 + self.cycles if self.cycles < self.returns else start + block
            self.simulator.move_to_rest(rest)


def play_capture(
    simulator: Simulator, returns: int, arguments: Sequence[str], **options
) -> tuple[subprocess.CompletedProcess[str], Player]:
    """Run ``station capture`` with ``arguments``, playing the robot as it prints; the finished
    process (its whole stdout and stderr) and the player."""
    player = Player(simulator, returns)
    process = subprocess.Popen(
        list(arguments),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        bufsize=1,
        **options,
    )
    try:
        for line in process.stdout:
            player.heard(line.rstrip("\n"))
        _, err = process.communicate(timeout=120)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    done = subprocess.CompletedProcess(
        process.args, process.returncode, "\n".join(player.lines) + "\n", err
    )
    return done, player
