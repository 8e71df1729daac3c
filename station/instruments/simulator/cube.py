"""The ISO 9283 pose test (reference/standards.md §1.5): one 3-D fixture taken to the poses of
the test cube in turn, the robot running the standard's cycle P1 → P5 → P4 → P3 → P2 → P1."""

from __future__ import annotations

import random
from collections.abc import Sequence

from station.errors import StationError
from station.instruments.simulator.models import INCH_INDICATOR, GaugeSpec
from station.instruments.simulator.two_fixture import Placement, TwoFixtureModel

Point = tuple[float, float, float]

CUBE_CORNERS: tuple[Point, ...] = (
    (0.0, 0.0, 0.0),
    (1.0, 1.0, 1.0),
    (-1.0, -1.0, 1.0),
    (-1.0, -1.0, -1.0),
    (1.0, 1.0, -1.0),
)
"""P1 at the cube's centre, P2 to P5 towards the corners of its diagonal plane x = y (in
half-edges from the centre): the poses lie on the plane's diagonals."""
CORNER_SHARE = 0.1
"""How far from its corner a pose lies, as a share of the diagonal (the standard: 10 %)."""
POSE_BIAS: tuple[Point, ...] = (
    (0.0003, -0.0002, 0.0001),
    (-0.0004, 0.0003, 0.0005),
    (0.0006, 0.0001, -0.0003),
    (-0.0002, -0.0005, 0.0002),
    (0.0001, 0.0004, -0.0006),
)
"""Each pose's own mean error after the cycle (in): where the robot comes back to, against
where it was taught."""
POSE_NOISE: tuple[float, ...] = (0.0002, 0.00025, 0.0003, 0.00035, 0.0002)
"""Each pose's own repeatability σ per axis (in): the far corners scatter more."""


class CubePosesModel(TwoFixtureModel):
    """The pose test: at placement k the fixture sits at pose P_k of the test cube (a cube of
    ``edge`` about ``centre``, in the robot's frame: the teach pendant's X, Y, Z of the pose);
    the robot is taught there and the indicators zeroed (the zero rest reads the pose exactly:
    it is the command pose), then each of ``captures`` returns after the standard's cycle reads
    the pose's bias plus its noise (σ per axis). Poses past the fifth take the biases again.

    A :class:`TwoFixtureModel` whose placements are the cube's poses: the rests, the zero and
    the pendant display are its own.
    """

    def __init__(
        self,
        *,
        centre: Point = (40.0, 0.0, 30.0),
        edge: float = 20.0,
        biases: Sequence[Point] = POSE_BIAS,
        noises: Sequence[float] = POSE_NOISE,
        captures: int = 30,
        preload: float = 0.0,
        gauge: GaugeSpec = INCH_INDICATOR,
        seed: int = 0,
    ) -> None:
        if not biases or len(biases) != len(noises):
            raise StationError("give one bias and one noise per pose of the cube.")
        if not edge > 0:
            raise StationError("the test cube's edge must be greater than 0.")
        super().__init__(captures=captures, preload=preload, gauge=gauge, seed=seed)
        self.centre = tuple(float(v) for v in centre)
        self.edge = float(edge)
        self.biases = tuple(tuple(float(v) for v in bias) for bias in biases)
        self.noises = tuple(float(v) for v in noises)

    @property
    def cycles(self) -> int:
        """The returns per pose (what a demo that plays the robot steps through)."""
        return self.captures

    def _index(self, number: int) -> int:
        if number < 1:
            raise StationError(f"poses are numbered from 1, not {number}.")
        return (number - 1) % len(self.biases)

    def placement_of(self, number: int) -> Placement:
        """Pose ``number`` (P1 ...): its pendant X, Y, Z, at the pendant's resolution."""
        self._index(number)  # a pose number from 1
        corner = CUBE_CORNERS[(number - 1) % len(CUBE_CORNERS)]
        # A point 10 % of the diagonal from a corner is 80 % of the way out from the centre.
        reach = (1.0 - 2.0 * CORNER_SHARE) * self.edge / 2.0
        step = self.pendant_resolution
        coordinates = tuple(
            round(round((c + reach * k) / step) * step, 6)
            for c, k in zip(self.centre, corner, strict=True)
        )
        return Placement(number, (coordinates[0], coordinates[1], coordinates[2]))

    def systematic_error(self, number: int) -> tuple[float, float, float]:
        """Pose ``number``'s bias per axis."""
        x, y, z = self.biases[self._index(number)]
        return x, y, z

    def true_value(self, channel: str, rest: int, seed: int) -> float:
        """Where the indicator rests: at the zero rest the taught pose itself (only the
        fixture's preload), after a cycle the pose's bias plus its noise."""
        index = self.channels.index(channel)
        number = self.current_placement(rest)
        preload = self.preload_of(number)[index]
        if self.at_home(rest):
            return preload
        rng = random.Random(f"{seed}/{index}/{rest}")
        noise = self.noises[self._index(number)]
        return preload + self.systematic_error(number)[index] + noise * rng.gauss(0.0, 1.0)
