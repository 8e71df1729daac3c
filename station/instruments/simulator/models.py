"""The fixture models a simulator serves: what each gauge shows, reading by reading.

A **model** (:class:`RobotModel`) is a pure function ``value(channel, k, seed)``: what the gauge
on ``channel`` shows for its ``k``-th reading. :class:`FixtureModel` is the repeatability set-up
(per-axis bias, noise, skew, warm-up drift, backlash, outliers; a gauge with a resolution and a
range); :class:`RampModel` sends every value once, for checking a line end to end. The
two-fixture and bar models live in their own modules.

Determinism: the k-th reading of a channel depends only on the seed and k (each value draws from
its own generator seeded with ``(seed, channel index, k)``).
"""

from __future__ import annotations

import math
import random
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from station.errors import StationError


@dataclass(frozen=True)
class AxisModel:
    """What one axis of the robot does at one gauge, in the gauge's unit.

    ``skew`` is the shape α of a skew-normal error (0 = normal; the noise keeps σ = ``noise``).
    ``drift`` is the warm-up offset approached exponentially with a time constant of
    ``drift_tau`` readings. ``backlash`` is the full difference between approaching from the
    two directions (each reading's direction is drawn at random). An outlier (probability
    ``outlier_rate``) adds ± ``outlier_size`` × ``noise``.
    """

    bias: float = 0.0
    noise: float = 0.0005
    skew: float = 0.0
    drift: float = 0.0
    drift_tau: float = 10.0
    backlash: float = 0.0
    outlier_rate: float = 0.0
    outlier_size: float = 8.0


@dataclass(frozen=True)
class GaugeSpec:
    """The indicator: what it can show. Values are quantised and clipped to the range."""

    resolution: float = 0.001
    low: float = -12.5
    high: float = 12.5
    unit: str = "mm"
    noise: float = 0.0
    """The indicator's own reading noise (σ, in its unit): what its readings scatter by while
    the robot stands still (a few tenths of a resolution on a good indicator)."""

    def show(self, value: float) -> float:
        """``value`` as the gauge displays it: clipped to its range, at its resolution."""
        clipped = min(self.high, max(self.low, value))
        steps = round(clipped / self.resolution)
        decimals = max(0, -math.floor(math.log10(self.resolution)) + 1)
        return round(steps * self.resolution, decimals)


INCH_INDICATOR = GaugeSpec(0.0001, -0.5, 0.5, "in")
"""A 0.0001 in dial indicator with ±0.5 in of travel (the report's gauges)."""


class RobotModel:
    """The interface the server needs: channels, a gauge per channel, and what each gauge
    shows while the robot is at its ``rest``-th rest (0-based: the robot's state, stepped each
    time it leaves and comes back).

    At rest the robot is still: every reading of that rest is the same rest position plus the
    indicator's own noise (:attr:`GaugeSpec.noise`), so a zero of several readings sees a gauge
    at rest. The rest positions differ from rest to rest by the model's repeatability, bias,
    drift and so on.
    """

    channels: tuple[str, ...] = ()
    moves_per_set: bool = False
    """True for a model whose robot moves one point per set sent (a bar's strokes, a ramp):
    its :meth:`reading` gets ``k`` counted from the start of the current rest."""

    def gauge(self, channel: str) -> GaugeSpec:
        """The indicator on ``channel``."""
        raise NotImplementedError

    def value(self, channel: str, rest: int, seed: int) -> float:
        """Where ``channel``'s gauge rests at the robot's ``rest``-th rest, as it shows it
        (without the indicator's own noise)."""
        raise NotImplementedError

    def rest_position(self, channel: str, rest: int, seed: int) -> float:
        """Where ``channel``'s indicator rests at the ``rest``-th rest, before quantisation."""
        return self.value(channel, rest, seed)

    def reading(self, channel: str, rest: int, k: int, seed: int) -> float:
        """What ``channel``'s gauge shows for its ``k``-th reading, taken while the robot is at
        its ``rest``-th rest: the rest position plus the indicator's noise (its own draw per
        reading), at the gauge's resolution."""
        return self.shown(channel, self.rest_position(channel, rest, seed), k, seed)

    def shown(self, channel: str, position: float, k: int, seed: int) -> float:
        """``position`` as ``channel``'s gauge shows it in its ``k``-th reading: with the
        indicator's own noise (a draw of its own per reading), at its resolution."""
        gauge = self.gauge(channel)
        if gauge.noise:
            index = self.channels.index(channel)
            position += gauge.noise * random.Random(f"{seed}/gauge/{index}/{k}").gauss(0.0, 1.0)
        return gauge.show(position)

    def zero_reference(self, channel: str, rest: int, seed: int) -> float | None:
        """What the gauge's zero key sets as its zero at the ``rest``-th rest, when the model
        knows better than the gauge's last reading (None: the last reading it showed)."""
        return None


def skew_normal_unit(alpha: float, z0: float, z1: float) -> float:
    """A skew-normal draw with shape ``alpha``, standardised to mean 0 and σ 1."""
    if alpha == 0:
        return z1
    delta = alpha / math.sqrt(1 + alpha * alpha)
    x = delta * abs(z0) + math.sqrt(1 - delta * delta) * z1
    mean = delta * math.sqrt(2 / math.pi)
    sd = math.sqrt(1 - 2 * delta * delta / math.pi)
    return (x - mean) / sd


class FixtureModel(RobotModel):
    """The repeatability set-up: the end effector returns to one fixture; a gauge per axis."""

    def __init__(
        self,
        axes: Mapping[str, AxisModel],
        gauge: GaugeSpec | Mapping[str, GaugeSpec] = GaugeSpec(),
    ) -> None:
        if not axes:
            raise StationError("A simulated fixture needs at least one channel, e.g. x.")
        self.axes = dict(axes)
        self.channels = tuple(self.axes)
        self._gauges = (
            {c: gauge.get(c, GaugeSpec()) for c in self.channels}
            if isinstance(gauge, Mapping)
            else dict.fromkeys(self.channels, gauge)
        )

    def gauge(self, channel: str) -> GaugeSpec:
        """The indicator on ``channel``."""
        return self._gauges[channel]

    def true_value(self, channel: str, k: int, seed: int) -> float:
        """Where the indicator rests at the robot's k-th rest, before quantisation."""
        axis = self.axes[channel]
        index = self.channels.index(channel)
        # One generator per (seed, channel, k): the k-th value never depends on other draws.
        rng = random.Random(f"{seed}/{index}/{k}")
        z0, z1 = rng.gauss(0.0, 1.0), rng.gauss(0.0, 1.0)
        direction = 1.0 if rng.random() < 0.5 else -1.0
        outlier = rng.random() < axis.outlier_rate
        outlier_sign = 1.0 if rng.random() < 0.5 else -1.0
        value = axis.bias + axis.noise * skew_normal_unit(axis.skew, z0, z1)
        if axis.drift:
            value += axis.drift * (1.0 - math.exp(-k / max(axis.drift_tau, 1e-9)))
        value += direction * axis.backlash / 2.0
        if outlier:
            value += (
                outlier_sign * axis.outlier_size * max(axis.noise, self.gauge(channel).resolution)
            )
        return value

    def rest_position(self, channel: str, rest: int, seed: int) -> float:
        """Where the indicator rests at the robot's ``rest``-th rest, before quantisation."""
        return self.true_value(channel, rest, seed)

    def value(self, channel: str, k: int, seed: int) -> float:
        """The k-th rest position of ``channel`` as the gauge shows it."""
        return self.gauge(channel).show(self.true_value(channel, k, seed))


class RampModel(RobotModel):
    """Every reading distinct: ``start + k × step`` per channel, wrapping inside the gauge range.

    For checking a line end to end: a lost, invented or duplicated reading is visible by value
    (the reconnect tests and the reader benchmark use it).
    """

    moves_per_set = True

    def __init__(
        self, channels: Sequence[str], gauge: GaugeSpec = GaugeSpec(), step: float | None = None
    ) -> None:
        self.channels = tuple(channels)
        self._gauge = gauge
        self.step = gauge.resolution if step is None else step
        self._span = round((gauge.high - gauge.low) / self.step)

    def gauge(self, channel: str) -> GaugeSpec:
        """The indicator on ``channel``."""
        return self._gauge

    def reading(self, channel: str, rest: int, k: int, seed: int) -> float:
        """Every reading its own value, whatever the robot does."""
        return self.value(channel, k, seed)

    def value(self, channel: str, k: int, seed: int) -> float:
        """``low`` + ((k + channel index × 1000 + seed) mod span) × step, at the resolution."""
        index = self.channels.index(channel)
        steps = (k + index * 1000 + seed) % self._span
        return self._gauge.show(self._gauge.low + steps * self.step)


def fixture_model(
    channels: Sequence[str],
    *,
    axis: AxisModel | Mapping[str, AxisModel] = AxisModel(),
    gauge: GaugeSpec = GaugeSpec(),
) -> FixtureModel:
    """A :class:`FixtureModel` with the same (or a per-channel) axis model on ``channels``."""
    if isinstance(axis, Mapping):
        axes = {c: axis.get(c, AxisModel()) for c in channels}
    else:
        axes = dict.fromkeys(channels, axis)
    return FixtureModel(axes, gauge)


def demo_model(channels: Sequence[str] = ("x", "y", "z"), unit: str = "in") -> FixtureModel:
    """A fixture like the report's Table 2-1 (X: mean +0.00008 in, σ 0.00026 in, a₁ ≈ −0.36).

    Every axis has that spread at a 0.0001 in (0.001 mm) indicator; y sits a little off
    nominal with a short warm-up drift, z has some backlash and a rare outlier, so the demo's
    verdicts, histograms and control-chart rules have something to show.
    """
    scale = 25.4 if unit == "mm" else 1.0
    resolution = 0.001 if unit == "mm" else 0.0001
    base = AxisModel(bias=0.00008 * scale, noise=0.00026 * scale, skew=-2.0)
    variants = [
        base,
        AxisModel(
            bias=0.00025 * scale,
            noise=0.00022 * scale,
            skew=-1.0,
            drift=0.0002 * scale,
            drift_tau=6.0,
        ),
        AxisModel(
            bias=-0.0001 * scale,
            noise=0.00024 * scale,
            backlash=0.0002 * scale,
            outlier_rate=0.02,
            outlier_size=5.0,
        ),
    ]
    axes = {c: variants[i % len(variants)] for i, c in enumerate(channels)}
    return FixtureModel(axes, GaugeSpec(resolution, -0.5 * scale, 0.5 * scale, unit))
