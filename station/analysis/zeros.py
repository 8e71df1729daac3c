"""The zero a session's readings are taken from: one draw of the robot's own repeatability.

How the station zeroes (``station.run.steps.zero``, ``station.instruments.zeroing``): with the
robot still at the fixture, each gauge is read m times over a settle window (5 polled readings or
3 DATA presses unless the step says) and a software zero is their mean; a gauge's own zero
command sets its zero at its reading of that moment, one reading (m = 1). The cycles that follow
each leave the fixture and come back to a new rest.

The model. A gauge's reading at cycle i is d_i = P_i + e_i: the robot's rest position P_i, which
differs from rest to rest by σ_p, plus the indicator's own scatter e_i (σ_e) while the robot is
still; both as the gauge shows them, at its step. The zero is z = P_0 + ē_0: one rest and the
mean of its m readings' scatter. The zeroed readings x_i = d_i − z scatter by σ² = σ_p² + σ_e²
(what the session's own sd s estimates: z is one constant inside the session), and their mean
x̄ = P̄ + ē − z. So

    Var(x̄) = σ²/n + Var(z),     Var(z) = σ_p² + σ_e²/m = σ² − (1 − 1/m)·σ_e².

σ_e² is estimated from the zero's own readings (their sample variance s_w², all taken at one
rest), capped at s² (a rest cannot scatter more than the session does); where they are not
recorded (an older file, or a device zero: m = 1) Var(z) is taken at its upper bound σ². Var(z)
lies between σ²/m (the robot repeats perfectly, only the gauge scatters) and σ² (a still gauge
that only rounds, the usual dial indicator): about n times the sampling variance of the mean
itself. This is why two separately zeroed sessions of one untouched robot differ in their means
by about σ·√2, which a test of the readings alone (Welch) calls a shift nearly every time.

The guess σ²(1 + 1/m) for Var(z) counts the indicator's scatter twice (once inside σ², once in
σ²/m); the form above keeps the rest draw and the averaged scatter apart.

With several zeros in force over a session (a zero per placement), the mean's zero part is the
reading-weighted mean of independent zeros: Σ (w_k/W)² Var(z_k), w_k readings under zero k.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class ZeroDraw:
    """One zero a session's readings of a channel were taken under.

    ``readings``: m, the readings the zero is the mean of (1 for a gauge's own zero command);
    ``within_sd``: the sample sd of those readings, all at one rest (None when not recorded);
    ``weight``: how many of the session's readings were taken under this zero.
    """

    readings: int = 1
    within_sd: float | None = None
    weight: int = 1


def zero_variance(sd: float, readings: int = 1, within_sd: float | None = None) -> float:
    """Var(z) of one zero taken as the mean of ``readings`` readings at one rest, for a session
    whose readings scatter by ``sd`` (the module's model): sd² − (1 − 1/m)·min(s_w², sd²), with
    s_w = ``within_sd`` (0 when unknown, giving the upper bound sd²)."""
    if not math.isfinite(sd) or sd <= 0:
        return 0.0
    m = max(1, int(readings))
    within = 0.0 if within_sd is None or not math.isfinite(within_sd) else within_sd
    total = sd * sd
    return total - (1.0 - 1.0 / m) * min(within * within, total)


def zeros_variance(sd: float, zeros: Sequence[ZeroDraw]) -> float:
    """The variance the zeros ``zeros`` add to a session's mean (0.0 without any): each zero's
    :func:`zero_variance`, weighted by the share of readings taken under it, squared."""
    used = [z for z in zeros if z.weight > 0]
    total = sum(z.weight for z in used)
    if not total:
        return 0.0
    return sum((z.weight / total) ** 2 * zero_variance(sd, z.readings, z.within_sd) for z in used)


__all__ = ["ZeroDraw", "zero_variance", "zeros_variance"]
