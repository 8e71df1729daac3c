"""A simulated gauge bench for the gauge check (Type-1 study): one indicator over a surface plate,
a gauge block of known size re-seated under it for every reading.

The model follows the bench's state, not the readings: the first rest (the simulator's robot
state 0) is the spindle on the surface plate, where the station zeroes (a device zero sets the
indicator's zero on the plate, :meth:`GaugeBenchModel.zero_reference`; a software zero reads the
plate as many times as it likes); every later rest is the block re-seated under the spindle:
its size ``reference`` plus the indicator's ``bias`` and its repeatability ``noise`` (σ, drawn
per seating), at the indicator's resolution. A gauge with a bias fails Cgk; a noisy one fails
Cg.
"""

from __future__ import annotations

import random

from station.errors import StationError
from station.instruments.simulator import GaugeSpec, RobotModel

#: A 0.0001 in indicator with a 1 in travel.
BENCH_INDICATOR = GaugeSpec(0.0001, -0.5, 1.0, "in")


class GaugeBenchModel(RobotModel):
    """One indicator (channel ``x``) reading a gauge block of size ``reference`` (see the
    module)."""

    channels = ("x",)

    def __init__(
        self,
        reference: float = 0.1,
        *,
        bias: float = 0.0,
        noise: float = 0.00003,
        gauge: GaugeSpec = BENCH_INDICATOR,
    ) -> None:
        if noise < 0:
            raise StationError(f"the gauge's noise must not be negative, not {noise}.")
        if not gauge.low <= reference <= gauge.high:
            raise StationError(
                f"the reference {reference:g} is outside the indicator's range "
                f"{gauge.low:g} to {gauge.high:g}."
            )
        self.reference, self.bias, self.noise = float(reference), float(bias), float(noise)
        self._gauge = gauge

    def gauge(self, channel: str) -> GaugeSpec:
        """The indicator."""
        return self._gauge

    def rest_position(self, channel: str, rest: int, seed: int) -> float:
        """The plate at rest 0, then the block as seated the ``rest``-th time."""
        if rest <= 0:
            return 0.0
        noise = random.Random(f"{seed}/bench/{rest}").gauss(0.0, 1.0)
        return self.reference + self.bias + self.noise * noise

    def value(self, channel: str, rest: int, seed: int) -> float:
        """The ``rest``-th rest as the indicator shows it: the plate, then the block."""
        return self._gauge.show(self.rest_position(channel, rest, seed))

    def zero_reference(self, channel: str, rest: int, seed: int) -> float:
        """Zeroing on the surface plate: the indicator's zero is the plate."""
        return 0.0
