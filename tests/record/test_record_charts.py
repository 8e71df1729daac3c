"""Issue 22, item 3: the filed record's charts. The HTML histogram drew 6 equal bins over the
range (two neighbouring gauge values merged into one bar, the drawn mode was not the data's);
the control chart drew the retrospective limits beside live alarms judged against the frozen
ones, circled the point after each alarm, and its legend covered the last point."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest
from helpers import run_station
from matplotlib.backends.backend_agg import FigureCanvasAgg

from station.record.charts import (
    alarms_id,
    control_chart,
    envelope,
    envelope_column,
    histogram_chart,
    judged_limits,
)
from station.record.render import render_report
from station.record.source import analyse_session
from station.session.journal import SessionWriter
from station.text import format_figure

from .conftest import WHEN, _reading, header_fields, write_repeatability
from .test_report import CHROMIUM, chromium, console_messages

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


def test_the_envelope_keeps_every_extreme_in_a_bounded_number_of_points():
    rng = np.random.default_rng(7)
    y = rng.normal(0, 1, 50_000)
    y[12_345], y[40_000] = 9.0, -9.0
    x = np.arange(1, y.size + 1, dtype=float)
    drawn_x, drawn_y, reduced = envelope(x, y, columns=500)
    assert reduced and drawn_y.size == 1000
    assert drawn_y.max() == 9.0 and drawn_y.min() == -9.0
    assert np.all(np.diff(drawn_x) >= 0)  # still in cycle order
    short = np.arange(10.0)
    assert envelope(short, short)[2] is False


def _svg_bytes(html: str) -> list[int]:
    return [len(svg) for svg in re.findall(r"<svg.*?</svg>", html, re.S)]


def test_a_long_session_draws_small_charts_that_still_mark_every_alarm(tmp_path, monkeypatch):
    """A 20,000-cycle session drew 18.6 MB of SVG (every point a marker, every alarm a
    circle, a 3-D scatter of every reading) and took minutes. Its charts now weigh under
    1 MB together (each column of a long series its least and greatest point), and every
    alarmed point still lies under a circle of its chart."""
    # Writing speed, not durability, is what 20,000 fsyncs would cost here.
    monkeypatch.setattr(os, "fsync", lambda fd: None)
    path = write_repeatability(tmp_path, cycles=20_000, alarm=False)
    monkeypatch.undo()
    html = render_report(path, "html")
    sizes = _svg_bytes(html)
    assert len(sizes) == 8 and sum(sizes) < 1_000_000, sizes
    # The rest of the page is the record itself: the readings table lists every cycle.
    assert len(html) < 6_000_000
    channels = analyse_session(path).report.analysis.channels
    for key, channel in channels.items():
        _, alarms, _ = judged_limits(channel)
        cycles = np.asarray(channel.cycles, dtype=float)
        alarmed = sorted({p - 1 for alarm in alarms for p in alarm.points})
        assert alarmed, f"{key}: a 20,000-cycle session of this noise raises alarms"
        figure = control_chart(key, channel, resolution=RESOLUTION, key=key)
        (circles,) = [c for c in figure.axes[0].collections if c.get_gid() == alarms_id(key)]
        circled = {
            (column, value)
            for column, (_, value) in zip(
                envelope_column(cycles, circles.get_offsets()[:, 0]),
                circles.get_offsets(),
                strict=True,
            )
        }
        points = np.asarray(channel.chart.points)
        under = {
            (column, points[i])
            for column, i in zip(envelope_column(cycles, cycles[alarmed]), alarmed, strict=True)
        }
        assert under == circled, key
        group = re.search(rf'<g id="{alarms_id(key)}">(.*?)\n   </g>', html, re.S)
        assert group is not None and group.group(1).count("<use") == len(circled), key
    if CHROMIUM is not None:
        page = tmp_path / "long.html"
        page.write_text(html, encoding="utf-8")
        result = chromium(page.as_uri(), "--dump-dom")
        assert console_messages(result.stderr) == []
        assert result.stdout.count('class="chart"') == 8
