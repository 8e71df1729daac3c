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

    Each placement is ``home_readings`` readings at home (the indicators show their preload,
    seeded per placement and axis within ±``preload``, plus noise) followed by ``captures``
    readings after the return (preload + error + noise); the k-th reading belongs to placement
    ``k // (home_readings + captures) + 1`` unless :attr:`placement` is set (a runner or the
    autopilot that knows which placement it is at). :meth:`placement_of` gives the pendant
    display to type in.

    Zeroing at the first fixture must take out the preload and nothing else: a software zero
    reads the home readings (so a procedure run with a software-zero protocol wants
    ``home_readings=1``: its zero step reads one set per placement); a device zero
    (:meth:`zero_reference`) takes the placement's preload itself, with no reading
    (``home_readings=0``). Either way the capture after the return shows the placement's error.
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
        home_readings: int = 0,
        preload: float = 0.0,
        pendant_resolution: float = 0.001,
        gauge: GaugeSpec = INCH_INDICATOR,
        seed: int = 0,
        lead_readings: int = 0,
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
        if home_readings < 0 or preload < 0:
            raise StationError("home readings and the preload must not be negative.")
        self.captures = int(captures)
        self.home_readings = int(home_readings)
        self.preload = float(preload)
        self.pendant_resolution = float(pendant_resolution)
        self._gauge = gauge
        self.seed = seed
        self.lead_readings = max(0, int(lead_readings))
        """Readings at home before the first placement begins (the station reads one set to
        check the gauges' frames before a session starts)."""
        self.placement: int | None = None
        """The placement the robot is at now; None: derived from the reading index."""

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
    def readings_per_placement(self) -> int:
        """Readings of each channel per placement: at home, then after the return."""
        return self.home_readings + self.captures

    def current_placement(self, k: int) -> int:
        """The placement of the k-th reading."""
        if self.placement is not None:
            return self.placement
        return max(k - self.lead_readings, 0) // self.readings_per_placement + 1

    def at_home(self, k: int) -> bool:
        """True when the k-th reading is taken at home (before the round trip)."""
        if k < self.lead_readings:
            return True
        return (k - self.lead_readings) % self.readings_per_placement < self.home_readings

    def preload_of(self, number: int) -> tuple[float, float, float]:
        """How far the cube depresses each indicator at placement ``number``, about its mid
        travel (what zeroing at the first fixture takes out)."""
        rng = random.Random(f"preload/{self.seed}/{number}")
        return tuple(rng.uniform(-self.preload, self.preload) for _ in range(3))  # type: ignore[return-value]

    def true_value(self, channel: str, k: int, seed: int) -> float:
        """The indicator's reading before quantisation and clipping."""
        index = self.channels.index(channel)
        rng = random.Random(f"{seed}/{index}/{k}")
        number = self.current_placement(k)
        error = 0.0 if self.at_home(k) else self.systematic_error(number)[index]
        return self.preload_of(number)[index] + error + self.noise * rng.gauss(0.0, 1.0)

    def zero_reference(self, channel: str, k_next: int, seed: int) -> float:
        """A device zero at the first fixture takes the placement's preload: the robot is at
        home, so the indicator shows no error there."""
        number = self.current_placement(k_next)
        return self._gauge.show(self.preload_of(number)[self.channels.index(channel)])

    def value(self, channel: str, k: int, seed: int) -> float:
        """The k-th displayed reading of ``channel``."""
        return self._gauge.show(self.true_value(channel, k, seed))
