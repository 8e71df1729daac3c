"""Is a tolerance plausible for the gauge? Limits against the resolution, before a session.

A tolerance narrower than 10 gauge steps cannot be judged (the usual 10:1 rule); one wider than
100,000 steps is almost always a slip: a bare ``25`` typed in a limits field with a 0.0001 in
gauge reads as ±25 in (issue 13). Both ask the operator to confirm, naming the ratio.
"""

from __future__ import annotations

from station.text import format_spread

FEWEST_STEPS = 10.0
MOST_STEPS = 100_000.0


def tolerance_steps(
    lsl: float | None, usl: float | None, nominal: float | None, resolution: float
) -> float | None:
    """How many gauge steps the tolerance spans: USL − LSL, or the one limit's distance from
    the nominal (0 when unset) for a one-sided limit; None when it cannot be said."""
    if not resolution or resolution <= 0:
        return None
    if lsl is not None and usl is not None:
        width = usl - lsl
    elif usl is not None:
        width = abs(usl - (nominal or 0.0))
    elif lsl is not None:
        width = abs((nominal or 0.0) - lsl)
    else:
        return None
    return width / resolution


def implausible_tolerance(
    channel: str,
    lsl: float | None,
    usl: float | None,
    nominal: float | None,
    resolution: float,
    unit: str,
) -> str | None:
    """A sentence asking to confirm a tolerance of fewer than 10 or more than 100,000 gauge
    steps (naming the ratio), or None when it is plausible."""
    steps = tolerance_steps(lsl, usl, nominal, resolution)
    if steps is None:
        return None
    if steps < FEWEST_STEPS:
        return (
            f"{channel}: the tolerance spans only {steps:,.3g} gauge steps of "
            f"{format_spread(resolution, resolution, unit=unit)} (under {FEWEST_STEPS:g}): the "
            "gauge is too coarse for a verdict."
        )
    if steps > MOST_STEPS:
        return (
            f"{channel}: the tolerance spans {steps:,.0f} gauge steps of "
            f"{format_spread(resolution, resolution, unit=unit)} "
            f"(over {MOST_STEPS:,.0f}): is the limit in {unit}, and not a slip?"
        )
    return None
