"""Issue 22, item 3: the filed record's charts. The HTML histogram drew 6 equal bins over the
range (two neighbouring gauge values merged into one bar, the drawn mode was not the data's);
the control chart drew the retrospective limits beside live alarms judged against the frozen
ones, circled the point after each alarm, and its legend covered the last point."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from helpers import run_station
from matplotlib.backends.backend_agg import FigureCanvasAgg

from station.record.charts import control_chart, histogram_chart
from station.record.render import render_report
from station.record.source import analyse_session
from station.session.journal import SessionWriter
from station.text import format_figure

from .conftest import WHEN, _reading, header_fields, write_repeatability

RESOLUTION = 0.0001
QUIET = [0.0, 0.0001, -0.0001, 0.0, 0.0001, 0.0, -0.0001, 0.0001, 0.0, -0.0001]
"""A still robot's readings at the gauge step (centre 0, a moving range of about a step)."""


def _session(folder: Path, x: list[float]) -> Path:
    """A finished repeatability session whose x reads ``x`` (y and z read 0 and a step)."""
    header = header_fields("repeatability", robot="KSC-7")
    with SessionWriter.create(folder, header, now=WHEN) as writer:
        for cycle, value in enumerate(x, start=1):
            values = {"x": value, "y": QUIET[cycle % len(QUIET)], "z": QUIET[(cycle + 3) % 10]}
            writer.append(
                "reading", cycle=cycle, step="cycles", channels=_reading(values, "in"), by="op"
            )
        writer.append("finish", by="operator", complete=True)
    return writer.path


def _text_histogram(text: str, channel: str) -> dict[str, int]:
    """The counts per bin centre of ``channel``'s HISTOGRAM block in the analysis text."""
    block = text.split(f"FEATURE: {channel} ", 1)[1].split("HISTOGRAM", 1)[1]
    counts = {}
    for line in block.splitlines()[1:]:
        found = re.match(r"\s*([-+]\d+\.\d+) \|#*\s*(\d+)", line)
        if found is None:
            break
        counts[found.group(1)] = int(found.group(2))
    return counts


def test_the_html_histogram_counts_each_gauge_value_as_the_text_report_does(sessions):
    # Counts 4 and 5 on two neighbouring gauge values: drawn as one bar of 9 before.
    x = [0.0001] * 4 + [0.0002] * 5 + [0.0] * 3 + [-0.0001] * 2 + [0.0004] + [-0.0004] * 1
    path = _session(sessions, x * 2)
    html = render_report(path, "html")
    text = run_station("analyze", path).stdout
    for channel in ("x", "y", "z"):
        drawn = {
            centre: int(count)
            for centre, count in re.findall(rf'id="histogram-{channel}:([-+\d.]+):(\d+)"', html)
        }
        assert drawn and drawn == _text_histogram(text, channel), channel
    drawn_x = dict(re.findall(r'id="histogram-x:([-+\d.]+):(\d+)"', html))
    assert drawn_x["+0.00010"] == "8" and drawn_x["+0.00020"] == "10"
    # The tallest bar is the data's mode, and the chart says which value it is.
    mode = re.search(r"MODE: (\S+)", text.split("FEATURE: x ", 1)[1]).group(1)
    assert mode == "+0.00020" == max(drawn_x, key=lambda centre: int(drawn_x[centre]))
    assert f"mode {mode}" in html


def _drawn(figure) -> None:
    FigureCanvasAgg(figure).draw()


def test_the_control_chart_draws_the_limits_its_alarms_were_judged_against(sessions):
    # 25 quiet points freeze the live limits; cycle 28 is far beyond them (a live alarm).
    x = (QUIET * 3)[:25] + [0.0, 0.0001, 0.0009, 0.0, 0.0001]
    path = _session(sessions, x)
    analysed = analyse_session(path)
    channel = analysed.report.analysis.channels["x"]
    frozen = channel.frozen
    assert frozen is not None and frozen.ucl != channel.chart.ucl
    figure = control_chart("x", channel, resolution=RESOLUTION)
    _drawn(figure)
    (axes,) = figure.axes
    legend = [text.get_text() for text in axes.get_legend().get_texts()]
    assert f"UCL {format_figure(frozen.ucl, RESOLUTION)}" in legend
    assert f"CL {format_figure(frozen.center, RESOLUTION)}" in legend
    assert f"UCL {format_figure(channel.chart.ucl, RESOLUTION)}" not in legend
    assert "frozen after the first 25 points" in axes.get_title()
    # The circles sit on the live alarms' own cycles (they sat one point later).
    (circles,) = [c for c in axes.collections if str(c.get_label()).startswith("alarm")]
    alarmed = sorted({c for alarm in channel.live_alarms for c in alarm.cycles})
    assert 28 in alarmed
    assert sorted(float(x) for x, _ in circles.get_offsets()) == alarmed
    # And the HTML report draws the same.
    html = render_report(path, "html")
    assert f"UCL {format_figure(frozen.ucl, RESOLUTION)}" in html


def test_before_the_limits_freeze_the_chart_says_they_are_retrospective(sessions):
    path = _session(sessions, QUIET * 2)
    channel = analyse_session(path).report.analysis.channels["x"]
    assert channel.frozen is None
    figure = control_chart("x", channel, resolution=RESOLUTION)
    (axes,) = figure.axes
    assert "retrospective limits" in axes.get_title()
    legend = [text.get_text() for text in axes.get_legend().get_texts()]
    assert f"UCL {format_figure(channel.chart.ucl, RESOLUTION)}" in legend


@pytest.mark.parametrize("chart", ["histogram", "control"])
def test_the_legend_stands_outside_the_data(sessions, chart):
    path = write_repeatability(sessions)
    channel = analyse_session(path).report.analysis.channels["x"]
    if chart == "histogram":
        figure = histogram_chart("x", channel, "in", RESOLUTION, "x")
    else:
        figure = control_chart("x", channel, resolution=RESOLUTION)
    _drawn(figure)
    (axes,) = figure.axes
    legend = axes.get_legend().get_window_extent()
    assert legend.x0 >= axes.get_window_extent().x1, (legend, axes.get_window_extent())
    assert legend.x1 <= figure.bbox.x1 + 1  # and on the page
