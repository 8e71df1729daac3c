"""Verdict hints: what the figures suggest to look at, in the words of the report (§2.7.1–2.7.2).

Each hint is one sentence that names the channel and the figure behind it. They are hints, not
verdicts: the verdict is the capability index; these point the technician at a likely cause.

* Skewness: the report says a₁ "close to the value of +1 or higher" means a highly skewed
  histogram, "usually attributed to an instability in the robot's control system". We read
  "close to 1" as |a₁| ≥ 0.8 (:data:`SKEW_HINT`).
* Offset: "if the average value does not coincide with the nominal value", the error "could be
  attributed to the linearization of the inverse kinematics software and/or the effect of the
  ambient temperature". With 25–30 noisy readings the average never equals the nominal exactly,
  so the hint fires only when the offset is statistically clear: |X̄ − nominal| greater than the
  two-sided 95 % t-interval half-width t(0.975, n−1)·s/√n. A session's readings are taken
  from a zero, which is one rest of the robot: its rest-to-rest uncertainty √Var(z)
  (:mod:`station.analysis.zeros`, about s for a still dial indicator) is combined with that
  half-width, and an offset within both is said to be the zero's, not the inverse kinematics'.
* Shift: Cp ≥ threshold but Cpk < threshold means the spread fits the tolerance but the process
  sits off centre (the report's Cpk1/Cpk2 "shift off the nominal value").
* Rule alarms: a pattern on the control chart; look at the cycles it names.
* Gauge too coarse: a tolerance narrower than 10 gauge steps (the usual 10:1 rule for
  measurement resolution) makes the verdict rest on a handful of distinct readings.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from statistics import NormalDist

from station.analysis.capability import Capability, SpecLimits
from station.analysis.descriptive import Descriptive
from station.analysis.rules import Alarm, number_list, rule_name
from station.text import format_figure

#: |a₁| at or above this is "close to 1 or higher" (report §2.7.1).
SKEW_HINT = 0.8
#: The tolerance should span at least this many gauge steps.
RESOLUTION_RATIO = 10.0


def _figure(value: float, resolution: float | None, unit: str) -> str:
    """A figure as every screen writes it (one decimal beyond the gauge step, never
    scientific), with its unit."""
    return f"{format_figure(value, resolution)} {unit}".rstrip()


def _where(alarm: Alarm) -> str:
    """Where an alarm looks: its cycles when known ("cycle 7", "cycles 6 to 9"), else its
    chart points."""
    numbers, word = (alarm.cycles, "cycle") if alarm.cycles else (alarm.points, "point")
    return f"{word}{'s' if len(numbers) > 1 else ''} {number_list(numbers)}"


_T_SERIES_FROM = 1000


def t_quantile(p: float, degrees: int) -> float:
    """Student's t quantile: scipy's ``stdtrit`` for small ``degrees``; from 1000 degrees the
    Cornish-Fisher series in 1/degrees (Abramowitz & Stegun 26.7.5, four terms), exact to
    double precision there and without loading scipy for a large file."""
    if degrees < _T_SERIES_FROM:
        from scipy.special import stdtrit  # on first use: see station/README.md

        return float(stdtrit(degrees, p))
    z = NormalDist().inv_cdf(p)
    g1 = (z**3 + z) / 4
    g2 = (5 * z**5 + 16 * z**3 + 3 * z) / 96
    g3 = (3 * z**7 + 19 * z**5 + 17 * z**3 - 15 * z) / 384
    g4 = (79 * z**9 + 776 * z**7 + 1482 * z**5 - 1920 * z**3 - 945 * z) / 92160
    v = float(degrees)
    return z + g1 / v + g2 / v**2 + g3 / v**3 + g4 / v**4


def offset_is_clear(descriptive: Descriptive, nominal: float) -> bool:
    """True when the mean differs from nominal beyond its two-sided 95 % t-interval."""
    if descriptive.n < 2 or descriptive.mean is None or descriptive.sd is None:
        return False
    offset = abs(descriptive.mean - nominal)
    if descriptive.sd == 0.0:
        return offset > 0.0
    return offset > _mean_half_width(descriptive)


def _mean_half_width(descriptive: Descriptive) -> float:
    """The half-width of the mean's two-sided 95 % t-interval."""
    if descriptive.sd is None or descriptive.n < 2:
        return 0.0
    return t_quantile(0.975, descriptive.n - 1) * descriptive.sd / math.sqrt(descriptive.n)


ZERO_COVERAGE = 2.0
"""Coverage factor on the zero's standard uncertainty (about 95 %)."""


def zero_explains(descriptive: Descriptive, nominal: float, zero_sd: float) -> bool:
    """True when the mean's offset from nominal lies within what the readings' own scatter and
    the zero's uncertainty ``zero_sd`` together explain: every reading was shifted by the zero
    taken, so an offset of the zero's size is no evidence against the robot. ``zero_sd`` is
    √Var(z) of :mod:`station.analysis.zeros`: a zero is one rest of the robot, so it carries
    the robot's rest-to-rest repeatability, not only the gauge's noise while it was taken."""
    if descriptive.mean is None:
        return False
    offset = abs(descriptive.mean - nominal)
    combined = math.hypot(_mean_half_width(descriptive), ZERO_COVERAGE * zero_sd)
    return offset <= combined


def channel_hints(
    name: str,
    descriptive: Descriptive,
    capability: Capability,
    alarms: Sequence[Alarm],
    *,
    limits: SpecLimits | None,
    nominal: float,
    resolution: float | None,
    unit: str = "",
    zero_sd: float | None = None,
) -> list[str]:
    """The hints for one channel, each a sentence naming the channel and the figure.
    ``zero_sd``: the standard uncertainty the zero the readings are taken from puts on their
    mean (:func:`station.analysis.summary.zero_sd_of`: rest to rest); an offset it explains is
    said to be the zero's, not the robot's."""
    hints: list[str] = []
    skew = descriptive.skewness
    if skew is not None and abs(skew) >= SKEW_HINT:
        side = "right" if skew > 0 else "left"
        hints.append(
            f"{name}: skewness a1 = {skew:+.3f} is near 1 or beyond (histogram skewed to the "
            f"{side}); the report attributes this to an instability in the robot's control "
            "system: correct it before trusting the verdict."
        )
    if descriptive.mean is not None and offset_is_clear(descriptive, nominal):
        offset = descriptive.mean - nominal
        # "off nominal (+0 in)" reads oddly; the nominal is named only when it is not zero.
        where = (
            "off nominal"
            if nominal == 0
            else f"off the nominal {_figure(nominal, resolution, unit)}"
        )
        zero = (
            f"±{format_figure(ZERO_COVERAGE * zero_sd, resolution, signed=False)} {unit}".rstrip()
            if zero_sd is not None
            else ""
        )
        if zero_sd is not None and zero_explains(descriptive, nominal, zero_sd):
            hints.append(
                f"{name}: the average is {_figure(offset, resolution, unit)} {where}, within "
                f"what the zero's uncertainty ({zero}, rest to rest) explains: every reading "
                "carries the zero taken, and a zero is one rest of the robot, so this offset "
                "says nothing of the robot; to measure one, zero on a master or as the mean of "
                "several returns to the pose."
            )
        else:
            beyond = f", beyond the zero's uncertainty ({zero}, rest to rest)" if zero else ""
            hints.append(
                f"{name}: the average is {_figure(offset, resolution, unit)} {where}, "
                f"more than chance explains with {descriptive.n} readings{beyond}; the report "
                "attributes this to the linearisation of the inverse kinematics or to the "
                "ambient temperature."
            )
    threshold = capability.threshold
    if (
        capability.cp is not None
        and capability.cpk is not None
        and capability.cp >= threshold
        and capability.cpk < threshold
    ):
        hints.append(
            f"{name}: Cp = {capability.cp:.2f} meets {threshold:g} but Cpk = "
            f"{capability.cpk:.2f} does not: the spread fits the tolerance but the process "
            "has shifted off nominal; re-centre it (re-teach or compensate the offset)."
        )
    if alarms:
        fired = "; ".join(f"{rule_name(alarm.rule)} at {_where(alarm)}" for alarm in alarms[:6])
        more = f"; and {len(alarms) - 6} more" if len(alarms) > 6 else ""
        hints.append(
            f"{name}: the control chart shows a pattern ({fired}{more}); look at those cycles "
            "for a cause (warm-up, a bumped fixture, a loose indicator) before trusting the "
            "verdict."
        )
    if (
        resolution
        and limits is not None
        and limits.lsl is not None
        and limits.usl is not None
        and (limits.usl - limits.lsl) < RESOLUTION_RATIO * resolution
    ):
        steps = (limits.usl - limits.lsl) / resolution
        tolerance = _figure(limits.usl - limits.lsl, resolution, unit).lstrip("+")
        hints.append(
            f"{name}: the tolerance {tolerance} spans "
            f"only {steps:.3g} gauge steps of {format_figure(resolution, resolution, signed=False)}"
            " (fewer than "
            f"{RESOLUTION_RATIO:g}); the gauge is too coarse for this verdict: use a finer "
            "indicator."
        )
    return hints
