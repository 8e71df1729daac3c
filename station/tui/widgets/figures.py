"""How the TUI writes numbers and verdicts: one place, so every screen says them the same way.

Nothing here computes a statistic; it only formats what the analysis returned.
"""

from __future__ import annotations

import math

from station.tui.theme import VERDICT_STYLES

__all__ = ["VERDICT_STYLES", "NOT_AVAILABLE"]

NOT_AVAILABLE = "—"


def decimals_for(resolution: float | None) -> int:
    """Digits after the point that show one more digit than the gauge resolves (4 → 5)."""
    if not resolution or resolution <= 0:
        return 5
    return max(0, min(8, -math.floor(math.log10(resolution) + 1e-9) + 1))


def number(value: float | None, decimals: int, *, signed: bool = True) -> str:
    """A value with a fixed number of decimals, or a dash when undefined (None or NaN)."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return NOT_AVAILABLE
    return f"{value:+.{decimals}f}" if signed else f"{value:.{decimals}f}"


def ratio(value: float | None) -> str:
    """An index such as Cp, Cpk or a₁ with two decimals, or a dash when undefined."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return NOT_AVAILABLE
    return f"{value:.2f}"
