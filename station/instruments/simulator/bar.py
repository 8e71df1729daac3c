"""The linearity set-up (report 2.9): indicators riding along a parallel bar, a linear scale."""

from __future__ import annotations

import math
import random

from station.errors import StationError
from station.instruments.simulator.models import INCH_INDICATOR, GaugeSpec, RobotModel


class BarModel(RobotModel):
    """The linearity set-up (§2.9): indicators h and v ride along a parallel bar, scale s.

    The robot shuttles A→B→A… over ``length``: each stroke is a dwell of ``dwell`` readings at
    its start, then ``points`` readings while moving (a smooth start and stop), so the k-th
    reading of every channel belongs to one instant. The indicators read, at position s
    (u = s / length):

    * h: the bar's bow in the horizontal plane, a parabola of sagitta ``bow`` (0 at the ends),
    * v: the bar's sag under its own weight, the simply supported beam's shape of sagitta
      ``sag``,
    * both: the robot path's wobble, ``wobble`` (h) / ``wobble_v`` (v) × sin(2π s / ``period``),
      the misalignment of the bar to the robot's straight line (``tilt_h``, ``tilt_v`` per unit
      of travel; a straightness fit removes it), a random offset per stroke (σ
      ``stroke_jitter``: the path does not repeat exactly) and reading noise (σ ``noise``).

    The scale s reads the position with its own resolution and noise ``scale_noise``. The
    robot stands still at A while the station zeroes (the simulator's rest 0) and shuttles from
    rest 1 on (:meth:`reading`).
    """

    channels = ("h", "v", "s")

    def __init__(
        self,
        *,
        length: float = 20.0,
        points: int = 400,
        dwell: int = 20,
        bow: float = 0.0012,
        sag: float = 0.0006,
        wobble: float = 0.0004,
        wobble_v: float = 0.0002,
        period: float = 5.0,
        tilt_h: float = 5.0e-5,
        tilt_v: float = -3.0e-5,
        stroke_jitter: float = 0.00005,
        noise: float = 0.00005,
        scale_noise: float = 0.0,
        indicator: GaugeSpec = INCH_INDICATOR,
        scale: GaugeSpec | None = None,
    ) -> None:
        if points < 2 or dwell < 0:
            raise StationError("a stroke needs at least 2 points and a dwell of 0 or more.")
        if not length > 0 or not period > 0:
            raise StationError("the bar's length and the wobble's period must be positive.")
        self.length = float(length)
        self.points = int(points)
        self.dwell = int(dwell)
        self.bow, self.sag = float(bow), float(sag)
        self.wobble, self.wobble_v, self.period = float(wobble), float(wobble_v), float(period)
        self.tilt_h, self.tilt_v = float(tilt_h), float(tilt_v)
        self.stroke_jitter, self.noise, self.scale_noise = (
            float(stroke_jitter),
            float(noise),
            float(scale_noise),
        )
        self._indicator = indicator
        self._scale = scale or GaugeSpec(indicator.resolution, -1.0, self.length + 1.0, "in")

    @property
    def readings_per_stroke(self) -> int:
        """Readings of each channel per stroke (dwell and motion)."""
        return self.dwell + self.points

    def gauge(self, channel: str) -> GaugeSpec:
        """The indicator on h and v, the linear scale on s."""
        return self._scale if channel == "s" else self._indicator

    def stroke_of(self, k: int) -> tuple[int, float]:
        """The 1-based stroke of the k-th reading and the true position s along the bar."""
        stroke, i = divmod(k, self.readings_per_stroke)
        t = 0.0 if i < self.dwell else (i - self.dwell + 1) / self.points
        u = (1.0 - math.cos(math.pi * t)) / 2.0  # a smooth start and stop
        fraction = u if stroke % 2 == 0 else 1.0 - u
        return stroke + 1, fraction * self.length

    def profile(self, channel: str, s: float) -> float:
        """The systematic reading of h or v at position s (bar shape, wobble, tilt), no noise."""
        u = s / self.length
        wave = math.sin(2.0 * math.pi * s / self.period)
        if channel == "h":
            return 4.0 * self.bow * u * (1.0 - u) + self.wobble * wave + self.tilt_h * s
        if channel == "v":
            beam = 16.0 / 5.0 * (u - 2.0 * u**3 + u**4)
            return self.sag * beam + self.wobble_v * wave + self.tilt_v * s
        raise StationError(f"the bar model has no indicator {channel!r}.")

    def true_value(self, channel: str, k: int, seed: int) -> float:
        """The reading before quantisation and clipping."""
        stroke, s = self.stroke_of(k)
        index = self.channels.index(channel)
        rng = random.Random(f"{seed}/{index}/{k}")
        if channel == "s":
            return s + self.scale_noise * rng.gauss(0.0, 1.0)
        jitter = random.Random(f"{seed}/{index}/stroke/{stroke}").gauss(0.0, 1.0)
        return (
            self.profile(channel, s)
            + self.stroke_jitter * jitter
            + self.noise * rng.gauss(0.0, 1.0)
        )

    moves_per_set = True

    def reading(self, channel: str, rest: int, k: int, seed: int) -> float:
        """Rest 0: the robot stands still at end A (the zero steps), its indicators showing
        the stroke's start plus their own noise. From rest 1 it shuttles A→B→A…, one point per
        set sent: the k-th reading of the rest (``k`` counted from its start) is the k-th
        point."""
        if rest <= 0:
            return self.shown(channel, self.true_value(channel, 0, seed), k, seed)
        return self.value(channel, k, seed)

    def value(self, channel: str, k: int, seed: int) -> float:
        """The k-th displayed reading of ``channel``."""
        return self.gauge(channel).show(self.true_value(channel, k, seed))

    def stream(self, strokes: int, seed: int = 0) -> dict[str, list[float]]:
        """The displayed readings of ``strokes`` whole strokes plus a final dwell, per channel
        (what a capture would record from the server, without the server)."""
        count = strokes * self.readings_per_stroke + self.dwell
        return {c: [self.value(c, k, seed) for k in range(count)] for c in self.channels}
