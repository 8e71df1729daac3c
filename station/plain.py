"""Text from outside shown as text: the one function every display point uses.

A robot name, a note, a gauge frame, a CSV header, a file name or a procedure title comes from
outside the program; printed raw it could drive the operator's terminal (an ``ESC ] 0;`` sets
the window title, ``ESC [ 2 J`` clears the screen, U+202E reverses what follows) or, in the TUI,
be read as Rich/Textual markup (``[/]`` crashes the screen, ``[@click=app.quit]`` becomes a live
action). :func:`plain` turns any such text into characters that are only ever shown: control
characters (C0, DEL, C1) and bidirectional overrides/isolates become visible escapes such as
``\\x1b`` and ``\\u202e``, and a display can bound very long text with an ellipsis.

:func:`plain` returns ``str`` and knows nothing of markup: the TUI shows its result through a
``rich.text.Text`` (never parsed as markup), the command line prints it as it is. Nothing here
imports the UI.
"""

from __future__ import annotations

import io
import re
from typing import TextIO

# C0 controls except tab and newline (those are kept or escaped by the caller's choice), DEL,
# C1 controls, the bidirectional embeddings/overrides/isolates and marks, the line and paragraph
# separators, and the byte-order mark / zero-width no-break space (an invisible character).
_INVISIBLE = (
    "\x00-\x08\x0b-\x1f\x7f-\x9f\u061c\u200e\u200f\u2028\u2029\u202a-\u202e\u2066-\u2069\ufeff"
)
_UNSAFE_KEEP_LINES = re.compile(f"[{_INVISIBLE}]")
_UNSAFE_ONE_LINE = re.compile(f"[{_INVISIBLE}\t\n]")
# Lone surrogates (from surrogateescape decoding) cannot be encoded for a terminal.
_SURROGATE = re.compile("[\ud800-\udfff]")

ELLIPSIS = "…"


def _escape(match: re.Match[str]) -> str:
    code = ord(match.group(0))
    if code == 0x09:
        return "\\t"
    if code == 0x0A:
        return "\\n"
    if code == 0x0D:
        return "\\r"
    return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}"


def plain(text: object, *, limit: int | None = None, one_line: bool = True) -> str:
    """``text`` (any object, through ``str``) with every control character made visible.

    Control characters, DEL, C1 controls and bidi overrides/isolates (U+202E ...) become
    escapes (``\\x1b``, ``\\u202e``); with ``one_line`` (the default) tab and newline do too,
    so one value stays on one line; ``one_line=False`` keeps them (a multi-line message).
    ``limit`` bounds the result to that many characters, the last being an ellipsis. The
    result is plain text: it still contains ``[`` and ``]``; show it through ``rich.text.Text``
    (or escape it) where markup is parsed.
    """
    value = text if isinstance(text, str) else str(text)
    if limit is not None and len(value) > 4 * limit + 16:
        # Escapes only lengthen text: cut early so a 100 k name costs nothing to show.
        value = value[: 4 * limit + 16]
    pattern = _UNSAFE_ONE_LINE if one_line else _UNSAFE_KEEP_LINES
    value = pattern.sub(_escape, value)
    value = _SURROGATE.sub(lambda m: f"\\u{ord(m.group(0)):04x}", value)
    if limit is not None and len(value) > limit:
        value = value[: max(limit - 1, 0)] + ELLIPSIS
    return value


def has_unsafe_characters(text: str) -> bool:
    """True when ``text`` holds a character :func:`plain` would escape (one-line rules)."""
    return bool(_UNSAFE_ONE_LINE.search(text) or _SURROGATE.search(text))


class PlainStream(io.TextIOBase):
    """A text stream that passes everything written through :func:`plain`, lines kept.

    The command line wraps ``sys.stdout`` and ``sys.stderr`` in it, so no command can put a
    raw escape from a file, a device or a name on the operator's terminal, whatever it prints.
    """

    def __init__(self, stream: TextIO) -> None:
        super().__init__()
        self._stream = stream

    def write(self, text: str) -> int:
        """Write ``text`` with its control characters made visible; returns ``len(text)``."""
        self._stream.write(plain(text, one_line=False))
        return len(text)

    def flush(self) -> None:
        """Flush the wrapped stream."""
        self._stream.flush()

    def fileno(self) -> int:
        """The wrapped stream's file descriptor."""
        return self._stream.fileno()

    def isatty(self) -> bool:
        """Whether the wrapped stream is a terminal."""
        return self._stream.isatty()

    def writable(self) -> bool:
        """Always True."""
        return True

    @property
    def encoding(self) -> str:  # type: ignore[override]
        """The wrapped stream's encoding."""
        return getattr(self._stream, "encoding", "utf-8")

    @property
    def wrapped(self) -> TextIO:
        """The stream underneath."""
        return self._stream
