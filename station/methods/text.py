"""Report lines as the methods write them: fitted to the report's width (the TUI's summary
column is narrower than the 80 columns of a printed report)."""

from __future__ import annotations

import textwrap
from collections.abc import Sequence


def fitted(lines: Sequence[str], width: int) -> tuple[str, ...]:
    """The report lines, each longer than ``width`` wrapped under its own indent."""
    out: list[str] = []
    for line in lines:
        if len(line) <= width:
            out.append(line)
            continue
        indent = " " * (len(line) - len(line.lstrip()))
        out.extend(
            textwrap.wrap(
                line.strip(),
                width=max(width, 40),
                initial_indent=indent,
                subsequent_indent=indent + "  ",
            )
        )
    return tuple(out)
