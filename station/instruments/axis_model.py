"""A simulated axis under an ISO 230-2 positioning test: a linear scale (channel ``s``) reads
where the axis stops at each target of the standard test cycle.

The robot's program runs the cycle: in each run it stops at targets 1 to m moving up, goes past
the last, and stops at m to 1 moving down (the order :mod:`station.methods.positioning` reads
the stops in). The first rest (the simulator's robot state 0) is the reference position, where
the station zeroes the scale; rest r ≥ 1 is the (r − 1)-th stop of the cycle, run after run.
The axis stops at

    P + slope · P − direction · backlash / 2 + noise

for a target P: ``slope`` is its systematic positioning error per unit of travel (a pitch or
scale error: the error grows along the axis), ``backlash`` the lost motion at a reversal (the
axis stops short of the target in the direction it moves, so the reversal B_i = x̄↑ − x̄↓ is
−``backlash`` at every target), ``noise`` its repeatability (σ, drawn per stop).
"""

from __future__ import annotations

import random
from collections.abc import Sequence

from station.errors import StationError
from station.instruments.simulator import GaugeSpec, RobotModel

SCALE_RESOLUTION = 0.001
"""The scale's step (mm): a 1 µm linear scale."""


class AxisPositioningModel(RobotModel):
    """One axis stopping at ``targets`` in the standard test cycle (see the module)."""

    channels = ("s",)

    def __init__(
        self,
        targets: Sequence[float],
        *,
        slope: float = 0.0,
        backlash: float = 0.0,
        noise: float = 0.002,
        gauge: GaugeSpec | None = None,
    ) -> None:
        self.targets = tuple(float(t) for t in targets)
        if not self.targets:
            raise StationError("the simulated axis needs at least one target.")
        if any(b <= a for a, b in zip(self.targets, self.targets[1:], strict=False)):
            raise StationError("the simulated axis's targets must rise along the axis.")
        if noise < 0 or backlash < 0:
            raise StationError("the axis's noise and backlash must not be negative.")
        self.slope, self.backlash, self.noise = float(slope), float(backlash), float(noise)
        span = max(abs(t) for t in self.targets) + 10.0
        self._gauge = gauge or GaugeSpec(SCALE_RESOLUTION, -span, span, "mm")

    @property
    def stops_per_run(self) -> int:
        """Stops in one run of the cycle: every target up, then down."""
        return 2 * len(self.targets)

    @property
    def cycles(self) -> int:
        """Stops per run: a session's run (a placement of its repeated block) takes so many."""
        return self.stops_per_run

    def rest_of(self, run: int, stop: int = 0) -> int:
        """The rest of run ``run``'s ``stop``-th stop (1, 2, ...); the reference position (0)
        for ``stop`` 0, as before the first run, so a session can put the axis where its
        steps say."""
        if stop <= 0:
            return 0
        if run < 1 or stop > self.stops_per_run:
            raise StationError(
                f"a run of the test cycle has {self.stops_per_run} stops, not stop {stop} of "
                f"run {run}."
            )
        return (run - 1) * self.stops_per_run + stop

    def stop_of(self, rest: int) -> tuple[float, bool]:
        """The target of the ``rest``-th rest (1, 2, ...) and whether the axis came to it
        moving up."""
        k = (max(rest, 1) - 1) % self.stops_per_run
        count = len(self.targets)
        if k < count:
            return self.targets[k], True
        return self.targets[2 * count - 1 - k], False

    def error(self, target: float, up: bool) -> float:
        """Where the axis stops at ``target``, less the target, without the noise."""
        return self.slope * target - (1.0 if up else -1.0) * self.backlash / 2.0

    def gauge(self, channel: str) -> GaugeSpec:
        """The scale."""
        return self._gauge

    def rest_position(self, channel: str, rest: int, seed: int) -> float:
        """The reference position (0) at rest 0, then where the axis stops at each stop."""
        if rest <= 0:
            return 0.0
        target, up = self.stop_of(rest)
        noise = random.Random(f"{seed}/axis/{rest}").gauss(0.0, 1.0)
        return target + self.error(target, up) + self.noise * noise

    def value(self, channel: str, rest: int, seed: int) -> float:
        """The ``rest``-th rest as the scale shows it."""
        return self._gauge.show(self.rest_position(channel, rest, seed))

    def zero_reference(self, channel: str, rest: int, seed: int) -> float:
        """Zeroing at the reference position: the scale's zero is the reference."""
        return 0.0
