"""The control chart drawn in text: points per cycle, centre line, control limits, alarms marked.

It draws the chart the analysis computed (``ControlChart.points``) and computes no limit itself.
While the limits are being estimated (phase I) it draws the chart's own, moving ``center``,
``ucl`` and ``lcl`` and marks the alarms raised against them; once the limits are frozen (phase
II: after the first points, or a robot's baseline) it draws the frozen limits the live alarms
are judged against, and marks those alarms. Points in alarm are drawn as ``✖`` (and in red where
there is colour), so they read without colour too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from rich.text import Text
from textual.widget import Widget

from station.text import format_figure
from station.tui.text import shown_line

_GUTTER = 13  # "UCL +0.00031 " fits; values outside are written in the rows they fall on


@dataclass(frozen=True)
class ChartData:
    """What the control chart draws."""

    points: tuple[float, ...]
    center: float | None
    ucl: float | None
    lcl: float | None
    alarm_points: frozenset[int]
    labels: tuple[int, ...]
    """The cycle number of each point, for the axis."""
    resolution: float | None = None
    """The gauge's step: the limits are written at one decimal beyond it."""
    title: str = ""
    message: str = ""
    label: str = "cycle"
    """What a point is (``cycle``, ``stroke``), written under the first one."""


def _finite(value: Any) -> float | None:
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def chart_data(
    channel: Any, cycle_numbers: list[int] | None, resolution: float | None, label: str = "cycle"
) -> ChartData | None:
    """The drawable part of a channel analysis (``.chart`` and ``.alarms``, or once frozen
    ``.frozen`` and ``.live_alarms``), or None; ``label`` names the points (``stroke`` for a
    linearity run's straightness chart)."""
    chart = getattr(channel, "chart", None)
    if chart is None:
        # "no readings yet" only when there are none: a single reading has no chart yet.
        n = int(getattr(getattr(channel, "descriptive", None), "n", 0) or 0)
        if n <= 0:
            return None
        return ChartData(
            points=(),
            center=None,
            ucl=None,
            lcl=None,
            alarm_points=frozenset(),
            labels=(),
            resolution=resolution,
            message=f"control chart: {n} {label} so far, it starts at the 2nd",
            label=label,
        )
    points = tuple(float(p) for p in getattr(chart, "points", ()))
    # Once frozen, the limits the live alarms are judged against, and those alarms.
    frozen = getattr(channel, "frozen", None)
    lines = frozen if frozen is not None else chart
    alarms = getattr(channel, "live_alarms" if frozen is not None else "alarms", ()) or ()
    alarmed: set[int] = set()
    for alarm in alarms:
        # Alarm points are 1-based positions on the chart.
        alarmed.update(int(p) - 1 for p in getattr(alarm, "points", ()))
    labels = tuple(cycle_numbers[: len(points)]) if cycle_numbers else ()
    if len(labels) != len(points):
        labels = tuple(range(1, len(points) + 1))
    kind = getattr(chart, "type", "control")
    name = shown_line(getattr(channel, "name", ""), limit=20)
    # Short, so "(last 26 of 60)" and the alarm mark's legend still fit beside it.
    title = f"{kind} {name}, frozen limits" if frozen is not None else f"{kind} chart {name}"
    return ChartData(
        points=points,
        center=_finite(getattr(lines, "center", None)),
        ucl=_finite(getattr(lines, "ucl", None)),
        lcl=_finite(getattr(lines, "lcl", None)),
        alarm_points=frozenset(alarmed),
        labels=labels,
        resolution=resolution,
        title=title.strip(),
        message=str(getattr(chart, "message", "") or ""),
        label=label,
    )


def render_chart(data: ChartData | None, width: int, height: int) -> Text:
    """The chart as ``height`` lines of ``width`` cells."""
    if data is not None and not data.points and data.message:
        return Text(data.message, style="dim")
    if data is None or not data.points:
        return Text("no readings yet", style="dim")
    if width < _GUTTER + 8 or height < 5:
        return Text("control chart: too little room to draw", style="dim")
    plot_width = width - _GUTTER - 1
    rows = height - 2  # a title line and the cycle-number line
    # One column per point when crowded, up to three when there is room; the newest points win.
    spacing = max(1, min(3, plot_width // max(1, len(data.points))))
    shown = min(len(data.points), plot_width // spacing)
    first = len(data.points) - shown
    points = data.points[first:]
    lines_at = [v for v in (data.ucl, data.center, data.lcl) if v is not None]
    low = min([*points, *lines_at])
    high = max([*points, *lines_at])
    span = high - low or abs(high) or 1.0
    low, high = low - span * 0.05, high + span * 0.05

    def row_of(value: float) -> int:
        return min(rows - 1, max(0, round((high - value) / (high - low) * (rows - 1))))

    grid = [[(" ", "")] * plot_width for _ in range(rows)]
    gutter = [""] * rows
    for name, value, char, style in (
        ("UCL", data.ucl, "┈", "yellow"),
        ("LCL", data.lcl, "┈", "yellow"),
        ("CL", data.center, "─", "green"),
    ):
        if value is None:
            continue
        row = row_of(value)
        grid[row] = [(char, style)] * plot_width
        gutter[row] = f"{name} {format_figure(value, data.resolution)}"
    for offset, value in enumerate(points):
        column = offset * spacing
        alarm = (first + offset) in data.alarm_points
        grid[row_of(value)][column] = ("✖", "bold red") if alarm else ("●", "bold cyan")

    title = data.title + (f"  (last {shown} of {len(data.points)})" if first else "")
    if data.alarm_points:
        title += "  ✖ = alarm"
    out: list[Text] = [Text(title[:width], style="bold")]
    for row in range(rows):
        line = Text(gutter[row].rjust(_GUTTER - 1)[: _GUTTER - 1] + " ", style="dim")
        line.append("│" if row not in (0, rows - 1) else "┼", style="dim")
        for char, style in grid[row]:
            line.append(char, style=style)
        out.append(line)
    out.append(_cycle_axis(data.labels[first:], spacing, plot_width, data.label))
    return Text("\n").join(out)


def _cycle_axis(
    labels: tuple[int, ...], spacing: int, plot_width: int, label: str = "cycle"
) -> Text:
    """``cycle 1`` under the first point and the last cycle's number under the last."""
    cells = [" "] * (plot_width + _GUTTER)
    if labels:
        head = f"{label} {labels[0]}"
        cells[_GUTTER : _GUTTER + len(head)] = head
        tail = str(labels[-1])
        end = _GUTTER + (len(labels) - 1) * spacing + 1
        start = max(_GUTTER + len(head) + 1, end - len(tail))
        if start + len(tail) <= len(cells):
            cells[start : start + len(tail)] = tail
    return Text("".join(cells).rstrip(), style="dim")


class ControlChartView(Widget):
    """Shows one channel's control chart; call :meth:`show` with new data."""

    DEFAULT_CSS = """
    ControlChartView { height: 1fr; width: 1fr; }
    """

    def __init__(self, *, id: str | None = None, classes: str | None = None) -> None:
        super().__init__(id=id, classes=classes)
        self._data: ChartData | None = None

    def show(self, data: ChartData | None) -> None:
        """Replace what is drawn (UI thread only)."""
        if data != self._data:
            self._data = data
            self.refresh()

    def render(self) -> Text:
        """Draw for the current size."""
        return render_chart(self._data, self.content_size.width, self.content_size.height)
