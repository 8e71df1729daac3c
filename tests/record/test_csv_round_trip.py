"""CSV both ways: what ``station export`` writes, ``station analyze`` reads back to the same
analysis as the session file itself, for every procedure and layout."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from station.cli import main

from .conftest import write_accuracy, write_linearity, write_repeatability

LIMITS = [f"--limit={axis}=-0.001:0.001" for axis in "xyz"]
SETTINGS = {
    # The settings each session recorded, given on the command line for the CSV.
    "repeatability": ["--resolution", "0.0001", "--unit", "in", "--freeze-after", "25", *LIMITS],
    "relative_accuracy": [
        "--resolution", "0.0001", "--unit", "in", "--procedure", "relative_accuracy",
        "--freeze-after", "3", "--min-n", "3",
    ],
    "linearity": [
        "--resolution", "0.0001", "--unit", "in", "--procedure", "linearity",
        "--tolerance", "0.002", "--freeze-after", "25",
    ],
}  # fmt: skip
BUILDERS = {
    "repeatability": write_repeatability,
    "relative_accuracy": write_accuracy,
    "linearity": write_linearity,
}


def analyze_json(capsys: pytest.CaptureFixture, *args: str) -> dict:
    capsys.readouterr()
    assert main(["analyze", *args, "--json"]) == 0, capsys.readouterr().err
    return json.loads(capsys.readouterr().out)


@pytest.mark.parametrize(
    ("kind", "layout"),
    [
        ("repeatability", "tidy"),
        ("repeatability", "wide"),
        ("relative_accuracy", "wide"),
        ("linearity", "wide"),
    ],
)
def test_export_then_analyze_gives_the_session_analysis(kind, layout, sessions, capsys):
    session = BUILDERS[kind](sessions)
    table = sessions.parent / f"{kind}-{layout}.csv"
    assert main(["export", str(session), "--csv", "--layout", layout, "-o", str(table)]) == 0
    from_session = analyze_json(capsys, str(session))
    from_table = analyze_json(capsys, str(table), *SETTINGS[kind])
    # The alarm events the session journaled (with their acknowledgements) are the file's
    # record, not its analysis: a table of readings cannot carry them.
    assert "recorded_alarms" in from_session and "recorded_alarms" not in from_table
    from_session.pop("recorded_alarms")
    # So are the zeros' own readings: the off-nominal hint of a table weighs the offset without
    # the zero's rest-to-rest draw (issue 20), so it may word the same offset differently.
    for document in (from_session, from_table):
        document["hints"] = [h for h in document.get("hints", []) if "off nominal" not in h]
    assert from_table == from_session
    excluded = {"repeatability": [2], "relative_accuracy": [3], "linearity": []}
    assert from_session["excluded_cycles"] == excluded[kind]


def test_a_tidy_relative_accuracy_table_has_the_readings_but_not_the_pendant(sessions, capsys):
    """The tidy layout has no place for the pendant's coordinates: the readings, placements and
    their statistics come back, the error per unit moved (which needs them) does not."""
    session = write_accuracy(sessions)
    table = sessions.parent / "tidy.csv"
    assert main(["export", str(session), "--csv", "--layout", "tidy", "-o", str(table)]) == 0
    from_session = analyze_json(capsys, str(session))
    from_table = analyze_json(capsys, str(table), *SETTINGS["relative_accuracy"])
    assert from_table["channels"] == from_session["channels"]
    assert from_table["accuracy"]["axes"]["x"]["average"] == pytest.approx(
        from_session["accuracy"]["axes"]["x"]["average"]
    )
    assert from_table["accuracy"]["per_unit"] is None
    assert from_session["accuracy"]["per_unit"] is not None


def test_the_default_layout_follows_the_procedure(sessions, capsys):
    linearity = write_linearity(sessions)
    accuracy = write_accuracy(sessions)
    capsys.readouterr()
    assert main(["export", str(linearity), "--csv"]) == 0
    lines = [line for line in capsys.readouterr().out.splitlines() if not line.startswith("#")]
    assert lines[0] == "stroke,s,h,v"
    assert len(lines) == 1 + 8 * 60  # every streamed point of the 8 strokes
    assert main(["export", str(accuracy), "--csv"]) == 0
    out = capsys.readouterr().out
    assert "# rejected cycle 3 (left out): fixture not seated" in out
    rows = list(csv.reader(line for line in out.splitlines() if not line.startswith("#")))
    assert rows[0] == ["cycle", "placement", "x", "y", "z", "px", "py", "pz"]
    assert len(rows) == 1 + 5 * 6 - 1


def test_a_tidy_table_with_every_row_rejected_is_refused(tmp_path: Path, capsys):
    table = tmp_path / "t.csv"
    table.write_text("cycle,channel,value,status\n1,x,0.1,rejected: bumped\n")
    assert main(["analyze", str(table)]) == 2
    assert "every reading in the table is rejected" in capsys.readouterr().err


@pytest.mark.parametrize("layout", ["tidy", "wide"])
def test_a_reason_with_line_breaks_stays_on_its_line(layout, sessions, capsys):
    reason = "bumped\n99,x,5.0,in,ok\r\n# not a comment"
    session = write_repeatability(sessions, reject=(4, reason))
    table = sessions.parent / f"{layout}.csv"
    assert main(["export", str(session), "--csv", "--layout", layout, "-o", str(table)]) == 0
    assert "bumped 99,x,5.0,in,ok # not a comment" in table.read_text()
    from_session = analyze_json(capsys, str(session))
    from_session.pop("recorded_alarms")  # the journal's alarm events: not in a table
    assert analyze_json(capsys, str(table), *SETTINGS["repeatability"]) == from_session
    assert from_session["excluded_cycles"] == [4]
