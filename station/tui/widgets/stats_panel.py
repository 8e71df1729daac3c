"""The per-axis statistics table: live reading, n, X̄, σ, a₁, range, Cp, Cpk, the readings out
of specification and the verdict word.

One row per channel, so x, y and z sit one above the other and the table fits 80 columns. The
selected channel (the one the charts below show) is marked with ``▶``. A last reading beyond a
specification limit is marked ``▲`` (above the USL) or ``▼`` (below the LSL) at once, and the
``out`` column counts each channel's readings out of specification. Below the minimum count
the verdict is PROVISIONAL, and a caption says how many readings are in of how many needed;
another gives each channel's confidence bounds on Cpk, which decide CAPABLE, NOT CAPABLE or
INCONCLUSIVE.
Values come from the analysis the runner keeps; nothing is computed here.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from rich import box
from rich.table import Table
from rich.text import Text
from textual.widgets import Static

from station.analysis.verdict import confidence_text
from station.text import (
    NOT_AVAILABLE,
    format_figure,
    format_index,
    judged_cpk,
    judged_word,
)
from station.tui.text import shown_line
from station.tui.theme import VERDICT_STYLES

OUT_OF_SPEC_MARKS = {"above": "▲", "below": "▼"}
"""How the reading column marks a reading beyond the USL or the LSL (a mark, not a colour)."""


@dataclass(frozen=True)
class StatsRows:
    """What the table shows: the channels in order, their analyses and last readings."""

    channels: tuple[str, ...]
    analyses: Mapping[str, Any] = field(default_factory=dict)
    """Channel -> its ``ChannelAnalysis`` (``descriptive``, ``capability``), or absent."""
    last: Mapping[str, float] = field(default_factory=dict)
    resolution: float | None = None
    """The gauge's step: every figure is written at one decimal beyond it."""
    unit: str = ""
    selected: str = ""
    flags: Mapping[str, str] = field(default_factory=dict)
    """Channel -> "above" or "below" when its last reading is beyond a specification limit."""


def stats_table(rows: StatsRows) -> Table:
    """A compact rich table, at most 78 cells wide for three channels."""
    # No padding: the box's column dividers are the one-space gaps, so eleven columns (the
    # reading's out-of-spec mark, the out count, a PROVISIONAL or NOT CAPABLE word, a Cpk with
    # four decimals) fit 76 cells without cutting a figure. Every column is at least as wide as
    # the figures it can hold at this resolution, so the columns stand still from cycle to
    # cycle (content-sized columns moved as σ and a₁ appeared).
    value = len(format_figure(-9.0, rows.resolution))
    table = Table(box=box.SIMPLE_HEAD, padding=(0, 0), pad_edge=False, show_edge=False, expand=True)
    table.add_column("", width=3, no_wrap=True)
    widths = {
        "reading": value + 1,  # the ▲/▼ mark
        "n": 3,
        "X̄": value,
        "σ": value - 1,
        "a₁": len("-0.00"),
        "range": value - 1,
        "Cp": len("1.00"),
        "Cpk": len("0.9996"),
        "out": 3,
    }
    for heading, width in widths.items():
        table.add_column(heading, justify="right", no_wrap=True, min_width=width)
    table.add_column("verdict", no_wrap=True, min_width=len("INCONCLUSIVE"))
    provisional = []
    for channel in rows.channels:
        analysis = rows.analyses.get(channel)
        descriptive = getattr(analysis, "descriptive", None)
        capability = getattr(analysis, "capability", None)
        word = judged_word(analysis) if analysis is not None else NOT_AVAILABLE
        verdict = getattr(analysis, "verdict", None)
        if verdict is not None and verdict.provisional:
            provisional.append(verdict)
        marker = "▶" if channel == rows.selected else " "
        flag = rows.flags.get(channel)
        reading = Text(format_figure(rows.last.get(channel), rows.resolution))
        reading.append(OUT_OF_SPEC_MARKS.get(flag or "", " "), style="bold red")
        if flag:
            reading.stylize("bold red")
        found = getattr(analysis, "out_of_spec", None)
        out = getattr(found, "total", 0) if found is not None else 0
        table.add_row(
            Text(f"{marker}{shown_line(channel, limit=20)}", style="bold"),
            reading,
            str(getattr(descriptive, "n", 0)),
            format_figure(getattr(descriptive, "mean", None), rows.resolution),
            format_figure(getattr(descriptive, "sd", None), rows.resolution, signed=False),
            format_index(getattr(descriptive, "skewness", None)),
            format_figure(getattr(descriptive, "range", None), rows.resolution, signed=False),
            format_index(getattr(capability, "cp", None)),
            judged_cpk(analysis) if analysis is not None else NOT_AVAILABLE,
            Text(str(out), style="bold red" if out else "dim"),
            Text(word, style=VERDICT_STYLES.get(word, "")),
        )
    captions = []
    if provisional:
        fewest = min(provisional, key=lambda verdict: verdict.n)
        captions.append(
            f"PROVISIONAL: {fewest.n} of {fewest.min_n} readings, "
            f"{fewest.min_n - fewest.n} more before a verdict"
        )
    bounds = bounds_caption(rows)
    if bounds:
        captions.append(bounds)
    if captions:
        table.caption = "\n".join(captions)
        table.caption_justify = "left"
    return table


def bounds_caption(rows: StatsRows) -> str:
    """The one-sided confidence bounds on each channel's Cpk the verdict weighs (issue 20):
    ``Cpk 95% bounds (Bissell): x 0.90-1.44  y 1.02-1.61``; empty while none has a Cpk."""
    level = ""
    shown = []
    for channel in rows.channels:
        capability = getattr(rows.analyses.get(channel), "capability", None)
        lower = getattr(capability, "cpk_lower", None)
        upper = getattr(capability, "cpk_upper", None)
        if capability is None or lower is None or upper is None:
            continue
        level = confidence_text(capability.confidence)
        shown.append(f"{shown_line(channel, limit=8)} {format_index(lower)}-{format_index(upper)}")
    return f"Cpk {level} bounds (Bissell): " + "  ".join(shown) if shown else ""


class StatsPanel(Static):
    """The statistics table; :meth:`show` replaces its rows."""

    DEFAULT_CSS = """
    StatsPanel { height: auto; }
    """

    def __init__(self, *, id: str | None = None, classes: str | None = None) -> None:
        super().__init__(id=id, classes=classes)
        self._rows: StatsRows | None = None

    def show(self, rows: StatsRows, *, layout: bool = True) -> None:
        """Redraw with new rows (UI thread only); ``layout=False`` repaints in place without
        laying the screen out again (the same channels: the same rows)."""
        if rows != self._rows:
            same_rows = self._rows is not None and self._rows.channels == rows.channels
            self._rows = rows
            self.update(stats_table(rows), layout=layout or not same_rows)


def channel_rows(
    channels: Sequence[str], analyses: Mapping[str, Any], last: Mapping[str, float], **kw: Any
) -> StatsRows:
    """Convenience: a :class:`StatsRows` from plain mappings."""
    return StatsRows(channels=tuple(channels), analyses=dict(analyses), last=dict(last), **kw)
