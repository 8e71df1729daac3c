"""The simulated robot's own motion: it leaves the fixture and comes back every period.

:class:`CycleMotion` is a pure function of time: what an indicator shows ``t`` seconds after the
simulator started, given where the robot comes to rest on each return (the fixture model's
bias, noise, drift and backlash for that cycle). One period is, in order:

* **at rest** (``dwell``): the indicator shows the cycle's rest position, still;
* **departing** (``depart``): the cube leaves the fixture and the spindle runs out to its free
  travel (a smooth ramp);
* **away** (``away``): the indicator sits at its free travel (``free_travel``, e.g. −3/8 in: the
  cube deflected it by that much at the fixture);
* **approaching** (``approach``): the cube comes back and pushes the spindle in, a little past
  the next rest position (``overshoot``);
* **settling**: a damped swing about the next rest position, ending on it.

So cycle ``c``'s rest position is shown from ``c × period`` to ``c × period + dwell``; the
robot arrives at cycle ``c + 1``'s position at the end of cycle ``c``'s period. A *hunting* axis
(``hunt``: a servo that does not settle) swings about its rest position by ± the amplitude
from its return (settling included) to its departure on every ``hunt_every``-th return, so
the station must report that return rather than record it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Literal

from station.errors import StationError

Stage = Literal["at rest", "departing", "away", "approaching", "settling"]

DEFAULT_FRACTIONS = (0.35, 0.1, 0.25, 0.15)
"""Parts of a period at rest, departing, away and approaching; settling takes the rest (0.15)."""

FREE_TRAVEL_INCHES = -0.375
"""What an indicator shows with the cube away: the procedure deflects each by about 3/8 in."""


@dataclass(frozen=True)
class CycleMotion:
    """The robot's round trip from the fixture and back, every ``period`` seconds.

    ``free_travel`` and ``overshoot`` are in the gauge's unit; ``hunt`` is a per-channel
    amplitude (0 = the axis settles). Fractions of the period: ``dwell`` at rest, ``depart``,
    ``away``, ``approach``; the remainder is the settling swing.
    """

    period: float
    free_travel: float | Mapping[str, float]
    overshoot: float
    dwell: float = DEFAULT_FRACTIONS[0]
    depart: float = DEFAULT_FRACTIONS[1]
    away: float = DEFAULT_FRACTIONS[2]
    approach: float = DEFAULT_FRACTIONS[3]
    hunt: Mapping[str, float] = field(default_factory=dict)
    hunt_every: int = 1
    hunt_period: float = 0.037
    """Seconds per swing of a hunting axis."""

    def __post_init__(self) -> None:
        if not self.period > 0 or not math.isfinite(self.period):
            raise StationError(
                f"The cycle period must be a positive number of seconds, not {self.period}."
            )
        parts = (self.dwell, self.depart, self.away, self.approach)
        if any(not part > 0 for part in parts) or sum(parts) >= 1.0:
            raise StationError(
                "The parts of a cycle (at rest, departing, away, approaching) must each be "
                "more than 0 and leave time to settle (sum below 1)."
            )
        if self.hunt_every < 1:
            raise StationError(f"hunt every must be 1 or more returns, not {self.hunt_every}.")

    @property
    def settle(self) -> float:
        """The part of the period spent settling after the approach."""
        return 1.0 - self.dwell - self.depart - self.away - self.approach

    def stage(self, t: float) -> tuple[int, Stage, float]:
        """The cycle at time ``t`` (s since the start), its stage and how far into the stage
        (0..1)."""
        cycle, within = divmod(max(t, 0.0) / self.period, 1.0)
        edges: tuple[tuple[Stage, float], ...] = (
            ("at rest", self.dwell),
            ("departing", self.depart),
            ("away", self.away),
            ("approaching", self.approach),
            ("settling", self.settle),
        )
        start = 0.0
        for name, length in edges:
            if within < start + length or name == "settling":
                return int(cycle), name, min(1.0, (within - start) / length)
            start += length
        raise AssertionError("unreachable")

    def rest_window(self, cycle: int) -> tuple[float, float]:
        """When cycle ``cycle``'s rest position is shown, in seconds since the start."""
        start = cycle * self.period
        return start, start + self.dwell * self.period

    def free(self, channel: str) -> float:
        """What ``channel``'s indicator shows while the robot is away."""
        if isinstance(self.free_travel, Mapping):
            return float(self.free_travel.get(channel, 0.0))
        return float(self.free_travel)

    def hunts(self, channel: str, cycle: int) -> bool:
        """True when ``channel`` hunts (does not settle) while at rest in ``cycle``."""
        return bool(self.hunt.get(channel)) and cycle > 0 and cycle % self.hunt_every == 0

    def position(self, channel: str, t: float, rest: float, next_rest: float) -> float:
        """What ``channel``'s indicator shows at ``t`` (before quantisation): ``rest`` is this
        cycle's rest position, ``next_rest`` the next cycle's (the one it approaches)."""
        cycle, stage, u = self.stage(t)
        smooth = (1.0 - math.cos(math.pi * u)) / 2.0
        free = self.free(channel)
        if stage == "at rest":
            return rest + self._hunting(channel, cycle, t)
        if stage == "departing":
            return rest + (free - rest) * smooth
        if stage == "away":
            return free
        target = next_rest + math.copysign(self.overshoot, next_rest - free)
        if stage == "approaching":
            return free + (target - free) * smooth
        # A damped swing from the overshoot, ending exactly on the rest position (a hunting
        # axis never gets there: it hunts from the moment it is back).
        swing = math.exp(-5.0 * u) * math.cos(3.0 * math.pi * u) * (1.0 - u)
        return next_rest + (target - next_rest) * swing + self._hunting(channel, cycle + 1, t)

    def _hunting(self, channel: str, cycle: int, t: float) -> float:
        """The hunting swing of ``channel`` at ``t`` (0 unless it hunts in ``cycle``)."""
        if not self.hunts(channel, cycle):
            return 0.0
        return self.hunt[channel] * math.sin(2.0 * math.pi * t / self.hunt_period)


def default_free_travel(unit: str) -> float:
    """The free travel in ``unit``: −3/8 in, or −9.525 mm."""
    return FREE_TRAVEL_INCHES * (25.4 if unit == "mm" else 1.0)


__all__ = ["CycleMotion", "DEFAULT_FRACTIONS", "Stage", "default_free_travel"]
