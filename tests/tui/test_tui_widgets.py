"""The drawing widgets and the set-up's field parsing, on real analysis results.

Each drawing is checked for what an operator must be able to read off it: the limit marks and
labels of the histogram, the alarm marks and control lines of the chart, the verdict words of the
table (words, not only colours), all within the cells they are given.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from rich.cells import cell_len
from rich.console import Console

from station.analysis.capability import SpecLimits
from station.analysis.summary import AnalysisConfig, analyze
from station.errors import StationError
from station.text import (
    figure_decimals,
    format_figure,
    judged_word,
    limits_text,
    overall_verdict,
    parse_channel_map,
    parse_limits_text,
)
from station.tui.widgets.alarm_log import alarm_lines
from station.tui.widgets.control_chart import chart_data, render_chart
from station.tui.widgets.histogram import histogram_data, render_histogram
from station.tui.widgets.stats_panel import StatsRows, stats_table

RESOLUTION = 0.0001


def _analysis(seed: int = 3, n: int = 30, shift_at: int | None = None):
    rng = np.random.default_rng(seed)
    x = np.round(rng.normal(0.0, 0.0002, n) / RESOLUTION) * RESOLUTION
    y = np.round(rng.normal(0.0004, 0.0004, n) / RESOLUTION) * RESOLUTION
    z = np.round(rng.normal(0.0, 0.0001, n) / RESOLUTION) * RESOLUTION
    if shift_at is not None:
        z[shift_at] = 0.0009  # far beyond the control limits: rule 1 fires
    limits = {c: SpecLimits(lsl=-0.001, usl=0.001, nominal=0.0) for c in "xyz"}
    config = AnalysisConfig(limits=limits, resolution=RESOLUTION, unit="in")
    return analyze({"x": x, "y": y, "z": z}, config)


def _plain(text) -> list[str]:
    return text.plain.split("\n")


def test_histogram_fits_its_cells_and_marks_both_limits() -> None:
    channel = _analysis().channels["x"]
    lines = _plain(render_histogram(histogram_data(channel, RESOLUTION), 36, 10))
    assert len(lines) == 10
    assert all(len(line) <= 36 for line in lines)
    assert "LSL -0.00100" in lines[-1] and "USL +0.00100" in lines[-1]
    assert lines[-2].count("┴") == 2  # both limits marked on the axis
    assert any(ch in "".join(lines[1:-2]) for ch in "▁▂▃▄▅▆▇█")


def _histogram_lines(values: list[float], width: int) -> list[str]:
    limits = {"x": SpecLimits(lsl=-0.001, usl=0.001, nominal=0.0)}
    config = AnalysisConfig(limits=limits, resolution=RESOLUTION, unit="in")
    channel = analyze({"x": np.array(values)}, config).channels["x"]
    return _plain(render_histogram(histogram_data(channel, RESOLUTION), width, 10))


@pytest.mark.parametrize("width", [28, 36, 50])
def test_histogram_bars_never_cross_a_limit_and_equal_counts_are_equally_wide(width) -> None:
    """Finding 9: a bar stood over the USL border, and bins of equal counts were drawn one or
    two cells wide depending on where they fell."""
    # Three readings each at four values inside, two at the USL itself, one beyond it.
    values = [-0.0005] * 3 + [0.0] * 3 + [0.0003] * 3 + [0.0007] * 3 + [0.001] * 2 + [0.0012]
    lines = _histogram_lines(values, width)
    bars, axis = lines[1:-2], lines[-2]
    usl_column = axis.rindex("┴")
    lsl_column = axis.index("┴")
    for row in bars:
        assert row[usl_column] == "│" and row[lsl_column] == "│", row
    # The readings at the USL stand left of its mark, the one beyond it right of it.
    bottom = bars[-1]
    assert bottom[usl_column - 1] != " " and bottom[usl_column + 1 :].strip()
    # The four bins of three readings: as wide as each other, and as tall.
    runs = re.findall(r"[▁▂▃▄▅▆▇█]+", bars[0])
    assert len(runs) == 4 and len({len(run) for run in runs}) == 1, bars[0]


def test_histogram_without_data_says_so() -> None:
    assert render_histogram(None, 30, 8).plain == "no readings yet"


def test_chart_marks_the_alarm_point_and_draws_the_lines() -> None:
    analysis = _analysis(shift_at=20)
    channel = analysis.channels["z"]
    assert channel.alarms, "the shifted point must raise an alarm"
    cycles = list(range(1, 31))
    lines = _plain(render_chart(chart_data(channel, cycles, RESOLUTION), 44, 10))
    assert len(lines) == 10
    assert all(len(line) <= 44 for line in lines)
    body = "\n".join(lines)
    assert "✖" in body and "✖ = alarm" in lines[0]
    assert "UCL" in body and "LCL" in body and "CL" in body
    assert lines[-1].strip().startswith("cycle 1") and lines[-1].strip().endswith("30")


def test_chart_keeps_the_newest_points_when_crowded() -> None:
    channel = _analysis(n=60).channels["x"]
    lines = _plain(render_chart(chart_data(channel, list(range(1, 61)), RESOLUTION), 40, 8))
    assert "(last 26 of 60)" in lines[0]
    assert lines[-1].strip().endswith("60")


def test_stats_table_writes_verdict_words_within_80_columns() -> None:
    analysis = _analysis()
    rows = StatsRows(
        channels=("x", "y", "z"),
        analyses=analysis.channels,
        last={"x": 0.0001, "y": -0.0002, "z": 0.0},
        resolution=RESOLUTION,
        selected="y",
    )
    console = Console(width=78, record=True, color_system=None)
    console.print(stats_table(rows))
    text = console.export_text()
    assert all(cell_len(line) <= 78 for line in text.splitlines())
    words = {judged_word(c) for c in analysis.channels.values()}
    for word in words:
        assert word in text
    # The bounds the words rest on (issue 20), one pair per channel.
    caption = next(line for line in text.splitlines() if "bounds (Bissell)" in line)
    x = analysis.channels["x"].capability
    assert caption.startswith("Cpk 95% bounds (Bissell): x ")
    assert f"x {x.cpk_lower:.2f}-{x.cpk_upper:.2f}" in caption
    assert "▶y" in text
    assert "+0.00010" in text  # the live reading of x


def test_alarm_lines_name_the_cycle_the_operator_saw() -> None:
    analysis = _analysis(shift_at=20)
    # Cycle 5 was rejected: the 21st accepted point (index 20) is cycle 22.
    numbers = [n for n in range(1, 32) if n != 5]
    lines = alarm_lines(analysis.channels, numbers)
    assert any(line.startswith("cycle 22 z [report-1]") for line in lines), lines


@pytest.mark.parametrize(
    ("typed", "expected"),
    [
        ("±0.001", (-0.001, 0.001, 0.0)),
        ("+-0.002", (-0.002, 0.002, 0.0)),
        ("0.001", (-0.001, 0.001, 0.0)),
        ("-0.001:0.0015", (-0.001, 0.0015, None)),
        (":0.001", (None, 0.001, 0.0)),
        ("-0.001:", (-0.001, None, 0.0)),
    ],
)
def test_limits_field_accepts_tolerance_and_lsl_usl(typed: str, expected: tuple) -> None:
    parsed = parse_limits_text(typed)
    assert parsed is not None
    assert (parsed.lsl, parsed.usl, parsed.nominal) == expected


@pytest.mark.parametrize(
    ("typed", "sentence"),
    [
        ("0.001:-0.001", "not above the lower limit"),
        ("abc", "is not a limit"),
        ("-0.001", "must be a positive number"),
        (":", "is not a limit"),
    ],
)
def test_limits_field_refuses_with_a_sentence(typed: str, sentence: str) -> None:
    with pytest.raises(StationError, match=sentence):
        parse_limits_text(typed)


def test_limits_text_round_trips() -> None:
    assert limits_text(-0.001, 0.001, 0.0) == "±0.001"
    assert parse_limits_text(limits_text(-0.001, 0.002)) is not None


def test_channel_map_field() -> None:
    assert parse_channel_map("1=x, 2=y,3=z") == {"1": "x", "2": "y", "3": "z"}
    with pytest.raises(StationError, match="DEVICE=CHANNEL"):
        parse_channel_map("1x")


def test_figures() -> None:
    assert figure_decimals(0.0001) == 5
    assert figure_decimals(0.001) == 4
    assert format_figure(None, 0.001) == "-" and format_figure(float("nan"), 0.001) == "-"
    # Never scientific, never a signed spread, never "-0": one format for every figure.
    assert format_figure(4.11e-05, RESOLUTION) == "+0.00004"
    assert format_figure(0.00022, RESOLUTION, signed=False) == "0.00022"
    assert format_figure(-0.000004, RESOLUTION) == "+0.00000"
    assert overall_verdict(["CAPABLE", "NOT CAPABLE"]) == "NOT CAPABLE"
    assert overall_verdict(["CAPABLE", "CAPABLE"]) == "CAPABLE"
    assert overall_verdict(["CAPABLE", "UNDEFINED"]) == "UNDEFINED"
    assert overall_verdict(["CAPABLE", "INCONCLUSIVE"]) == "INCONCLUSIVE"
    assert overall_verdict(["INCONCLUSIVE", "NOT CAPABLE"]) == "NOT CAPABLE"


def test_stats_table_flags_out_of_spec_and_says_provisional() -> None:
    analysis = _analysis(n=9)
    rows = StatsRows(
        channels=("x", "y", "z"),
        analyses=analysis.channels,
        last={"x": 0.0001, "y": 0.0011, "z": -0.00105},
        resolution=RESOLUTION,
        flags={"y": "above", "z": "below"},
    )
    console = Console(width=76, record=True, color_system=None)
    console.print(stats_table(rows))
    text = console.export_text()
    assert all(cell_len(line) <= 76 for line in text.splitlines())
    assert "…" not in text, text  # no figure cut to fit
    assert "+0.00110▲" in text and "-0.00105▼" in text and "+0.00010▲" not in text
    assert "PROVISIONAL: 9 of 25 readings, 16 more before a verdict" in text
    assert "CAPABLE" not in text  # nothing judged from 9 readings
    # The out column counts each channel's readings beyond a limit.
    y_row = next(line for line in text.splitlines() if line.lstrip().startswith("y"))
    assert y_row.split()[-2] == str(analysis.channels["y"].out_of_spec.total)
