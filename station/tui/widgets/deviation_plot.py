"""Deviation versus position along the bar, drawn in text: the stroke under way over earlier ones.

Each stroke is drawn as its deviations from its own least-squares line (the analysis'
``Straightness.residuals_ls``) against the scale's position s. Earlier strokes are dim dots, the
newest whole stroke cyan, the stroke under way bold yellow, so the three read apart without
colour too (``·``, ``•``, ``●``). Nothing here is computed but the mapping to character cells.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from rich.text import Text
from textual.widget import Widget

from station.text import format_figure

_GUTTER = 11  # "+0.00123 " fits
EARLIER = ("·", "blue")
NEWEST = ("•", "cyan")
CURRENT = ("●", "bold yellow")


@dataclass(frozen=True)
class Trace:
    """One stroke's deviations ``d`` at positions ``s`` (equal lengths)."""

    s: tuple[float, ...]
    d: tuple[float, ...]


@dataclass(frozen=True)
class DeviationData:
    """What the plot draws: earlier strokes oldest first, the newest whole stroke, the one
    under way (each may be absent)."""

    channel: str
    earlier: tuple[Trace, ...] = ()
    newest: Trace | None = None
    current: Trace | None = None
    resolution: float | None = None
    """The gauge's step: deviations and positions are written at one decimal beyond it."""
    unit: str = ""


def render_deviation(data: DeviationData | None, width: int, height: int) -> Text:
    """The plot as ``height`` lines of ``width`` cells."""
    traces = [] if data is None else [*data.earlier, data.newest, data.current]
    drawn = [t for t in traces if t is not None and t.s]
    if data is None or not drawn or width < _GUTTER + 10 or height < 5:
        return Text("no stroke yet: the plot starts with the first points", style="dim")
    plot_width = width - _GUTTER - 1
    rows = height - 2
    s_low = min(min(t.s) for t in drawn)
    s_high = max(max(t.s) for t in drawn)
    peak = max(max(abs(v) for v in t.d) for t in drawn) or 1.0
    s_span = (s_high - s_low) or 1.0

    def cell(s: float, d: float) -> tuple[int, int]:
        column = round((s - s_low) / s_span * (plot_width - 1))
        row = round((peak - d) / (2 * peak) * (rows - 1))
        return min(rows - 1, max(0, row)), min(plot_width - 1, max(0, column))

    grid = [[(" ", "")] * plot_width for _ in range(rows)]
    zero_row = cell(s_low, 0.0)[0]
    grid[zero_row] = [("─", "dim")] * plot_width
    layers: list[tuple[Trace | None, tuple[str, str]]] = [(t, EARLIER) for t in data.earlier]
    layers += [(data.newest, NEWEST), (data.current, CURRENT)]
    for trace, mark in layers:
        if trace is None:
            continue
        for s, d in zip(trace.s, trace.d, strict=False):
            row, column = cell(s, d)
            grid[row][column] = mark
    unit = f" {data.unit}" if data.unit else ""
    title = f"{data.channel} − LS line ({unit.strip() or 'deviation'}) vs s"
    legend = " "
    if data.earlier:
        legend += " · earlier"
    if data.newest is not None:
        legend += " • last"
    if data.current is not None:
        legend += " ● now"
    out = [Text(title, style="bold").append(legend[: max(0, width - len(title))], style="dim")]
    labels = {
        0: format_figure(peak, data.resolution),
        rows - 1: format_figure(-peak, data.resolution),
    }
    labels.setdefault(zero_row, format_figure(0.0, data.resolution))
    for row in range(rows):
        line = Text(labels.get(row, "").rjust(_GUTTER - 1) + " ", style="dim")
        line.append("│", style="dim")
        for char, style in grid[row]:
            line.append(char, style=style)
        out.append(line)
    left = f"s {format_figure(s_low, data.resolution, signed=False)}"
    right = format_figure(s_high, data.resolution, signed=False)
    axis = " " * (_GUTTER + 1) + left
    axis += right.rjust(max(1, width - len(axis)))
    out.append(Text(axis[:width], style="dim"))
    return Text("\n").join(out)


def trace(s: Sequence[float], d: Sequence[float], limit: int = 600) -> Trace:
    """A trace of at most ``limit`` evenly taken points (a screen has fewer columns)."""
    step = max(1, len(s) // limit)
    return Trace(tuple(float(v) for v in s[::step]), tuple(float(v) for v in d[::step]))


class DeviationPlot(Widget):
    """Shows the deviation plot; call :meth:`show` with new data."""

    DEFAULT_CSS = """
    DeviationPlot { height: 1fr; width: 1fr; }
    """

    def __init__(self, *, id: str | None = None, classes: str | None = None) -> None:
        super().__init__(id=id, classes=classes)
        self._data: DeviationData | None = None

    def show(self, data: DeviationData | None) -> None:
        """Replace what is drawn (UI thread only)."""
        if data != self._data:
            self._data = data
            self.refresh()

    def render(self) -> Text:
        """Draw for the current size."""
        return render_deviation(self._data, self.content_size.width, self.content_size.height)
