"""A simulated gauge bench for the gauge check (Type-1 study): one indicator over a surface plate,
a gauge block of known size re-seated under it for every reading.

A device zero sets the indicator's zero on the plate (:meth:`GaugeBenchModel.zero_reference`);
a software zero reads one set on the plate, so a run zeroed in software wants
``plate_readings=1``: its first reading is the plate (0 plus noise). Every later reading is the
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
        plate_readings: int = 0,
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
        if plate_readings < 0:
            raise StationError("the readings on the plate must not be negative.")
        self.plate_readings = int(plate_readings)

    def gauge(self, channel: str) -> GaugeSpec:
        """The indicator."""
        return self._gauge

    def value(self, channel: str, k: int, seed: int) -> float:
        """The k-th reading: the plate for the first ``plate_readings``, then the block."""
        noise = random.Random(f"{seed}/bench/{k}").gauss(0.0, 1.0)
        size = 0.0 if k < self.plate_readings else self.reference + self.bias
        return self._gauge.show(size + self.noise * noise)

    def zero_reference(self, channel: str, k_next: int, seed: int) -> float:
        """Zeroing on the surface plate: the indicator's zero is the plate."""
        return 0.0
