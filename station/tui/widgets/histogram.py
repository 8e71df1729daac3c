"""A text histogram drawn with block characters, with the specification limits marked.

It draws the bins the analysis computed (``Histogram.edges`` and ``counts``, which cover the
readings and the limits); it never bins values itself. Every bin is equally wide on screen and
each limit is a column of its own between the bins on either side of it, so a histogram that sits
inside its limits looks it, and one that spills over shows where.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rich.text import Text
from textual.widget import Widget

from station.text import format_figure
from station.tui.text import shown_line

_EIGHTHS = " ▁▂▃▄▅▆▇█"


@dataclass(frozen=True)
class HistogramData:
    """What the histogram draws: bin edges and counts, the limits, and how to write values."""

    edges: tuple[float, ...]
    counts: tuple[int, ...]
    lsl: float | None = None
    usl: float | None = None
    resolution: float | None = None
    """The gauge's step: the limits are written at one decimal beyond it."""
    title: str = ""


def histogram_data(channel: Any, resolution: float | None) -> HistogramData | None:
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
        resolution=resolution,
        title=f"histogram {shown_line(getattr(channel, 'name', ''), limit=20)}",
    )


@dataclass(frozen=True)
class _Column:
    """One drawn column: the count of the bins it gathers and which side of the limits."""

    count: int
    region: int
    """0 below the LSL, 1 within the limits, 2 above the USL."""


def _region(centre: float, data: HistogramData) -> int:
    """Which side of the limits a bin falls on, by its centre (the bins are centred on the
    gauge's steps, so a bin centred on a limit holds readings equal to it: within)."""
    if data.lsl is not None and centre < data.lsl:
        return 0
    if data.usl is not None and centre > data.usl:
        return 2
    return 1


def _columns(data: HistogramData, room: int) -> list[_Column]:
    """The bars, left to right, each as wide as every other: ``g`` bins gathered per bar (1
    when they fit), never across a limit (a bar holds only readings of one side, so none
    stands over a limit's mark), and each bar as many cells wide as ``room`` allows."""
    bins = [((data.edges[i] + data.edges[i + 1]) / 2, count) for i, count in enumerate(data.counts)]
    regions: list[list[int]] = [[], [], []]
    for centre, count in bins:
        regions[_region(centre, data)].append(count)
    gather = 1
    while sum(-(-len(counts) // gather) for counts in regions) > room:
        gather += 1
    groups = [
        _Column(sum(counts[i : i + gather]), side)
        for side, counts in enumerate(regions)
        for i in range(0, len(counts), gather)
    ]
    # As many cells per group as fit, the same for each: equal counts, equal bars.
    per_group = max(1, room // max(1, len(groups)))
    return [group for group in groups for _ in range(per_group)]


def render_histogram(data: HistogramData | None, width: int, height: int) -> Text:
    """The histogram as ``height`` lines of ``width`` cells: bars, an axis, and limit labels.

    Every bin is drawn equally wide, so equal counts make equal bars, and each limit has a
    column of its own between the bins within it and those beyond it: a bar never crosses it.
    """
    if data is None or width < 10 or height < 4:
        return Text("no readings yet", style="dim")
    bar_rows = height - 3  # a title line, the axis line and the label line
    marks = sum(limit is not None for limit in (data.lsl, data.usl))
    columns = _columns(data, width - marks)
    # The cells, left to right: a bar column, or a limit's mark (None) between the sides.
    cells: list[_Column | None] = []
    side = 0
    for column in columns:
        while side < column.region:
            side += 1
            if (data.lsl, data.usl)[side - 1] is not None:
                cells.append(None)
        cells.append(column)
    while side < 2:
        side += 1
        if (data.lsl, data.usl)[side - 1] is not None:
            cells.append(None)
    # Centred in the room left over (bars of whole cells rarely fill it exactly).
    margin: list[_Column | None] = [_Column(0, 1)] * ((width - len(cells)) // 2)
    cells = margin + cells
    tallest = max((c.count for c in cells if c is not None), default=0) or 1
    limit_cells = [i for i, cell in enumerate(cells) if cell is None]

    lines: list[Text] = [Text(f"{data.title}  (tallest bar {tallest})", style="bold")]
    for row in range(bar_rows, 0, -1):
        line = Text()
        for cell in cells:
            if cell is None:
                line.append("│", style="red")
                continue
            eighths = round(cell.count / tallest * bar_rows * 8) - (row - 1) * 8
            line.append(_EIGHTHS[min(8, eighths)] if eighths > 0 else " ", style="cyan")
        lines.append(line)
    axis = [" " if i < len(margin) else "┴" if c is None else "─" for i, c in enumerate(cells)]
    lines.append(Text("".join(axis), style="dim"))
    lines.append(_limit_labels(data, width, limit_cells))
    return Text("\n").join(lines)


def _limit_labels(data: HistogramData, width: int, limit_cells: list[int]) -> Text:
    """``LSL value`` starting under its mark and ``USL value`` ending under its mark, moved
    just enough that both fit the line."""
    cells = [" "] * width
    marks = iter(limit_cells)
    lsl = "" if data.lsl is None else f"LSL {format_figure(data.lsl, data.resolution)}"
    usl = "" if data.usl is None else f"USL {format_figure(data.usl, data.resolution)}"
    taken_until = 0
    if lsl:
        room_after = len(usl) + 1 if usl else 0
        start = max(0, min(next(marks), width - len(lsl) - room_after))
        cells[start : start + len(lsl)] = lsl
        taken_until = start + len(lsl) + 1
    if usl:
        end = min(width, max(next(marks) + 1, len(usl)))
        start = max(end - len(usl), taken_until)
        if start + len(usl) <= width:
            cells[start : start + len(usl)] = usl
    if not lsl and not usl:
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
