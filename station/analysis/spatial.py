"""3-D figures from three orthogonal dial indicators (channels x, y, z).

Two families of figures, both from the same readings (x_j, y_j, z_j), j = 1..n:

* The report's (NASA/KSC 1990, §2.7.5): per-axis offset of the average from nominal,
  ``offset_a = mean(a) − nominal_a``, and the "total" ``sqrt(offset_x² + offset_y² + offset_z²)``.
* ISO 9283:1998 §7.2 (reference/standards.md §1.2–1.3), with the nominal position as the command
  pose: pose accuracy ``APx, APy, APz`` (the same signed offsets) and ``APp`` (the same total:
  the distance from the command point to the barycentre), and pose repeatability
  ``RP = l̄ + 3·S_l``, with ``l_j`` the distance of reading j from the barycentre and ``S_l``
  the sample (n−1) standard deviation of the ``l_j``.

Zeroing the indicators at the taught pose makes the nominal 0 on every axis; RP does not depend
on the nominal at all (it is translation-invariant).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from station.errors import StationError

AXES: tuple[str, str, str] = ("x", "y", "z")


@dataclass(frozen=True)
class Spatial:
    """The 3-D figures of one set of x, y, z readings (lengths in the readings' unit).

    ``offset`` maps each axis to mean − nominal (ISO 9283 APx, APy, APz); ``total_offset`` is
    the report's total, identical to ISO 9283 APp. ``rp`` is ISO 9283 pose repeatability
    l̄ + 3·S_l, ``l_mean`` and ``l_sd`` its parts. Figures that need two readings are None
    below that, with the reason in ``message``.
    """

    n: int
    nominal: dict[str, float]
    offset: dict[str, float]
    total_offset: float
    l_mean: float | None
    l_sd: float | None
    rp: float | None
    message: str | None = None

    @property
    def ap(self) -> dict[str, float]:
        """ISO 9283 pose accuracy: APx, APy, APz (the signed offsets) and APp (their norm)."""
        return {**self.offset, "p": self.total_offset}


def find_axes(names: list[str] | tuple[str, ...] | Mapping[str, object]) -> dict[str, str] | None:
    """Map "x", "y", "z" to the channel names that hold them (case-insensitive), or None.

    None unless all three axes are present.
    """
    by_lower = {str(name).lower(): str(name) for name in names}
    if all(axis in by_lower for axis in AXES):
        return {axis: by_lower[axis] for axis in AXES}
    return None


def spatial_figures(
    x: np.ndarray,
    y: np.ndarray,
    z: np.ndarray,
    nominal: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> Spatial:
    """Per-axis offsets, the report's total, ISO 9283 AP and RP of n readings (x_j, y_j, z_j).

    The three arrays are the readings of one cycle each, in cycle order, so they must have the
    same length (StationError otherwise, and for no readings at all).
    """
    points = [np.asarray(axis, dtype=float) for axis in (x, y, z)]
    n = len(points[0])
    if any(len(axis) != n for axis in points):
        lengths = ", ".join(f"{name} {len(a)}" for name, a in zip(AXES, points, strict=True))
        raise StationError(
            f"the 3-D figures need one x, y and z reading per cycle, but the counts differ "
            f"({lengths}); reject or complete the incomplete cycles."
        )
    if n == 0:
        raise StationError("the 3-D figures need at least one x, y, z reading.")
    means = [float(np.mean(axis)) for axis in points]
    offset = {name: mean - float(nom) for name, mean, nom in zip(AXES, means, nominal, strict=True)}
    total = math.sqrt(sum(value * value for value in offset.values()))
    nominal_map = {name: float(nom) for name, nom in zip(AXES, nominal, strict=True)}
    if n < 2:
        return Spatial(
            n=n,
            nominal=nominal_map,
            offset=offset,
            total_offset=total,
            l_mean=None,
            l_sd=None,
            rp=None,
            message="pose repeatability RP needs at least 2 cycles",
        )
    distances = np.sqrt(sum((axis - mean) ** 2 for axis, mean in zip(points, means, strict=True)))
    l_mean = float(np.mean(distances))
    l_sd = float(np.std(distances, ddof=1))
    return Spatial(
        n=n,
        nominal=nominal_map,
        offset=offset,
        total_offset=total,
        l_mean=l_mean,
        l_sd=l_sd,
        rp=l_mean + 3.0 * l_sd,
    )
