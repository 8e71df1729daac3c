"""A simulated 3-joint arm for per-joint troubleshooting (report §1.2, §2.8): one joint moves.

The report isolates a fault "by testing each individual joint separately". The arm is the usual
anthropomorphic one: joint 1 turns the arm about the vertical (base), joints 2 and 3 pitch the
upper arm (shoulder, length ``upper``) and the forearm (elbow, length ``forearm``). At the pose
``pose`` (radians) the cube at the tool centre point sits in the 3-D fixture, indicators x, y,
z. A small angular error δq_j of joint j moves the cube by J_j·δq_j, with J_j the j-th column of
the arm's Jacobian (:func:`jacobian`): the fixture sees each joint's angular repeatability times
its lever arm.

The procedure moves one joint at a time, away and back, for ``cycles`` readings each (joint 1
first), alternating the direction it leaves in (odd cycles +, even cycles −) so that backlash
shows. Per joint (:class:`JointFault`): ``noise`` is the angular repeatability (σ, radians; a
servo that does not settle to the same place), ``skew`` its skew-normal shape, ``overshoot``
the mean of a one-sided exponential error (an under-damped servo stops past the target, always
on the same side, by a varying amount: the report's skewness reading, a₁ ≈ 2), ``backlash`` the
full lost motion
between the two approach directions (radians), and ``offset`` a constant angular error of the
return (an encoder whose zero slipped). Each indicator adds its own reading noise ``gauge_noise``.

The model follows the arm's state (the simulator's robot rests, stepped as the arm leaves and
comes back), not the readings: with ``home_readings=1`` each joint's block starts with a rest at
the taught position (no angular error), where the station zeroes from as many readings as it
likes (a device zero, :meth:`JointModel.zero_reference`, sets the indicators' zero there), then
its ``cycles`` returns, one rest each.

Determinism as :mod:`station.instruments.simulator`: the k-th rest depends only on the seed and
k; the joint's angular error of rest k is drawn once for all three indicators.
"""

from __future__ import annotations

import math
import random
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from station.errors import StationError
from station.instruments.simulator import GaugeSpec, RobotModel, skew_normal_unit

JOINTS = 3
#: The fixture's indicators: 0.0001 in over ±0.5 in.
INCH_INDICATOR = GaugeSpec(0.0001, -0.5, 0.5, "in")


@dataclass(frozen=True)
class JointFault:
    """What one joint does when it returns (radians; see the module)."""

    noise: float = 5e-6
    backlash: float = 0.0
    skew: float = 0.0
    overshoot: float = 0.0
    offset: float = 0.0


def jacobian(
    pose: Sequence[float], upper: float, forearm: float
) -> tuple[tuple[float, float, float], ...]:
    """The 3×3 position Jacobian of the arm at ``pose`` = (q1, q2, q3): column j is how the
    tool centre point (x, y, z) moves per radian of joint j. Returned as three columns."""
    q1, q2, q3 = pose
    reach = upper * math.cos(q2) + forearm * math.cos(q2 + q3)
    d_reach_2 = -upper * math.sin(q2) - forearm * math.sin(q2 + q3)
    d_reach_3 = -forearm * math.sin(q2 + q3)
    d_height_2 = upper * math.cos(q2) + forearm * math.cos(q2 + q3)
    d_height_3 = forearm * math.cos(q2 + q3)
    c1, s1 = math.cos(q1), math.sin(q1)
    return (
        (-reach * s1, reach * c1, 0.0),
        (d_reach_2 * c1, d_reach_2 * s1, d_height_2),
        (d_reach_3 * c1, d_reach_3 * s1, d_height_3),
    )


class JointModel(RobotModel):
    """The per-joint troubleshooting set-up: a 3-joint arm returning to one 3-D fixture, one
    joint moving at a time (see the module)."""

    channels = ("x", "y", "z")

    def __init__(
        self,
        joints: Sequence[JointFault] = (JointFault(), JointFault(), JointFault()),
        *,
        cycles: int = 25,
        pose: Sequence[float] = (math.radians(35.0), math.radians(30.0), math.radians(-60.0)),
        upper: float = 20.0,
        forearm: float = 16.0,
        gauge_noise: float = 0.00003,
        gauge: GaugeSpec = INCH_INDICATOR,
        home_readings: int = 0,
    ) -> None:
        if len(joints) != JOINTS:
            raise StationError(f"the joint model's arm has {JOINTS} joints, not {len(joints)}.")
        if cycles < 2:
            raise StationError(f"each joint needs 2 or more cycles, not {cycles}.")
        if len(pose) != JOINTS:
            raise StationError("the arm's pose is three joint angles q1, q2, q3.")
        self.joints = tuple(joints)
        self.cycles = int(cycles)
        if home_readings < 0:
            raise StationError("the readings at the taught position must not be negative.")
        self.home_readings = int(home_readings)
        self.pose = tuple(float(q) for q in pose)
        self.upper, self.forearm = float(upper), float(forearm)
        self.gauge_noise = float(gauge_noise)
        self._gauge = gauge
        self.columns = jacobian(self.pose, self.upper, self.forearm)
        self.joint: int | None = None
        """The joint moving now (1-based); None: derived from the reading index."""

    def gauge(self, channel: str) -> GaugeSpec:
        """The indicator on ``channel``."""
        return self._gauge

    def lever_arms(self) -> tuple[float, ...]:
        """|J_j|: how far the cube moves per radian of each joint (in the gauge's unit)."""
        return tuple(math.sqrt(sum(c * c for c in column)) for column in self.columns)

    @property
    def readings_per_joint(self) -> int:
        """Readings of each channel per joint: at the taught position, then the returns."""
        return self.home_readings + self.cycles

    def rest_of(self, joint: int, returned: int = 0) -> int:
        """The rest at the taught position before ``joint``'s returns (``returned`` 0), or of
        its ``returned``-th return (1, 2, ...; needs ``home_readings`` 1)."""
        if not 1 <= joint <= JOINTS or not 0 <= returned <= self.cycles:
            raise StationError(
                f"joint {joint} has a rest at the taught position and {self.cycles} returns, "
                f"not return {returned}."
            )
        return (joint - 1) * self.readings_per_joint + returned + self.home_readings - 1

    def current_joint(self, k: int) -> int:
        """The joint (1-based) whose block the k-th reading belongs to."""
        if self.joint is not None:
            return self.joint
        return min(k // self.readings_per_joint, JOINTS - 1) + 1

    def angular_error(self, k: int, seed: int) -> float:
        """The moving joint's angular error on its return for reading k (radians; 0 for a
        reading at the taught position before the joint moves)."""
        joint = self.current_joint(k)
        fault = self.joints[joint - 1]
        cycle = k % self.readings_per_joint - self.home_readings
        if cycle < 0:
            return 0.0
        rng = random.Random(f"{seed}/joint/{k}")
        z0, z1 = rng.gauss(0.0, 1.0), rng.gauss(0.0, 1.0)
        overshoot = fault.overshoot * (rng.expovariate(1.0) - 1.0) if fault.overshoot else 0.0
        # Odd cycles leave in +, even cycles in −: the return approaches from alternate sides.
        direction = 1.0 if cycle % 2 == 0 else -1.0
        return (
            fault.offset
            + fault.noise * skew_normal_unit(fault.skew, z0, z1)
            + direction * fault.backlash / 2.0
            + overshoot
        )

    def true_value(self, channel: str, k: int, seed: int) -> float:
        """The indicator's reading before quantisation and clipping."""
        index = self.channels.index(channel)
        column = self.columns[self.current_joint(k) - 1]
        reading_noise = random.Random(f"{seed}/{index}/{k}").gauss(0.0, 1.0)
        return column[index] * self.angular_error(k, seed) + self.gauge_noise * reading_noise

    def rest_position(self, channel: str, rest: int, seed: int) -> float:
        """Where the indicator rests at the ``rest``-th rest, before quantisation."""
        return self.true_value(channel, rest, seed)

    def value(self, channel: str, k: int, seed: int) -> float:
        """The k-th rest of ``channel`` as the gauge shows it."""
        return self._gauge.show(self.true_value(channel, k, seed))

    def zero_reference(self, channel: str, rest: int, seed: int) -> float:
        """A device zero with the cube at the taught position, before the joint moves: the
        indicators' zero is that position."""
        return 0.0

    def table(self, seed: int = 0) -> list[tuple[int, float, float, float]]:
        """Rows ``(joint, x, y, z)`` of the returns of a whole run (what ``station analyze
        --procedure joint_troubleshooting`` reads from a CSV; readings at the taught position
        left out)."""
        return [
            (self.current_joint(k), *(self.value(c, k, seed) for c in self.channels))
            for k in range(JOINTS * self.readings_per_joint)
            if k % self.readings_per_joint >= self.home_readings
        ]


def faulty_arm(
    joint: int,
    fault: str = "backlash",
    *,
    size: float = 4e-5,
    healthy_noise: float = 5e-6,
    **options: Any,
) -> JointModel:
    """An arm whose joint ``joint`` (1-based) has one fault: ``backlash`` (lost motion ``size``
    radians), ``noise`` (angular σ ``size``), ``servo`` (a one-sided overshoot of mean ``size``:
    an under-damped servo) or ``encoder`` (a constant offset ``size``); the others repeat with σ
    ``healthy_noise``."""
    if not 1 <= joint <= JOINTS:
        raise StationError(f"the faulty joint is 1, 2 or 3, not {joint}.")
    faults = {
        "backlash": JointFault(noise=healthy_noise, backlash=size),
        "noise": JointFault(noise=size),
        "servo": JointFault(noise=healthy_noise, overshoot=size),
        "encoder": JointFault(noise=healthy_noise, offset=size),
    }
    if fault not in faults:
        raise StationError(f"unknown joint fault {fault!r}: use {', '.join(faults)}.")
    joints = [JointFault(noise=healthy_noise)] * JOINTS
    joints[joint - 1] = faults[fault]
    return JointModel(joints, **options)


JOINT_FAULTS: tuple[str, ...] = ("backlash", "noise", "servo", "encoder")
