"""A usage mistake is one line that says what to do, with exit 2 (issue 27, finding 8)."""

from __future__ import annotations

import pytest
from helpers import run_station


@pytest.mark.parametrize(
    ("args", "says", "hint"),
    [
        (("capture", "--bogus"), "unrecognized arguments: --bogus", "station capture --help"),
        (("report",), "the following arguments are required: FILE", "station report --help"),
        (("frobnicate",), "invalid choice: 'frobnicate'", "station --help"),
        (("gauges", "list", "--bogus"), "unrecognized arguments", "station gauges --help"),
        (("report", "s.jsonl", "--format", "pdf"), "invalid choice: 'pdf'", "station report"),
    ],
)
def test_a_usage_error_is_one_line_with_exit_2(args, says, hint):
    result = run_station(*args)
    assert result.returncode == 2
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("station: error: ") and says in lines[0] and hint in lines[0]


@pytest.mark.parametrize("command", ["report", "export"])
def test_an_empty_output_name_is_refused_not_taken_for_standard_output(command, tmp_path):
    extra = ("--csv",) if command == "export" else ()
    result = run_station(command, tmp_path / "s.jsonl", *extra, "-o", "")
    assert result.returncode == 2 and result.stdout == ""
    assert result.stderr.count("\n") == 1
    assert "-o/--output: an empty name" in result.stderr
