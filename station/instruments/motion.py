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

With ``settling`` (:class:`Settling`), the arrival is a second-order one instead: the approach
ends on the rest position and every axis then rings about it, a damped oscillation of one period
and decay for all axes, each with its own first swing past the rest position, through the
settling stage and on into the rest (where it has died down). Its overshoot and stabilisation
time are known in closed form (:meth:`Settling.overshoot_distance`,
:meth:`CycleMotion.stabilisation_time`), so a test can recover them from the station's trace.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Literal

from station.errors import StationError

Stage = Literal["at rest", "departing", "away", "approaching", "settling"]

DEFAULT_FRACTIONS = (0.35, 0.1, 0.25, 0.15)
"""Parts of a period at rest, departing, away and approaching; settling takes the rest (0.15)."""

FREE_TRAVEL_INCHES = -0.375
"""What an indicator shows with the cube away: the procedure deflects each by about 3/8 in."""


@dataclass(frozen=True)
class Settling:
    """A second-order arrival: past the rest position by ``overshoot`` (per channel, in the
    gauge's unit) at its first swing, then ringing with a damped ``period`` (s) under an
    envelope that decays as exp(−t/``decay``). Every axis rings in step, so the distance from
    the rest position rings as one axis of amplitude ‖overshoot‖ does."""

    overshoot: Mapping[str, float]
    period: float = 0.1
    decay: float = 0.05

    def __post_init__(self) -> None:
        for name in ("period", "decay"):
            value = getattr(self, name)
            if not (value > 0 and math.isfinite(value)):
                raise StationError(f"The settling {name} must be a number of seconds over 0.")
        if any(not math.isfinite(v) or v < 0 for v in self.overshoot.values()):
            raise StationError("The settling overshoot must be 0 or more on every axis.")

    @property
    def _omega(self) -> float:
        return 2.0 * math.pi / self.period

    @property
    def first_peak(self) -> float:
        """Seconds from the end of the approach to the first swing's peak: where
        d/dt (exp(−t/T)·sin ωt) = 0, tan ωt = ωT."""
        return math.atan(self._omega * self.decay) / self._omega

    def shape(self, tau: float) -> float:
        """The ringing at ``tau`` seconds after the approach, 1 at the first peak."""
        if tau < 0:
            return 0.0
        peak = math.exp(-self.first_peak / self.decay) * math.sin(self._omega * self.first_peak)
        return math.exp(-tau / self.decay) * math.sin(self._omega * tau) / peak

    def amplitude(self, channel: str) -> float:
        """The first swing past the rest position of ``channel``."""
        return float(self.overshoot.get(channel, 0.0))

    def overshoot_distance(self, channels: Sequence[str]) -> float:
        """The overshoot as a distance: the first swing of every axis at once."""
        return math.sqrt(sum(self.amplitude(c) ** 2 for c in channels))

    def last_outside(self, radius: float, channels: Sequence[str]) -> float:
        """Seconds after the approach when the ringing distance last leaves ``radius`` (0
        when it never reaches it): the last crossing, found from the envelope down, to 1 µs."""
        amplitude = self.overshoot_distance(channels)
        peak = math.exp(-self.first_peak / self.decay) * math.sin(self._omega * self.first_peak)
        scale = amplitude / peak
        if amplitude <= radius:
            return 0.0
        # After the envelope falls below the radius nothing is outside: search the half-swings
        # before that moment, latest first, for one whose peak is outside.
        horizon = self.decay * math.log(scale / radius)
        half = self.period / 2
        k = math.floor((horizon - self.first_peak) / half)
        while k >= 0:
            top = self.first_peak + k * half
            if abs(scale * math.exp(-top / self.decay) * math.sin(self._omega * top)) > radius:
                low, high = top, top + half
                for _ in range(60):
                    middle = (low + high) / 2
                    value = abs(
                        scale * math.exp(-middle / self.decay) * math.sin(self._omega * middle)
                    )
                    if value > radius:
                        low = middle
                    else:
                        high = middle
                return high
            k -= 1
        return 0.0


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
    settling: Settling | None = None
    """A second-order arrival (see the module); None: the overshoot and its damped swing."""

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
        if self.settling is not None:
            return self._second_order(channel, t, cycle, stage, smooth, rest, next_rest)
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

    def _second_order(
        self,
        channel: str,
        t: float,
        cycle: int,
        stage: Stage,
        smooth: float,
        rest: float,
        next_rest: float,
    ) -> float:
        """The position with a second-order arrival: the approach ends on the rest position,
        the ringing goes on from there through the settling and the next rest."""
        settling = self.settling
        assert settling is not None
        free = self.free(channel)
        within = t - cycle * self.period
        approach_end = (1.0 - self.settle) * self.period
        if stage == "approaching":
            return free + (next_rest - free) * smooth
        if stage == "away":
            return free
        if stage == "settling":
            ringing, towards = within - approach_end, next_rest - free
            target = next_rest
        else:
            # Rest and departure ring on from the approach that ended the period before.
            ringing, towards = within + self.period - approach_end, rest - free
            target = rest
        # The first period starts at rest: no approach came before it to ring from.
        first_rest = cycle == 0 and stage != "settling"
        amplitude = 0.0 if first_rest else settling.amplitude(channel)
        offset = math.copysign(amplitude, towards) * settling.shape(ringing)
        if stage == "departing":
            return target + offset + (free - target) * smooth
        return target + offset + self._hunting(channel, cycle + (stage == "settling"), t)

    def entry_lead(self, radius: float, travel: float) -> float:
        """Seconds before the end of an approach of ``travel`` (the distance from the free
        travel to the rest position) at which it comes within ``radius`` of the rest position:
        the cosine ramp leaves (1 − smooth)·travel to go."""
        if radius >= travel:
            return self.approach * self.period
        u = math.acos(2.0 * radius / travel - 1.0) / math.pi
        return (1.0 - u) * self.approach * self.period

    def stabilisation_time(self, radius: float, travel: float, channels: Sequence[str]) -> float:
        """The true stabilisation time of a second-order arrival for a band of ``radius``:
        from the approach's entry into the band to the ringing's last exit from it (both in
        closed form, not from sampled readings)."""
        if self.settling is None:
            raise StationError("this motion has no second-order settling.")
        return self.entry_lead(radius, travel) + self.settling.last_outside(radius, channels)

    def _hunting(self, channel: str, cycle: int, t: float) -> float:
        """The hunting swing of ``channel`` at ``t`` (0 unless it hunts in ``cycle``)."""
        if not self.hunts(channel, cycle):
            return 0.0
        return self.hunt[channel] * math.sin(2.0 * math.pi * t / self.hunt_period)


def default_free_travel(unit: str) -> float:
    """The free travel in ``unit``: −3/8 in, or −9.525 mm."""
    return FREE_TRAVEL_INCHES * (25.4 if unit == "mm" else 1.0)


__all__ = ["CycleMotion", "DEFAULT_FRACTIONS", "Settling", "Stage", "default_free_travel"]
