"""The footer that keeps every key of the screen in view: on a second row when one is too short.

Textual's :class:`~textual.widgets.Footer` is one row that cuts what does not fit, so at 80
columns the dashboard lost its alarms, help and leave keys (issue 26). This footer lays the
same keys, drawn by the same :class:`~textual.widgets._footer.FooterKey` (click, dimmed when
not available, the theme's footer colours), on as many rows as the width needs, each key
whole, with the command palette's key at the right of the last row. When one row holds them
all it looks exactly like Textual's footer. It lays itself out again when the terminal's width
changes.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass

from rich.cells import cell_len
from textual import events
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import HorizontalGroup
from textual.screen import Screen
from textual.widgets import Footer
from textual.widgets._footer import FooterKey

PALETTE_GUTTER = 2
"""Cells the palette's key takes beside its text: the bar on its left and its right padding."""


@dataclass(frozen=True)
class FooterEntry:
    """One key as the footer shows it."""

    binding: Binding
    key_display: str
    enabled: bool
    tooltip: str

    def width(self, *, compact: bool) -> int:
        """Cells the key takes in a row (its key, its description, their padding)."""
        key, description = cell_len(self.key_display), cell_len(self.binding.description)
        # Compact: "key description" and a margin; otherwise " key description ".
        return key + description + (2 if compact else 3)


def rows_of(widths: Sequence[int], width: int) -> list[list[int]]:
    """The indexes of ``widths`` laid out in order on rows of ``width`` cells, each whole
    (a key wider than a row gets a row of its own)."""
    rows: list[list[int]] = []
    used = width
    for index, cells in enumerate(widths):
        if not rows or used + cells > width:
            rows.append([])
            used = 0
        rows[-1].append(index)
        used += cells
    return rows


def declared_order(screen: Screen[object]) -> dict[str, int]:
    """Each action's place in the ``BINDINGS`` of ``screen``'s classes, its own first."""
    order: dict[str, int] = {}
    for cls in type(screen).__mro__:
        for binding in vars(cls).get("BINDINGS", ()):
            action = binding.action if isinstance(binding, Binding) else binding[1]
            order.setdefault(action, len(order))
    return order


class KeyRow(HorizontalGroup):
    """One row of keys."""


class KeyFooter(Footer):
    """A footer on as many rows as its keys need at the terminal's width."""

    DEFAULT_CSS = """
    KeyFooter {
        layout: vertical;
        height: auto;
        max-height: 4;
    }
    KeyFooter > KeyRow {
        width: 1fr;
        height: 1;
    }
    """

    def __init__(self, *, compact: bool = False) -> None:
        super().__init__(compact=compact)
        self._laid_out_width = 0

    def entries(self) -> tuple[list[FooterEntry], FooterEntry | None]:
        """The keys the screen shows now (one per action, as Textual's footer), and the
        command palette's key."""
        app = self.app
        active = self.screen.active_bindings
        keys: list[FooterEntry] = []
        actions: set[str] = set()
        for _node, binding, enabled, tooltip in active.values():
            if not binding.show or binding.action in actions:
                continue
            actions.add(binding.action)
            keys.append(FooterEntry(binding, app.get_key_display(binding), enabled, tooltip))
        # In the order the screen declares them (Space Capture first, not Tab's axis key,
        # which Textual files where its own Tab binding stood).
        order = declared_order(self.screen)
        keys.sort(key=lambda entry: order.get(entry.binding.action, len(order)))
        palette = None
        if self.show_command_palette and app.ENABLE_COMMAND_PALETTE:
            found = active.get(app.COMMAND_PALETTE_BINDING)
            if found is not None:
                _node, binding, enabled, tooltip = found
                palette = FooterEntry(
                    binding,
                    app.get_key_display(binding),
                    enabled,
                    binding.tooltip or binding.description,
                )
        return keys, palette

    def compose(self) -> ComposeResult:
        """The keys, row by row, each whole; the palette's key at the right of the last."""
        if not self._bindings_ready:
            return
        keys, palette = self.entries()
        width = self.size.width or self.app.size.width
        self._laid_out_width = width
        widths = [entry.width(compact=self.compact) for entry in keys]
        if palette is not None:
            widths.append(palette.width(compact=self.compact) + PALETTE_GUTTER)
        rows = rows_of(widths, width)
        for number, row in enumerate(rows):
            with KeyRow():
                yield from self._keys(keys[index] for index in row if index < len(keys))
                if palette is not None and number == len(rows) - 1:
                    yield self._key(palette, classes="-command-palette")

    def _keys(self, entries: Iterator[FooterEntry]) -> Iterator[FooterKey]:
        for entry in entries:
            yield self._key(entry)

    def _key(self, entry: FooterEntry, classes: str = "") -> FooterKey:
        key = FooterKey(
            entry.binding.key,
            entry.key_display,
            entry.binding.description,
            entry.binding.action,
            disabled=not entry.enabled,
            tooltip=entry.tooltip,
            classes=classes,
        )
        if not classes:
            key.data_bind(compact=Footer.compact)
        return key

    def on_resize(self, event: events.Resize) -> None:
        """A narrower or wider terminal: the keys go on the rows that width needs."""
        if self._bindings_ready and event.size.width != self._laid_out_width:
            self.call_after_refresh(self.recompose)
