"""One line per port: where it is, whether it is connected, how many frames it rejected."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from rich.text import Text
from textual.widgets import Static

from station.tui.text import shown_line

_STATUS_STYLES = {"connected": "green", "connecting": "yellow", "disconnected": "bold red"}


def status_text(ports: Sequence[Any]) -> Text:
    """``port /dev/pts/3: connected, 0 rejected frames`` for each port (a ``PortState``)."""
    if not ports:
        return Text("instrument: not connected", style="dim")
    text = Text()
    for index, port in enumerate(ports):
        status = str(getattr(port, "status", "unknown"))
        shown = "reconnecting" if status == "disconnected" else status
        if index:
            text.append("  ")
        text.append(f"{shown_line(getattr(port, 'url', '?'))}: ")
        text.append(shown, style=_STATUS_STYLES.get(status, ""))
        rejected = int(getattr(port, "rejected_frames", 0) or 0)
        text.append(
            f", {rejected} rejected frame{'s' if rejected != 1 else ''}",
            style="yellow" if rejected else "dim",
        )
        detail = str(getattr(port, "detail", "") or "")
        if detail and status != "connected":
            text.append(f" ({shown_line(detail)})", style="dim")
    return text


class InstrumentStatus(Static):
    """The instruments' status line; :meth:`show` replaces it."""

    DEFAULT_CSS = """
    InstrumentStatus { height: auto; }
    """

    def show(self, ports: Sequence[Any], zero: str = "", width: int = 80) -> None:
        """Redraw from a runner state's ``instruments`` and the zero in force (UI thread only):
        the zero is never cut, beside the ports when the line has room (``width`` columns),
        else on a line of its own (a long port name, a narrow terminal)."""
        line = status_text(ports)
        if zero:
            fits = len(line.plain) + len(zero) + 5 <= width
            line.append(f"  ·  {zero}" if fits else f"\n{zero}")
        self.update(line)
