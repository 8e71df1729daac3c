"""Text from outside, ready for a Textual widget: made plain, never parsed as markup."""

from __future__ import annotations

from typing import Any

from rich.text import Text

from station.plain import plain


def shown(text: object, *, style: str = "", limit: int | None = None, **options: Any) -> Text:
    """``text`` as a ``rich.text.Text`` (so ``[`` never starts markup) with its control
    characters and bidi overrides made visible by :func:`station.plain.plain` (newlines kept,
    so a multi-line message stays one); ``limit`` bounds it with an ellipsis."""
    return Text(plain(text, limit=limit, one_line=False), style=style, **options)


def shown_line(text: object, *, limit: int | None = 200) -> str:
    """``text`` for one line of a ``Text`` being built (``text.append(shown_line(x))``):
    plain, newlines escaped, bounded to ``limit`` characters."""
    return plain(text, limit=limit)
