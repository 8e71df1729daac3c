"""Issue 22, item 1: one number format everywhere. A session is captured headless (its zero is
a mean of several readings, so its readings are no whole gauge steps), then every output of it
is read figure by figure: the ``capture`` lines and summary, the text, Markdown and HTML
reports, ``analyze``, ``baseline``, ``history``, ``compare`` and a gauge check's summary. Every
figure in the session's unit is written one decimal beyond the gauge step (0.0001 in: five),
positions signed, spreads unsigned, never in scientific notation; and the value listed is the
value the session file holds and the verdict judged."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from helpers import odd_figures, run_station

from station.instruments.protocols import get_protocol
from station.instruments.simulator import AxisModel, GaugeSpec, Simulator, fixture_model
from station.session.model import load_session
from station.text import format_figure

from .test_report import markdown_html, visible_text

RESOLUTION = 0.0001


def _capture(sessions: Path, seed: int, limit: str) -> tuple[Path, str]:
    """``station capture`` of 25 cycles against a seeded simulator on a pty (in inches at
    0.0001 in), the session file and what the command printed."""
    model = fixture_model(
        ("x", "y", "z"),
        axis=AxisModel(noise=0.0),
        # The gauges' own noise: the robot rests at the fixture (it can be zeroed) and every
        # reading still differs by a step or two.
        gauge=GaugeSpec(resolution=RESOLUTION, unit="in", low=-1.0, high=1.0, noise=0.0001),
    )
    simulator = Simulator(get_protocol("mitutoyo"), model, None, seed=seed)
    url = simulator.start_pty()
    try:
        done = run_station(
            "capture", "--procedure", "repeatability", "--port", url,
            "--protocol", "mitutoyo", "--robot", "KSC-7", "--operator", "ana",
            "--sessions", str(sessions), "--cycles", "30", "--trigger", "poll",
            "--every", "0.01", *(arg for ch in "xyz" for arg in ("--limit", f"{ch}={limit}")),
        )  # fmt: skip
    finally:
        simulator.stop()
    assert done.returncode == 0, done.stderr
    path = Path(done.stdout.splitlines()[-2].removeprefix("session file: "))
    return path, done.stdout


@pytest.fixture(scope="module")
def captured(tmp_path_factory: pytest.TempPathFactory) -> dict[str, object]:
    """Two sessions of one robot: the first with tight limits (readings out of spec, a run rule
    and the EWMA alarm), the second capable (a baseline; a point beyond a control limit), and
    what capture printed for each (the seeds are chosen for those alarms)."""
    sessions = tmp_path_factory.mktemp("sessions")
    tight, tight_out = _capture(sessions, 5, "-0.0001:0.0001")
    wide, wide_out = _capture(sessions, 3, "-0.01:0.01")
    return {"sessions": sessions, "tight": tight, "wide": wide, "outputs": [tight_out, wide_out]}


def _outputs(captured: dict[str, object]) -> dict[str, str]:
    sessions, tight, wide = captured["sessions"], captured["tight"], captured["wide"]
    said = {f"capture {n}": text for n, text in enumerate(captured["outputs"], start=1)}

    def station(*args: object) -> str:
        done = run_station(*map(str, args))
        assert done.returncode in (0, 1), done.stderr
        return done.stdout

    said["report txt"] = station("report", tight)
    out = Path(str(tight)).with_suffix(".test.md")
    station("report", tight, "-o", out)
    said["report md"] = visible_text(markdown_html(out.read_text()))
    out = Path(str(tight)).with_suffix(".test.html")
    station("report", tight, "-o", out)
    said["report html"] = visible_text(out.read_text())
    said["analyze"] = station("analyze", tight)
    said["baseline"] = station("baseline", "KSC-7", wide)
    said["history"] = station("history", "KSC-7", "--sessions", sessions)
    said["compare"] = station("compare", tight, wide)
    # A gauge check's summary: repeated readings of a 0.1 in block, no whole steps after a
    # zero taken as a mean.
    table = Path(str(tight)).with_name("gauge-check.csv")
    readings = [0.10003, 0.09993, 0.10013, 0.10003, 0.09993] * 6
    table.write_text("x\n" + "".join(f"{value}\n" for value in readings))
    said["gauge check"] = station(
        "analyze", table, "--procedure", "gauge_check", "--reference", "0.1",
        "--tolerance", "0.004", "--resolution", str(RESOLUTION), "--unit", "in",
    )  # fmt: skip
    return said


def test_every_figure_of_every_output_is_written_one_way(captured):
    outputs = _outputs(captured)
    # What is read: the live alarms' sentences, the zero, a gauge check's figures.
    assert "the EWMA (" in outputs["report txt"] and "control limit (" in outputs["capture 2"]
    assert "offset " in outputs["report html"] and "Zero taken" in outputs["capture 1"]
    assert "bias " in outputs["gauge check"]
    for name, text in outputs.items():
        assert text.strip(), name
        assert odd_figures(text, RESOLUTION) == [], (name, odd_figures(text, RESOLUTION))


def test_the_value_listed_is_the_value_saved_and_judged(captured):
    """``station capture`` printed ``cycle 3 ... y=+0.0010`` for a stored +0.00103, and the
    report listed it as ``+0.0010 ... ok`` though the verdict judged it out of spec."""
    session = load_session(captured["tight"])
    # The zero is a mean of several readings: the readings are no whole gauge steps.
    values = [r.value for c in session.cycles.values() for r in c.readings.values()]
    assert any(abs(v / RESOLUTION - round(v / RESOLUTION)) > 0.05 for v in values)
    printed = [line for line in captured["outputs"][0].splitlines() if line.startswith("cycle ")]
    report = run_station("report", captured["tight"]).stdout
    marked = 0
    for number, cycle in session.cycles.items():
        shown = " ".join(
            f"{ch}={format_figure(r.value, RESOLUTION)}" for ch, r in cycle.readings.items()
        )
        assert f"cycle {number} {shown}" in printed
        row = next(line for line in report.splitlines() if re.match(rf"{number}\s+\d{{4}}-", line))
        beyond_any = False
        for reading in cycle.readings.values():
            text = format_figure(reading.value, RESOLUTION)
            beyond = abs(reading.value) > 0.0001
            beyond_any |= beyond
            assert (f"{text} >USL" in row or f"{text} <LSL" in row) is beyond, row
            marked += beyond
        assert row.rstrip().endswith("out of spec" if beyond_any else "ok"), row
    assert marked
    # The HTML report shows an out-of-spec row as such, not greyed like a rejected one.
    html = captured["tight"].with_suffix(".rows.html")
    assert run_station("report", captured["tight"], "-o", html).returncode == 0
    rows = re.findall(r"<tr(?: class=\"(\w+)\")?><td>\d+</td>.*?</tr>", html.read_text())
    beyond_rows = [line for line in report.splitlines() if line.endswith(" out of spec")]
    assert rows.count("out") == len(beyond_rows) > 0 and "rejected" not in rows
