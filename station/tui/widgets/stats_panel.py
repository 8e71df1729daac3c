"""The per-axis statistics table: live reading, n, X̄, σ, a₁, range, Cp, Cpk and the verdict word.

One row per channel, so x, y and z sit one above the other and the table fits 80 columns. The
selected channel (the one the charts below show) is marked with ``▶``. Values come from the
analysis the runner keeps; nothing is computed here.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from rich import box
from rich.table import Table
from rich.text import Text
from textual.widgets import Static

from station.text import verdict_word
from station.tui.text import shown_line
from station.tui.widgets.figures import VERDICT_STYLES, number, ratio


@dataclass(frozen=True)
class StatsRows:
    """What the table shows: the channels in order, their analyses and last readings."""

    channels: tuple[str, ...]
    analyses: Mapping[str, Any] = field(default_factory=dict)
    """Channel -> its ``ChannelAnalysis`` (``descriptive``, ``capability``), or absent."""
    last: Mapping[str, float] = field(default_factory=dict)
    decimals: int = 5
    unit: str = ""
    selected: str = ""


def stats_table(rows: StatsRows) -> Table:
    """A compact rich table, at most 78 cells wide for three channels."""
    table = Table(
        box=box.SIMPLE_HEAD, padding=(0, 1), collapse_padding=True, pad_edge=False, expand=True
    )
    table.add_column("", width=3, no_wrap=True)
    for heading in ("reading", "n", "X̄", "σ", "a₁", "range", "Cp", "Cpk"):
        table.add_column(heading, justify="right", no_wrap=True)
    table.add_column("verdict", no_wrap=True, min_width=11)
    for channel in rows.channels:
        analysis = rows.analyses.get(channel)
        descriptive = getattr(analysis, "descriptive", None)
        capability = getattr(analysis, "capability", None)
        word = verdict_word(capability) if analysis is not None else "—"
        marker = "▶" if channel == rows.selected else " "
        table.add_row(
            Text(f"{marker}{shown_line(channel, limit=20)}", style="bold"),
            number(rows.last.get(channel), rows.decimals),
            str(getattr(descriptive, "n", 0)),
            number(getattr(descriptive, "mean", None), rows.decimals),
            number(getattr(descriptive, "sd", None), rows.decimals, signed=False),
            ratio(getattr(descriptive, "skewness", None)),
            number(getattr(descriptive, "range", None), rows.decimals, signed=False),
            ratio(getattr(capability, "cp", None)),
            ratio(getattr(capability, "cpk", None)),
            Text(word, style=VERDICT_STYLES.get(word, "")),
        )
    return table


class StatsPanel(Static):
    """The statistics table; :meth:`show` replaces its rows."""

    DEFAULT_CSS = """
    StatsPanel { height: auto; }
    """

    def __init__(self, *, id: str | None = None, classes: str | None = None) -> None:
        super().__init__(id=id, classes=classes)
        self._rows: StatsRows | None = None

    def show(self, rows: StatsRows) -> None:
        """Redraw with new rows (UI thread only)."""
        if rows != self._rows:
            self._rows = rows
            self.update(stats_table(rows))


def channel_rows(
    channels: Sequence[str], analyses: Mapping[str, Any], last: Mapping[str, float], **kw: Any
) -> StatsRows:
    """Convenience: a :class:`StatsRows` from plain mappings."""
    return StatsRows(channels=tuple(channels), analyses=dict(analyses), last=dict(last), **kw)
