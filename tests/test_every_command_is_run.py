"""Every command ``station --help`` lists, and every action of one (``station gauges record``), is
run by some test: ``station gauges record`` once crashed on every input for as long as no test
ran it.

A command counts as run when a test file names it as the first argument of the station command
line, in a real process (``STATION`` / ``-m station`` / the console script) or in this one
(``run_station``, ``main([...])``, a module's own ``station(...)`` helper); an action when its
command and its name stand together (``"gauges", "record"``) or it is the first argument of a
helper named after its command (``gauges("record", ...)``). :data:`KNOWN_GAPS` lists what no
test runs yet: a new command without a test fails here, and so does a gap that a test has closed
(take it off).
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from station.cli import build_parser

TESTS = Path(__file__).resolve().parent
KNOWN_GAPS: frozenset[str] = frozenset()
"""Commands and actions no test runs yet (none: ``station gauges list``, ``status`` and
``record`` are run by tests/runner/test_method_sessions.py)."""

_LAUNCH = re.compile(
    r"STATION|run_station|station\(|[\"']station[\"']|-m[\"'], [\"']station|_station|main\(\["
)


def commands_and_actions() -> set[str]:
    """``analyze``, ``gauges record``…: every command of ``station --help`` and every action
    of a command that has them."""
    names = set()
    parser = build_parser()
    for sub in parser._subparsers._group_actions:  # the one COMMAND argument
        for name, command in sub.choices.items():
            names.add(name)
            for action in command._actions:
                if isinstance(action, argparse._SubParsersAction):
                    names.update(f"{name} {verb}" for verb in action.choices)
    return names


def run_by_a_test(name: str, sources: list[str]) -> bool:
    """Whether some test source runs ``name`` (see the module)."""
    command, _, action = name.partition(" ")
    if action:
        together = re.compile(rf"[\"']{command}[\"'],\s*[\"']{action}[\"']")
        helper = re.compile(rf"\b{command}\(\s*[\"']{action}[\"']")
        return any(together.search(text) or helper.search(text) for text in sources)
    literal = re.compile(rf"[\"']{command}[\"']")
    if command == "tui":  # also the bare command: ``station --sessions DIR`` opens the TUI
        literal = re.compile(r"[\"']tui[\"']|[\"']station[\"'],\s*[\"']--")
    return any(
        literal.search(line) and _LAUNCH.search(line)
        for text in sources
        for line in text.splitlines()
    )


def test_every_command_and_action_is_run_by_a_test() -> None:
    sources = [
        path.read_text(encoding="utf-8")
        for path in TESTS.rglob("test_*.py")
        if path.resolve() != Path(__file__).resolve()
    ]
    names = commands_and_actions()
    assert "gauges record" in names and "analyze" in names  # the parser is read as meant
    unrun = {name for name in names if not run_by_a_test(name, sources)}
    assert unrun <= KNOWN_GAPS, f"no test runs: {sorted(unrun - KNOWN_GAPS)}"
    closed = KNOWN_GAPS - unrun
    assert not closed, f"now run by a test, take off KNOWN_GAPS: {sorted(closed)}"
