"""The alarm questions of ``station capture`` read the operator's answers from the terminal's
descriptor: answers typed ahead in one go (a paste, or keys pressed before the prompt) are each
taken in turn, even on a terminal not in line mode, and end of input or a caught signal ends
the questions."""

from __future__ import annotations

import os
import termios
import time

from station.commands.capture.output import TypedLines


def _terminal(line_mode: bool) -> tuple[int, int]:
    master, slave = os.openpty()
    if not line_mode:  # as a program that died in raw mode may leave it (CR still maps to NL)
        attributes = termios.tcgetattr(slave)
        attributes[3] &= ~termios.ICANON
        termios.tcsetattr(slave, termios.TCSANOW, attributes)
    return master, slave


def test_answers_typed_ahead_are_each_taken_in_turn() -> None:
    for line_mode in (True, False):
        master, slave = _terminal(line_mode)
        try:
            os.write(master, b"coffee\n\n\ntemperature\n")
            time.sleep(0.05)  # all of it in the terminal before the first question
            typed = TypedLines(slave)
            answers = [typed.readline(stop=lambda: False) for _ in range(4)]
            assert answers == ["coffee", "", "", "temperature"], (line_mode, answers)
        finally:
            os.close(master)
            os.close(slave)


def test_a_caught_signal_ends_the_wait_and_a_hang_up_ends_the_input() -> None:
    master, slave = _terminal(True)
    try:
        typed = TypedLines(slave)
        started = time.monotonic()
        assert typed.readline(stop=lambda: time.monotonic() - started > 0.2) is None
        os.write(master, b"half a line")
        os.close(master)  # the terminal hangs up: what was typed is still an answer
        master = -1
        assert typed.readline() in ("half a line", None)
        assert typed.readline() is None
    finally:
        if master != -1:
            os.close(master)
        os.close(slave)
