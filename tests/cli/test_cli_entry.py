"""The console script's dispatch: one command's module is all a command loads."""

import subprocess
import sys

from station.cli import build_parser, command_names


def run_station(*arguments: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "station", *arguments], capture_output=True, text=True, timeout=60
    )


def test_every_command_module_is_a_sub_command():
    help_text = build_parser().format_help()
    for name in command_names():
        assert name in help_text
    assert {"analyze", "capture", "demo", "tui", "verify"} <= set(command_names())


def test_a_command_imports_no_other_command_module():
    probe = (
        "import sys; from station.cli import main; "
        "code = main(['procedures']); "
        "loaded = sorted(m for m in sys.modules if m.startswith('station.commands.') "
        "and not m.rsplit('.', 1)[-1].startswith('_')); "
        "print(code, loaded)"
    )
    result = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True)
    assert result.stdout.strip().splitlines()[-1] == "0 ['station.commands.procedures']"


def test_an_unknown_command_lists_the_known_ones_and_exits_2():
    result = run_station("bogus")
    assert result.returncode == 2
    assert "invalid choice: 'bogus'" in result.stderr
    assert "'analyze'" in result.stderr and "'verify'" in result.stderr
