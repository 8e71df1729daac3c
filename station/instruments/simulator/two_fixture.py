"""The relative-accuracy set-up (report 2.8): two 3-D fixtures and a teach pendant."""

from __future__ import annotations

import math
import random
from dataclasses import dataclass

from station.errors import StationError
from station.instruments.simulator.models import INCH_INDICATOR, GaugeSpec, RobotModel


@dataclass(frozen=True)
class Placement:
    """One placement of the two fixtures (1-based ``number``): the teach pendant's X, Y, Z at
    the second fixture (home at the first), and the straight distance between the fixtures."""

    number: int
    pendant: tuple[float, float, float]

    @property
    def distance(self) -> float:
        """The length of the move between the fixtures: sqrt(X² + Y² + Z²)."""
        return math.sqrt(sum(c * c for c in self.pendant))

    def pendant_text(self, unit: str = "in") -> str:
        """What the pendant shows, e.g. ``X=+31.250 Y=-12.004 Z=+20.117 in``."""
        x, y, z = self.pendant
        return f"X={x:+.3f} Y={y:+.3f} Z={z:+.3f} {unit}"


class TwoFixtureModel(RobotModel):
    """The relative-accuracy set-up (§2.8): two 3-D fixtures, the robot homed at each in turn.

    At placement p the second fixture sits at the pendant coordinates P (seeded, each axis
    between ``reach_min`` and ``reach_max`` from the first, either sign). The robot returns
    from the second fixture by the inverse of P, and the first fixture's indicators read its
    error: a scale error per axis (``scale``, per unit moved) and a small rotation
    (``rotation``, radians about x, y, z: the error ω × P), both growing with the distance moved,
    plus a constant ``bias`` and repeatability ``noise`` (σ) per reading.

    The model follows the robot's state, not the readings: each placement is one rest at home
    (the first fixture's indicators show their preload, seeded per placement and axis within
    ±``preload``; the station zeroes there, from as many readings as it likes) followed by
    ``captures`` rests after returns from the second fixture (preload + error). Rest ``r`` (the
    simulator's robot state: stepped as the robot leaves and comes back, by its motion in time
    or by whoever plays the robot) belongs to placement ``r // (1 + captures) + 1``;
    :meth:`rest_of` gives the rest of a placement's home or return, :meth:`placement_of` the
    pendant display to type in. However many sets the station reads at a rest (the frames check,
    a zero of several readings), they all read that rest. The repeatability ``noise`` (σ) is
    drawn per rest; the indicator's own noise (its :class:`GaugeSpec`) per reading.

    Zeroing at home takes out the preload and nothing else: a software zero reads the home rest;
    a device zero (:meth:`zero_reference`) takes the placement's preload itself.
    """

    channels = ("x", "y", "z")

    def __init__(
        self,
        *,
        scale: tuple[float, float, float] = (2.0e-5, -1.5e-5, 1.0e-5),
        rotation: tuple[float, float, float] = (0.0, 0.0, 5.0e-6),
        bias: tuple[float, float, float] = (0.0, 0.0, 0.0),
        noise: float = 0.0002,
        reach_min: float = 10.0,
        reach_max: float = 40.0,
        captures: int = 1,
        preload: float = 0.0,
        pendant_resolution: float = 0.001,
        gauge: GaugeSpec = INCH_INDICATOR,
        seed: int = 0,
    ) -> None:
        if captures < 1:
            raise StationError(f"captures per placement must be 1 or more, not {captures}.")
        if not 0 <= reach_min <= reach_max:
            raise StationError("the fixtures' reach must satisfy 0 <= reach_min <= reach_max.")
        self.scale = tuple(float(v) for v in scale)
        self.rotation = tuple(float(v) for v in rotation)
        self.bias = tuple(float(v) for v in bias)
        self.noise = float(noise)
        self.reach = (float(reach_min), float(reach_max))
        if preload < 0:
            raise StationError("the preload must not be negative.")
        self.captures = int(captures)
        self.preload = float(preload)
        self.pendant_resolution = float(pendant_resolution)
        self._gauge = gauge
        self.seed = seed

    def gauge(self, channel: str) -> GaugeSpec:
        """The indicator on ``channel``."""
        return self._gauge

    def placement_of(self, number: int) -> Placement:
        """Placement ``number`` (1-based): where the pendant says the second fixture is."""
        if number < 1:
            raise StationError(f"placements are numbered from 1, not {number}.")
        rng = random.Random(f"placement/{self.seed}/{number}")
        low, high = self.reach
        step = self.pendant_resolution
        coordinates = []
        for _ in range(3):
            magnitude = rng.uniform(low, high) * (1.0 if rng.random() < 0.5 else -1.0)
            coordinates.append(round(round(magnitude / step) * step, 6))
        return Placement(number, (coordinates[0], coordinates[1], coordinates[2]))

    def systematic_error(self, number: int) -> tuple[float, float, float]:
        """The error per axis at placement ``number`` without noise: bias + S·P + ω × P."""
        px, py, pz = self.placement_of(number).pendant
        wx, wy, wz = self.rotation
        rotated = (wy * pz - wz * py, wz * px - wx * pz, wx * py - wy * px)
        return tuple(  # type: ignore[return-value]
            b + s * p + r
            for b, s, p, r in zip(self.bias, self.scale, (px, py, pz), rotated, strict=True)
        )

    @property
    def rests_per_placement(self) -> int:
        """The robot's rests per placement: one at home, then one per return."""
        return 1 + self.captures

    def current_placement(self, rest: int) -> int:
        """The placement (1-based) of the robot's ``rest``-th rest."""
        return max(rest, 0) // self.rests_per_placement + 1

    def at_home(self, rest: int) -> bool:
        """True when the ``rest``-th rest is at home (before the round trip)."""
        return max(rest, 0) % self.rests_per_placement == 0

    def rest_of(self, placement: int, returned: int = 0) -> int:
        """The rest at home of ``placement`` (``returned`` 0), or after its ``returned``-th
        return (1, 2, ...)."""
        if placement < 1 or not 0 <= returned <= self.captures:
            raise StationError(
                f"placement {placement} has a rest at home and {self.captures} after returns, "
                f"not return {returned}."
            )
        return (placement - 1) * self.rests_per_placement + returned

    def preload_of(self, number: int) -> tuple[float, float, float]:
        """How far the cube depresses each indicator at placement ``number``, about its mid
        travel (what zeroing at the first fixture takes out)."""
        rng = random.Random(f"preload/{self.seed}/{number}")
        return tuple(rng.uniform(-self.preload, self.preload) for _ in range(3))  # type: ignore[return-value]

    def true_value(self, channel: str, rest: int, seed: int) -> float:
        """Where the indicator rests at the ``rest``-th rest, before quantisation."""
        index = self.channels.index(channel)
        rng = random.Random(f"{seed}/{index}/{rest}")
        number = self.current_placement(rest)
        error = 0.0 if self.at_home(rest) else self.systematic_error(number)[index]
        return self.preload_of(number)[index] + error + self.noise * rng.gauss(0.0, 1.0)

    def rest_position(self, channel: str, rest: int, seed: int) -> float:
        """Where the indicator rests at the ``rest``-th rest, before quantisation."""
        return self.true_value(channel, rest, seed)

    def zero_reference(self, channel: str, rest: int, seed: int) -> float:
        """A device zero at the first fixture takes the placement's preload: the robot is at
        home, so the indicator shows no error there."""
        number = self.current_placement(rest)
        return self._gauge.show(self.preload_of(number)[self.channels.index(channel)])

    def value(self, channel: str, rest: int, seed: int) -> float:
        """The ``rest``-th rest position of ``channel`` as the gauge shows it."""
        return self._gauge.show(self.true_value(channel, rest, seed))
