"""A simulated gauge bench for the gauge studies: one indicator over a surface plate, a gauge
block of known size re-seated under it for every reading (the gauge check, a Type-1 study),
or several blocks in turn, each re-seated for every reading (the linearity and bias study).

The model follows the bench's state, not the readings: the first rest (the simulator's robot
state 0) is the spindle on the surface plate, where the station zeroes (a device zero sets the
indicator's zero on the plate, :meth:`GaugeBenchModel.zero_reference`; a software zero reads the
plate as many times as it likes); every later rest is a block re-seated under the spindle. The
indicator shows a block of size x as

    x + bias + slope · x + noise

at its resolution: ``bias`` is its error at zero size, ``slope`` its linearity error (the bias
grows by ``slope`` per unit of size, as an indicator whose scale is a little long or short
does), ``noise`` its repeatability (σ, drawn per seating). A gauge with a bias fails Cgk, a
noisy one Cg; a slope shows in the linearity study.

With several ``references`` the blocks come in turn, ``readings`` seatings each: seating r (1,
2, ...) is of block ``(r − 1) // readings`` (the last one after that). :meth:`rest_of` names the
rest of a block's seating, so a session can put the bench where its steps say.

:class:`GageRRBenchModel` is the same bench for a Gage R&R: the blocks are the parts, seated in
whatever order the operator is given, by appraisers who each read with an offset of their own.
"""

from __future__ import annotations

import random
from collections.abc import Mapping, Sequence

from station.errors import StationError
from station.instruments.simulator import GaugeSpec, RobotModel

#: A 0.0001 in indicator with a 1 in travel.
BENCH_INDICATOR = GaugeSpec(0.0001, -0.5, 1.0, "in")


class GaugeBenchModel(RobotModel):
    """One indicator (channel ``x``) reading gauge blocks of the ``references`` sizes (see the
    module)."""

    channels = ("x",)

    def __init__(
        self,
        reference: float | Sequence[float] = 0.1,
        *,
        bias: float = 0.0,
        slope: float = 0.0,
        noise: float = 0.00003,
        readings: int = 12,
        gauge: GaugeSpec = BENCH_INDICATOR,
    ) -> None:
        references = (
            (float(reference),)
            if isinstance(reference, int | float)
            else tuple(float(r) for r in reference)
        )
        if not references:
            raise StationError("the gauge bench needs at least one gauge block.")
        if noise < 0:
            raise StationError(f"the gauge's noise must not be negative, not {noise}.")
        if readings < 1:
            raise StationError(f"each block is read once or more, not {readings} times.")
        for size in references:
            if not gauge.low <= size <= gauge.high:
                raise StationError(
                    f"the reference {size:g} is outside the indicator's range "
                    f"{gauge.low:g} to {gauge.high:g}."
                )
        self.references = references
        self.bias, self.slope, self.noise = float(bias), float(slope), float(noise)
        self.readings = int(readings)
        self._gauge = gauge

    @property
    def reference(self) -> float:
        """The first block's size (the gauge check's one block)."""
        return self.references[0]

    @property
    def cycles(self) -> int | None:
        """Seatings per block before the next (None with one block: every seating is it)."""
        return self.readings if len(self.references) > 1 else None

    def gauge(self, channel: str) -> GaugeSpec:
        """The indicator."""
        return self._gauge

    def block_of(self, rest: int) -> float:
        """The size of the block seated at the ``rest``-th rest (1, 2, ...)."""
        index = min((max(rest, 1) - 1) // self.readings, len(self.references) - 1)
        return self.references[index] if len(self.references) > 1 else self.references[0]

    def rest_of(self, block: int, returned: int = 0) -> int:
        """The rest of block ``block``'s ``returned``-th seating (1, 2, ...); the plate (0) for
        ``returned`` 0, as between two blocks."""
        if returned <= 0:
            return 0
        if len(self.references) == 1:
            return returned
        if not 1 <= block <= len(self.references) or returned > self.readings:
            raise StationError(
                f"the bench has {len(self.references)} blocks of {self.readings} seatings, "
                f"not seating {returned} of block {block}."
            )
        return (block - 1) * self.readings + returned

    def rest_position(self, channel: str, rest: int, seed: int) -> float:
        """The plate at rest 0, then the block as seated the ``rest``-th time."""
        if rest <= 0:
            return 0.0
        size = self.block_of(rest)
        noise = random.Random(f"{seed}/bench/{rest}").gauss(0.0, 1.0)
        return size + self.bias + self.slope * size + self.noise * noise

    def value(self, channel: str, rest: int, seed: int) -> float:
        """The ``rest``-th rest as the indicator shows it: the plate, then the block."""
        return self._gauge.show(self.rest_position(channel, rest, seed))

    def zero_reference(self, channel: str, rest: int, seed: int) -> float:
        """Zeroing on the surface plate: the indicator's zero is the plate."""
        return 0.0


class GageRRBenchModel(GaugeBenchModel):
    """The gauge bench for a Gage R&R: the ``references`` are the parts' sizes (part 1, 2 ...),
    and each of the ``appraisers`` (by name, an offset each: an appraiser who reads high or
    seats a part a little off) reads part p as

        size_p + offset_appraiser + bias + slope · size_p + noise

    with a fresh noise draw per seating. Who seats which part is the operator's business (the
    procedure's random order): :meth:`rest_of_part` names the rest of a seating, so a session
    puts the bench where its current step says (the plate at rest 0, as for the other studies).
    """

    def __init__(
        self,
        references: Sequence[float],
        appraisers: Mapping[str, float],
        *,
        bias: float = 0.0,
        slope: float = 0.0,
        noise: float = 0.00003,
        gauge: GaugeSpec = BENCH_INDICATOR,
    ) -> None:
        super().__init__(references, bias=bias, slope=slope, noise=noise, readings=1, gauge=gauge)
        if not appraisers:
            raise StationError("the Gage R&R bench needs at least one appraiser.")
        self.appraisers = dict(appraisers)
        self._names = tuple(self.appraisers)

    @property
    def cycles(self) -> None:
        """Every seating is a part's, in the operator's order (no blocks of seatings)."""
        return None

    def rest_of_part(self, part: int, appraiser: str, seating: int) -> int:
        """The rest of ``appraiser``'s seating of ``part`` (1, 2 ...), the ``seating``-th of the
        session (a new one each time: its noise is its own)."""
        parts = len(self.references)
        if not 1 <= part <= parts:
            raise StationError(f"the bench has parts 1 to {parts}, not part {part}.")
        if appraiser not in self.appraisers:
            raise StationError(
                f"the bench knows appraisers {', '.join(self._names)}, not {appraiser!r}."
            )
        index = self._names.index(appraiser)
        return 1 + (max(seating, 0) * len(self._names) + index) * parts + (part - 1)

    def seated(self, rest: int) -> tuple[int, str]:
        """The part and the appraiser of the ``rest``-th rest (1, 2 ...)."""
        parts = len(self.references)
        part, block = (rest - 1) % parts + 1, (rest - 1) // parts
        return part, self._names[block % len(self._names)]

    def rest_position(self, channel: str, rest: int, seed: int) -> float:
        """The plate at rest 0, then the part as its appraiser seated and read it."""
        if rest <= 0:
            return 0.0
        part, appraiser = self.seated(rest)
        size = self.references[part - 1]
        noise = random.Random(f"{seed}/grr-bench/{rest}").gauss(0.0, 1.0)
        offset = self.appraisers[appraiser]
        return size + offset + self.bias + self.slope * size + self.noise * noise
