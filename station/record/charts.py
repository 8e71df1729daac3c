"""The report's charts as SVG text (matplotlib's SVG backend, no display, no global state).

Each chart is one ``Figure`` drawn by ``FigureCanvasSVG``: the method's own charts (linearity's
profiles along the bar, a gauge study's bias against the size: :meth:`Method.charts
<station.methods.contract.Method.charts>`, drawn with this module's figure and colours), then
the histogram of each judged channel against its limits, the control chart with its limits and
the alarms marked, the offsets of x, y, z seen along each axis pair, and the readings over time
with their trend (drift) where the method's readings are cycles in time order. Text is kept as
SVG text (searchable, small). A long session's series are drawn as their min/max envelope per
column (:func:`envelope`) and its alarm circles one per column and value, so the SVG stays small
whatever the count of cycles. A channel name or a unit comes from outside and is shown as text:
maths parsing is off while every chart is drawn (``$\\frac{1}{$`` would stop the report), its
control characters are made visible (:func:`chart_text`) and a long one is cut with a mark (a
100,000-character name laid out by matplotlib took minutes), and matplotlib's warnings (a glyph
the font lacks) stay off the terminal.
"""

from __future__ import annotations

import io
import re
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from station.methods import Judgement
from station.plain import plain
from station.record.content import parse_time
from station.record.source import AnalysedSession
from station.text import format_figure

if TYPE_CHECKING:
    # The type only: this module loads matplotlib when it draws.
    from matplotlib.typing import RcKeyType

RC: dict[RcKeyType, Any] = {
    "svg.fonttype": "none",
    "text.parse_math": False,
    "text.usetex": False,
    "font.size": 9,
    "axes.grid": True,
    "grid.alpha": 0.3,
}
LIMIT_COLOUR = "#c0392b"
CENTRE_COLOUR = "#2c3e50"
POINT_COLOUR = "#1f77b4"
ALARM_COLOUR = "#d62728"
_METADATA_KEYS = ("Date", "Creator", "Format", "Type")
CHART_TEXT_LIMIT = 60
"""The most characters of outside text (a channel name, a unit) a chart shows."""


def chart_text(text: object) -> str:
    """Text from outside (a channel name, a unit) as a chart shows it: controls made visible,
    cut to :data:`CHART_TEXT_LIMIT` characters with an ellipsis."""
    return plain(text, limit=CHART_TEXT_LIMIT)


@dataclass(frozen=True)
class Chart:
    """One chart: its title (for a caption) and its SVG element (no XML prolog)."""

    key: str
    title: str
    svg: str


def _svg(figure: Any, salt: str) -> str:
    """The figure as an inline ``<svg>`` element: prolog and doctype dropped, ids made unique
    per chart (several charts share one HTML page)."""
    from matplotlib import rc_context
    from matplotlib.backends.backend_svg import FigureCanvasSVG

    buffer = io.StringIO()
    with rc_context({**RC, "svg.hashsalt": salt}):
        # No metadata block: no date (the same session gives the same page), no outside links.
        FigureCanvasSVG(figure).print_svg(buffer, metadata=dict.fromkeys(_METADATA_KEYS))
    text = buffer.getvalue()
    start = text.find("<svg")
    return text[start:] if start >= 0 else text


def _figure(width: float = 7.0, height: float = 3.2) -> Any:
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


def _figure_ticks(axis: Any, resolution: float | None) -> None:
    """An axis of figures in the session's unit labelled in the one number format."""
    from matplotlib.ticker import FuncFormatter

    axis.set_major_formatter(FuncFormatter(lambda value, _: format_figure(value, resolution)))


def _legend_outside(axes: Any) -> None:
    """The legend to the right of the plot, never over a bar or a point."""
    axes.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, fontsize=7)


ENVELOPE_COLUMNS = 600
"""Columns a long series is drawn in: about the pixel columns of a 7 in plot at 100 dpi. A
series of more points than twice this is drawn as each column's least and greatest value."""
SCATTER_POINTS = 2000
"""The most distinct points a scatter draws as vector marks; more are drawn as one image."""


def envelope(
    x: np.ndarray, y: np.ndarray, columns: int = ENVELOPE_COLUMNS
) -> tuple[np.ndarray, np.ndarray, bool]:
    """A long series as its min/max envelope: ``x`` (ascending) cut into ``columns`` runs of
    consecutive points, each drawn as its least and greatest ``y`` at the run's middle, so
    every extreme stays in sight while the SVG holds ``2 * columns`` points whatever the
    session's length. Returns the points to draw and whether they were reduced (a series of
    at most ``2 * columns`` points is returned as it is)."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if y.size <= 2 * columns:
        return x, y, False
    starts = np.linspace(0, y.size, columns + 1).astype(int)
    ends = starts[1:] - 1
    starts = starts[:-1]
    low, high = np.minimum.reduceat(y, starts), np.maximum.reduceat(y, starts)
    middle = (x[starts] + x[ends]) / 2
    return np.repeat(middle, 2), np.column_stack([low, high]).ravel(), True


def envelope_column(x: np.ndarray, at: np.ndarray, columns: int = ENVELOPE_COLUMNS) -> np.ndarray:
    """The column of :func:`envelope` each of the values ``at`` (on ``x``'s scale) falls in."""
    x = np.asarray(x, dtype=float)
    span = float(x[-1] - x[0]) or 1.0
    return np.minimum(np.floor((np.asarray(at) - x[0]) / span * columns), columns - 1)


def one_per_column(
    x: np.ndarray, y: np.ndarray, marked: list[int], columns: int = ENVELOPE_COLUMNS
) -> list[int]:
    """Of the points ``marked`` (indices) of a series drawn as its :func:`envelope`, one for
    each column and value: the others would be drawn on top of it, so every marked point still
    lies under a mark while a long session's thousands of alarms stay a bounded SVG."""
    index = np.asarray(marked, dtype=int)
    places = np.column_stack([envelope_column(x, x[index], columns), np.asarray(y)[index]])
    _, first = np.unique(places, axis=0, return_index=True)
    return sorted(int(i) for i in index[first])


def bin_id(key: str, centre: str, count: int) -> str:
    """The SVG id of a histogram bar (``histogram-x:+0.00010:4``): the channel (its key with
    anything but letters, digits, ``_`` and ``-`` made ``_``, cut to
    :data:`CHART_TEXT_LIMIT`: a name from outside is no markup), the gauge value the bar is
    centred on and its count, so the drawn counts can be checked against the text report's."""
    return f"histogram-{_SAFE_KEY.sub('_', key)[:CHART_TEXT_LIMIT]}:{centre}:{count}"


def alarms_id(key: str) -> str:
    """The SVG id of a control chart's alarm circles (``alarms-x``), one mark per circled
    point, so the drawn alarms can be counted in the page."""
    return f"alarms-{_SAFE_KEY.sub('_', key)[:CHART_TEXT_LIMIT]}"


def histogram_chart(
    name: str, channel: Any, unit: str, resolution: float | None = None, key: str = ""
) -> Any:
    """The readings' histogram against LSL and USL, with the nominal, the mean and the mode
    marked: the analysis' own bins (those of the text report), each centred on a gauge value
    with its edges midway to the next, so two neighbouring gauge values never share a bar and
    the tallest bar is the data's mode. Each bar is labelled with its count."""
    name, unit = chart_text(name), chart_text(unit)
    figure = _figure()
    axes = figure.add_subplot()
    hist = channel.histogram
    edges = np.asarray(hist.edges, dtype=float)
    centres = (edges[:-1] + edges[1:]) / 2
    bars = axes.bar(
        centres,
        hist.counts,
        width=hist.bin_width * 0.9,
        color=POINT_COLOUR,
        alpha=0.75,
        edgecolor="white",
    )
    for bar, centre, count in zip(bars, centres, hist.counts, strict=True):
        bar.set_gid(bin_id(key, format_figure(float(centre), resolution), int(count)))
    axes.bar_label(bars, labels=[str(c) if c else "" for c in hist.counts], fontsize=7)
    limits = channel.limits
    if limits is not None:
        for value, label in ((limits.lsl, "LSL"), (limits.usl, "USL")):
            if value is not None:
                shown = format_figure(value, resolution)
                axes.axvline(value, color=LIMIT_COLOUR, linestyle="--", label=f"{label} {shown}")
    axes.axvline(channel.nominal, color="grey", linestyle=":", label="nominal")
    mean = channel.descriptive.mean
    axes.axvline(mean, color=CENTRE_COLOUR, label=f"mean {format_figure(mean, resolution)}")
    for number, mode in enumerate(channel.descriptive.modes):
        axes.axvline(
            mode,
            color=ALARM_COLOUR,
            linestyle="-.",
            linewidth=1,
            label=f"mode {format_figure(mode, resolution)}" if number == 0 else None,
        )
    axes.set_title(f"Histogram of {name} against the limits")
    axes.set_xlabel(f"reading ({unit})" if unit else "reading")
    axes.set_ylabel("count")
    axes.margins(y=0.12)  # room for the counts above the tallest bar
    _figure_ticks(axes.xaxis, resolution)
    axes.tick_params(axis="x", labelrotation=30, labelsize=7)
    _legend_outside(axes)
    return figure


def judged_limits(channel: Any) -> tuple[Any, tuple[Any, ...], str]:
    """The control lines a channel's drawn alarms were judged against, those alarms, and what
    the lines are: once the live limits froze (after the first points, or a robot's baseline),
    the frozen limits and the live alarms (those the report lists); before that, the limits
    of all the points (retrospective) and their alarms."""
    frozen = channel.frozen
    if frozen is not None:
        source = frozen.source or "frozen"
        if not source.startswith("frozen"):
            source = f"baseline: {source}" if not source.startswith("baseline") else source
        return frozen, tuple(channel.live_alarms), f"live limits, {source}"
    return channel.chart, tuple(channel.alarms), "retrospective limits (all points)"


def control_chart(
    name: str,
    channel: Any,
    xlabel: str = "cycle",
    resolution: float | None = None,
    key: str = "",
) -> Any:
    """The location chart: points by cycle (or stroke), the centre line and control limits its
    alarms were judged against (:func:`judged_limits`, named in the title and the legend),
    those alarms circled in red (their SVG group's id is :func:`alarms_id` of ``key``). More
    than ``2 * ENVELOPE_COLUMNS`` points are drawn as their :func:`envelope`; the alarms'
    circles are always drawn, each on its own point."""
    chart = channel.chart
    name = chart_text(name)
    lines, alarms, judged = judged_limits(channel)
    figure = _figure()
    axes = figure.add_subplot()
    points = np.asarray(chart.points, dtype=float)
    subgroup = max(1, chart.subgroup)
    labels = channel.cycles or tuple(range(1, len(channel.readings) + 1))
    x = np.asarray(
        [labels[min(i * subgroup, len(labels) - 1)] for i in range(points.size)], dtype=float
    )
    drawn_x, drawn_y, reduced = envelope(x, points)
    if reduced:
        # Each column's least and greatest point: every extreme in sight, the SVG small.
        axes.plot(
            drawn_x,
            drawn_y,
            color=POINT_COLOUR,
            linewidth=0.6,
            label=f"{points.size} points, min and max per column",
        )
    else:
        axes.plot(x, points, marker="o", markersize=3, color=POINT_COLOUR, linewidth=1)
    for value, label, style in (
        (lines.center, "CL", "-"),
        (lines.ucl, "UCL", "--"),
        (lines.lcl, "LCL", "--"),
    ):
        if value is not None:
            colour = CENTRE_COLOUR if label == "CL" else LIMIT_COLOUR
            shown = f"{label} {format_figure(value, resolution)}"
            axes.axhline(value, color=colour, linestyle=style, linewidth=1, label=shown)
    # Alarm points are 1-based positions on the chart.
    flagged = sorted({p - 1 for alarm in alarms for p in alarm.points if 1 <= p <= points.size})
    if flagged and reduced:
        flagged = one_per_column(x, points, flagged)
    if flagged:
        axes.scatter(
            x[flagged],
            points[flagged],
            s=60,
            facecolors="none",
            edgecolors=ALARM_COLOUR,
            linewidths=1.5,
            label=f"alarm ({len(alarms)})",
            zorder=3,
            gid=alarms_id(key),
        )
    axes.set_title(f"Control chart ({chart.type}) of {name}: {judged}", fontsize=8)
    axes.set_xlabel(xlabel)
    _figure_ticks(axes.yaxis, resolution)
    _legend_outside(axes)
    return figure


AXIS_PAIRS = (("x", "y"), ("x", "z"), ("y", "z"))
SIZE_CLASSES = 4
"""How many sizes the offsets chart draws a place's count in."""


def offsets_chart(analysis: Any, unit: str, resolution: float | None = None) -> Any:
    """The x, y, z readings seen along each axis pair (x–y, x–z, y–z: three small plots side by
    side, each axis labelled in the one number format with a few ticks), the nominal and the
    mean (the offset) marked and joined. Readings at the same place are drawn once, sized by
    their count; more than :data:`SCATTER_POINTS` distinct places are drawn as one image."""
    from matplotlib.ticker import MaxNLocator

    spatial = analysis.spatial
    channels = analysis.channels
    names = {n.lower(): n for n in channels if n.lower() in ("x", "y", "z")}
    unit = chart_text(unit)
    suffix = f" ({unit})" if unit else ""
    figure = _figure(8.0, 3.0)
    panels = figure.subplots(1, len(AXIS_PAIRS))
    for axes, (first, second) in zip(panels, AXIS_PAIRS, strict=True):
        pairs = np.column_stack(
            [
                np.asarray(channels[names[first]].readings, dtype=float),
                np.asarray(channels[names[second]].readings, dtype=float),
            ]
        )
        places, counts = np.unique(pairs, axis=0, return_counts=True)
        # Four sizes, one mark each in the SVG (a size per point wrote a path per point).
        classes = np.ceil(SIZE_CLASSES * counts / counts.max()).astype(int)
        for size in range(1, SIZE_CLASSES + 1):
            chosen = classes == size
            if chosen.any():
                axes.scatter(
                    places[chosen, 0],
                    places[chosen, 1],
                    s=4 + 10 * size,
                    color=POINT_COLOUR,
                    alpha=0.6,
                    rasterized=len(places) > SCATTER_POINTS,
                    zorder=2,
                )
        nominal = (spatial.nominal[first], spatial.nominal[second])
        mean = (nominal[0] + spatial.offset[first], nominal[1] + spatial.offset[second])
        axes.scatter(*nominal, s=60, color="grey", marker="+", zorder=3)
        axes.scatter(*mean, s=50, color=ALARM_COLOUR, marker="x", zorder=3)
        axes.plot(*zip(nominal, mean, strict=True), color=ALARM_COLOUR, linewidth=1)
        axes.set_xlabel(first + suffix)
        axes.set_ylabel(second + suffix)
        axes.set_title(f"{first}–{second}", fontsize=8)
        for axis in (axes.xaxis, axes.yaxis):
            axis.set_major_locator(MaxNLocator(nbins=4))
            _figure_ticks(axis, resolution)
        axes.tick_params(axis="both", labelsize=6)
        axes.tick_params(axis="x", labelrotation=45)
    legend = panels[0].collections
    handles = [legend[0], legend[-2], legend[-1]]
    figure.legend(
        handles,
        ["readings (size: count)", "nominal", "mean (offset)"],
        loc="outside lower center",
        ncols=3,
        fontsize=7,
    )
    figure.suptitle("Offsets from nominal, seen along each axis pair", fontsize=9)
    return figure


def drift_chart(
    analysed: AnalysedSession, unit: str, resolution: float | None = None
) -> Any | None:
    """Each channel's accepted readings against the time since the first (seconds, minutes or
    hours, as the session's length suits), with its least-squares trend; None with fewer than
    three timed cycles."""
    session = analysed.session
    numbers = session.accepted_cycles
    if len(numbers) < 3:
        return None
    first = parse_time(session.cycles[numbers[0]].t)
    if first is None:
        return None
    series = {}
    for channel in session.channels:
        pairs = []
        for n in numbers:
            cycle = session.cycles[n]
            moment = parse_time(cycle.t)
            if channel in cycle.readings and moment is not None:
                pairs.append(((moment - first).total_seconds(), cycle.readings[channel].value))
        if len(pairs) >= 3:
            series[channel] = tuple(np.asarray(v, dtype=float) for v in zip(*pairs, strict=True))
    if not series:
        return None
    span = max(float(np.ptp(seconds)) for seconds, _ in series.values())
    scale, label = (1.0, "s") if span < 120 else (60.0, "min") if span < 7200 else (3600.0, "h")
    unit = chart_text(unit)
    figure = _figure()
    axes = figure.add_subplot()
    for channel, (seconds, values) in series.items():
        elapsed = seconds / scale
        channel = chart_text(channel)
        drawn_x, drawn_y, reduced = envelope(elapsed, values)
        (line,) = axes.plot(
            drawn_x,
            drawn_y,
            marker=None if reduced else ".",
            linewidth=0.6 if reduced else 0.8,
            label=f"{channel} (min and max per column)" if reduced else channel,
        )
        if np.ptp(elapsed) > 0:
            slope, intercept = np.polyfit(elapsed, values, 1)
            ends = np.asarray([elapsed.min(), elapsed.max()])  # a straight line: two points
            axes.plot(
                ends,
                intercept + slope * ends,
                color=line.get_color(),
                linestyle="--",
                label=f"{channel} trend {format_figure(slope, resolution, unit=unit)}/{label}",
            )
    axes.set_title("Readings over time (drift)")
    axes.set_xlabel(f"time since the first cycle ({label})")
    axes.set_ylabel(f"reading ({unit})" if unit else "reading")
    _figure_ticks(axes.yaxis, resolution)
    _legend_outside(axes)
    return figure


@dataclass(frozen=True)
class _Kit:
    """What a method draws its own charts with (:class:`station.methods.contract.ChartKit`):
    this module's figure and colours."""

    point: str = POINT_COLOUR
    centre: str = CENTRE_COLOUR
    limit: str = LIMIT_COLOUR
    alarm: str = ALARM_COLOUR
    resolution: float | None = None
    """The session's gauge step, which :meth:`number` writes figures one decimal beyond."""

    def figure(self, width: float = 7.0, height: float = 3.2) -> Any:
        """A new figure of that size (inches)."""
        return _figure(width, height)

    def label(self, text: object) -> str:
        """Text from outside as a chart shows it (:func:`chart_text`)."""
        return chart_text(text)

    def number(self, value: float, *, signed: bool = True) -> str:
        """A figure in the one number format (:func:`~station.text.format_figure`)."""
        return format_figure(value, self.resolution, signed=signed)

    def legend(self, axes: Any) -> None:
        """The legend outside the plot (:func:`_legend_outside`)."""
        _legend_outside(axes)


def _figures(analysed: AnalysedSession) -> Iterator[tuple[str, str, Any]]:
    report = analysed.report
    if report is None:
        return
    if report.inputs is not None:
        judgement = Judgement(report.analysis, report.result, report.sections, report.verdict)
        recorded = analysed.session.header.get("resolution")
        step = float(recorded) if isinstance(recorded, int | float) and recorded > 0 else None
        yield from report.method.charts(report.inputs, judgement, _Kit(resolution=step))
    analysis = report.analysis
    if analysis is None:
        return
    unit, resolution = analysis.config.unit, analysis.config.resolution
    for key, channel in analysis.channels.items():
        yield (
            f"histogram-{key}",
            f"Histogram of {chart_text(channel.name)}",
            histogram_chart(channel.name, channel, unit, resolution, str(key)),
        )
        if channel.chart.points:
            yield (
                f"control-{key}",
                f"Control chart of {chart_text(channel.name)}",
                control_chart(channel.name, channel, resolution=resolution, key=str(key)),
            )
    if analysis.spatial is not None:
        yield "offsets-3d", "3-D offsets", offsets_chart(analysis, unit, resolution)
    if report.method.drift_chart:
        drift = drift_chart(analysed, unit, resolution)
        if drift is not None:
            yield "drift", "Readings over time (drift)", drift


_SAFE_KEY = re.compile(r"[^A-Za-z0-9_-]")


def report_charts(analysed: AnalysedSession) -> list[Chart]:
    """Every chart of the session's report, as SVG (empty without an analysis)."""
    from matplotlib import rc_context

    charts = []
    # Drawn under RC, not only saved: a text artist reads text.parse_math when it is made, so
    # a title or a legend made outside would still parse a channel name as maths.
    with rc_context(RC), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for number, (key, title, figure) in enumerate(_figures(analysed)):
            safe = f"{number}-{_SAFE_KEY.sub('_', key)}"
            svg = _svg(figure, f"station-chart-{safe}")
            charts.append(Chart(key=safe, title=title, svg=svg))
    return charts
