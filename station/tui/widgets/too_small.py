"""The "terminal too small" notice: below the smallest size the screens are laid out for, the
tables would lose their axis names and values (issue 13), so the screen shows one sentence
instead until the window is enlarged. Keys keep working meanwhile, and nothing is lost."""

from __future__ import annotations

from textual.geometry import Size
from textual.widgets import Static

MIN_WIDTH = 76
"""Columns the stats tables, the checklist's two panes and the set-up's labels need."""
MIN_HEIGHT = 20
"""Rows the dashboard needs for its stats, charts, alarm line and footer."""


def too_small(size: Size) -> bool:
    """True when ``size`` is below what the screens are laid out for."""
    return size.width < MIN_WIDTH or size.height < MIN_HEIGHT


def notice_text(size: Size) -> str:
    """The sentence shown instead of a broken screen."""
    return (
        f"Terminal too small: {size.width}×{size.height}. station needs at least "
        f"{MIN_WIDTH}×{MIN_HEIGHT} (80×24 is best). Enlarge the window; the keys still work "
        "and nothing captured is lost meanwhile."
    )


class TooSmallNotice(Static):
    """Mounted on every screen; shown (and everything else hidden) by the app's
    ``-too-small`` class."""

    def show_size(self, size: Size) -> None:
        """Say the current size."""
        self.update(notice_text(size))
