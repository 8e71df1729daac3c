"""How the TUI writes numbers and verdicts: one place, so every screen says them the same way.

Nothing here computes a statistic; it only formats what the analysis returned.
"""

from __future__ import annotations

import math
from typing import Any

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


def verdict_word(capability: Any) -> str:
    """CAPABLE, NOT CAPABLE or UNDEFINED from ``capability.capable`` (True, False, None)."""
    capable = getattr(capability, "capable", None) if capability is not None else None
    if capable is True:
        return "CAPABLE"
    if capable is False:
        return "NOT CAPABLE"
    return "UNDEFINED"


def overall_verdict(words: list[str]) -> str:
    """The session's verdict: NOT CAPABLE if any axis is, CAPABLE if all are, else UNDEFINED."""
    if not words:
        return "UNDEFINED"
    if "NOT CAPABLE" in words:
        return "NOT CAPABLE"
    if all(word == "CAPABLE" for word in words):
        return "CAPABLE"
    return "UNDEFINED"
