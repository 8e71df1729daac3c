"""A linearity verdict is PROVISIONAL below the strokes its procedure's stroke step asks for at
least, not below the repeatability's cycle count (25 when the file has no ``[cycles]``)."""

from __future__ import annotations

from pathlib import Path

from station.analysis.linearity import analyze_linearity, linearity_summary
from station.analysis.strokes import profiles_from_stream
from station.instruments.simulator import BarModel
from station.procedures import parse_procedure
from station.run import PortSetup, SessionSetup
from station.session.header import analysis_config

SHORT_LINEARITY = b"""
id = "site-linearity"
title = "Linearity, six strokes"
version = "1"
report_section = "2.9"
analysis = "linearity"
channels = ["h", "v", "s"]
unit = "in"
resolution = 0.0001
[limits]
h = { lsl = -0.001, usl = 0.001 }
v = { lsl = -0.001, usl = 0.001 }
[[steps]]
id = "strokes"
kind = "stroke"
title = "Shuttle between A and B six to eight times"
channels = ["h", "v", "s"]
direction_channel = "s"
min = 6
target = 8
"""


def header_of(tmp_path: Path, strokes: int | None = None) -> dict:
    procedure = parse_procedure(SHORT_LINEARITY, tmp_path / "site-linearity.toml")
    setup = SessionSetup(
        procedure=procedure,
        robot="KSC-7",
        operator="tester",
        ports=(PortSetup("socket://127.0.0.1:1", "mitutoyo", {"1": "h", "2": "v", "3": "s"}),),
        trigger="push",
        strokes=strokes,
    )
    return setup.header_fields()


def test_six_strokes_of_a_six_stroke_procedure_give_a_final_verdict(tmp_path):
    header = header_of(tmp_path)
    assert header["strokes_min"] == 6
    config = analysis_config(header)
    assert config.min_n == 6
    model = BarModel(points=100, dwell=5, bow=0.0003, sag=0.0002, noise=0.00002)
    stream = model.stream(6, 1)
    profiles = profiles_from_stream(stream["s"], {"h": stream["h"], "v": stream["v"]})
    assert len(profiles) == 6
    summary = linearity_summary(analyze_linearity(profiles, tolerance=0.002, config=config))
    for channel in summary.channels.values():
        assert channel.verdict is not None and not channel.verdict.provisional
    five = linearity_summary(analyze_linearity(profiles[:5], tolerance=0.002, config=config))
    assert all(c.verdict.provisional for c in five.channels.values())


def test_a_trial_run_the_set_up_shortens_stays_provisional(tmp_path):
    # Four strokes asked for at the set-up end the step, but the procedure asks for six: as a
    # short run of cycles, the verdict of four stays provisional.
    assert analysis_config(header_of(tmp_path, strokes=4)).min_n == 6
