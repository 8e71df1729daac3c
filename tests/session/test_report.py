"""`analyze_session_file`: the one place that turns a session file into its analysis and report,
on real session files written through the real writer."""

from __future__ import annotations

from pathlib import Path

import pytest

from station.errors import StationError
from station.instruments.simulator import TwoFixtureModel
from station.methods import analyze_session_file
from station.procedures import discover_procedures
from station.run import PortSetup, SessionSetup
from station.session.journal import SessionWriter
from station.session.model import load_session


def write_procedure_session(
    folder: Path, procedure_id: str, events: list[tuple[str, dict]]
) -> Path:
    """A hash-chained session of the built-in procedure ``procedure_id`` holding ``events``."""
    procedure = discover_procedures(use_env=False).get(procedure_id)
    channel_map = {str(n): ch for n, ch in enumerate(procedure.channels, start=1)}
    port = PortSetup("loop://", "mitutoyo", channel_map)
    header = SessionSetup(procedure, "sim", "F", (port,)).header_fields()
    with SessionWriter.create(folder, header) as writer:
        for kind, fields in events:
            writer.append(kind, **fields)
        return writer.path


def test_a_repeatability_session_is_judged_by_its_readings_with_cycle_numbers(session_factory):
    path = session_factory(cycles=6)
    report = analyze_session_file(path)
    session = load_session(path, recover=False)
    assert report.kind == "repeatability"
    # Its one block: the gauge checks recorded at the start (none in the test's register).
    assert report.result is None and len(report.sections) == 1
    assert report.sections[0][0].startswith("GAUGE CHECKS")
    assert all("WARNING: no gauge check covers" in report.lines[i] for i in (1, 3, 5))
    assert report.title == f"BASIC STATISTICS COMPREHENSIVE REPORT ON {path.name}"
    assert report.excluded_cycles == (2,)
    assert any(session.last_hash in note for note in report.notes)
    # Cycle 2 is rejected: the readings are those of cycles 1, 3, 4, 5, 6, named by number.
    x = report.analysis.channels["x"]
    assert x.cycles == (1, 3, 4, 5, 6)
    assert x.readings == tuple(session.channel_values()["x"])
    assert report.analysis.excluded_cycles == (2,)
    document = report.document()
    assert document["procedure"] == "repeatability"
    assert "accuracy" not in document and "linearity" not in document


def test_a_relative_accuracy_session_gets_its_own_analysis_and_report_block(tmp_path):
    from station.analysis.report import format_accuracy

    model = TwoFixtureModel(seed=4)
    events = []
    for placement in range(1, 4):
        x, y, z = model.placement_of(placement).pendant
        values = {"x": x, "y": y, "z": z}
        events.append(("input", {"step": "pendant", "placement": placement, "values": values}))
        readings = {axis: {"value": model.value(axis, placement - 1, 0)} for axis in "xyz"}
        events.append(
            (
                "reading",
                {
                    "cycle": placement,
                    "step": "return",
                    "placement": placement,
                    "channels": readings,
                },
            )
        )
    path = write_procedure_session(tmp_path, "relative_accuracy", events)
    report = analyze_session_file(path, width=74)
    assert report.kind == "relative_accuracy"
    assert report.count == "3 placements"
    assert report.title == f"RELATIVE ACCURACY REPORT ON {path.name}"
    assert report.analysis is report.result.overall
    config = report.analysis.config
    assert report.sections == (tuple(format_accuracy(report.result, config, 74)),)
    assert max(len(line) for line in report.lines) <= 74
    assert [p.number for p in report.result.placements] == [1, 2, 3]
    assert report.document()["procedure"] == "relative_accuracy"
    assert [p["placement"] for p in report.document()["accuracy"]["placements"]] == [1, 2, 3]
    # Asked as repeatability, the same file is judged by its raw readings.
    plain = analyze_session_file(path, method="repeatability")
    assert plain.result is None and set(plain.analysis.channels) == {"x", "y", "z"}


def test_a_linearity_session_without_strokes_says_so(tmp_path):
    path = write_procedure_session(tmp_path, "linearity", [])
    with pytest.raises(StationError, match="no streamed strokes"):
        analyze_session_file(path)
