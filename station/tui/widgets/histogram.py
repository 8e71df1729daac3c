"""A text histogram drawn with block characters, with the specification limits marked.

It draws the bins the analysis computed (``Histogram.edges`` and ``counts``); it never bins values
itself. The horizontal axis spans the bins and the limits, so a histogram that sits inside its
limits looks it, and one that spills over shows where.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rich.text import Text
from textual.widget import Widget

from station.tui.text import shown_line
from station.tui.widgets.figures import number

_EIGHTHS = " ▁▂▃▄▅▆▇█"


@dataclass(frozen=True)
class HistogramData:
    """What the histogram draws: bin edges and counts, the limits, and how to write values."""

    edges: tuple[float, ...]
    counts: tuple[int, ...]
    lsl: float | None = None
    usl: float | None = None
    decimals: int = 5
    title: str = ""


def histogram_data(channel: Any, decimals: int) -> HistogramData | None:
    """The drawable part of a channel analysis (``.histogram``, ``.capability``), or None."""
    histogram = getattr(channel, "histogram", None)
    if histogram is None or len(getattr(histogram, "counts", ())) == 0:
        return None
    capability = getattr(channel, "capability", None)
    return HistogramData(
        edges=tuple(float(edge) for edge in histogram.edges),
        counts=tuple(int(count) for count in histogram.counts),
        lsl=getattr(capability, "lsl", None),
        usl=getattr(capability, "usl", None),
        decimals=decimals,
        title=f"histogram {shown_line(getattr(channel, 'name', ''), limit=20)}",
    )


def render_histogram(data: HistogramData | None, width: int, height: int) -> Text:
    """The histogram as ``height`` lines of ``width`` cells: bars, an axis, and limit labels."""
    if data is None or width < 10 or height < 4:
        return Text("no readings yet", style="dim")
    bar_rows = height - 3  # a title line, the axis line and the label line
    low, high = data.edges[0], data.edges[-1]
    for limit in (data.lsl, data.usl):
        if limit is not None:
            low, high = min(low, limit), max(high, limit)
    span = high - low or 1.0
    low, high = low - span * 0.04, high + span * 0.04
    step = (high - low) / width

    def column_of(value: float) -> int:
        return min(width - 1, max(0, int((value - low) / step)))

    heights = [0] * width
    bin_width = data.edges[1] - data.edges[0] if len(data.edges) > 1 else span
    if bin_width >= step:
        # Wide bins: every column whose centre falls inside a bin takes that bin's count.
        for column in range(width):
            centre = low + (column + 0.5) * step
            for index, count in enumerate(data.counts):
                if data.edges[index] <= centre < data.edges[index + 1]:
                    heights[column] = count
                    break
    else:
        # Narrow bins: a column gathers the bins whose centres fall inside it.
        for index, count in enumerate(data.counts):
            heights[column_of((data.edges[index] + data.edges[index + 1]) / 2)] += count
    tallest = max(heights) or 1
    limit_columns = {column_of(v) for v in (data.lsl, data.usl) if v is not None}

    lines: list[Text] = [Text(f"{data.title}  (tallest bar {tallest})", style="bold")]
    for row in range(bar_rows, 0, -1):
        line = Text()
        for column in range(width):
            eighths = round(heights[column] / tallest * bar_rows * 8) - (row - 1) * 8
            if eighths > 0:
                line.append(_EIGHTHS[min(8, eighths)], style="cyan")
            elif column in limit_columns:
                line.append("│", style="red")
            else:
                line.append(" ")
        lines.append(line)
    axis = ["─"] * width
    for column in limit_columns:
        axis[column] = "┴"
    lines.append(Text("".join(axis), style="dim"))
    lines.append(_limit_labels(data, width, column_of))
    return Text("\n").join(lines)


def _limit_labels(data: HistogramData, width: int, column_of: Any) -> Text:
    """``LSL value`` starting under its mark and ``USL value`` ending under its mark."""
    cells = [" "] * width
    taken_until = 0
    if data.lsl is not None:
        label = f"LSL {number(data.lsl, data.decimals)}"
        start = max(0, min(column_of(data.lsl), width - len(label)))
        cells[start : start + len(label)] = label
        taken_until = start + len(label) + 1
    if data.usl is not None:
        label = f"USL {number(data.usl, data.decimals)}"
        end = min(width, max(column_of(data.usl) + 1, len(label)))
        start = max(end - len(label), taken_until)
        if start + len(label) <= width:
            cells[start : start + len(label)] = label
    if data.lsl is None and data.usl is None:
        text = "no specification limits"
        cells[: len(text)] = text[:width]
    return Text("".join(cells)[:width], style="red")


class HistogramView(Widget):
    """Shows one channel's histogram; call :meth:`show` with new data, it redraws on resize."""

    DEFAULT_CSS = """
    HistogramView { height: 1fr; width: 1fr; }
    """

    def __init__(self, *, id: str | None = None, classes: str | None = None) -> None:
        super().__init__(id=id, classes=classes)
        self._data: HistogramData | None = None

    def show(self, data: HistogramData | None) -> None:
        """Replace what is drawn (UI thread only)."""
        if data != self._data:
            self._data = data
            self.refresh()

    def render(self) -> Text:
        """Draw for the current size."""
        return render_histogram(self._data, self.content_size.width, self.content_size.height)
