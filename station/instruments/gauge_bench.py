"""A simulated gauge bench for the gauge check (Type-1 study): one indicator over a surface plate,
a gauge block of known size re-seated under it for every reading.

Zeroing reads the plate (the indicator's zero: 0, whatever it read before); each reading is the
block's size ``reference`` plus the indicator's ``bias`` and its repeatability ``noise`` (σ),
at the indicator's resolution. A gauge with a bias fails Cgk; a noisy one fails Cg.
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

    def value(self, channel: str, k: int, seed: int) -> float:
        """The k-th reading of the block."""
        noise = random.Random(f"{seed}/bench/{k}").gauss(0.0, 1.0)
        return self._gauge.show(self.reference + self.bias + self.noise * noise)

    def zero_reference(self, channel: str, k_next: int, seed: int) -> float:
        """Zeroing on the surface plate: the indicator's zero is the plate."""
        return 0.0
