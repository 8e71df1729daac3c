"""Bidirectional positioning of one axis, ISO 230-2 (the report's "inverse move" made
systematic): targets P_i along the axis, each approached 5 times moving up (in the positive
direction, ↑) and 5 times moving down (↓); x_ij is the deviation, actual − target, of the j-th
approach. Per target i, with s the sample standard deviation (n − 1):

* x̄↑_i, x̄↓_i, s↑_i, s↓_i; the bidirectional mean x̄_i = (x̄↑_i + x̄↓_i)/2;
* the reversal B_i = x̄↑_i − x̄↓_i (signed: a backlash that leaves the axis short of each target
  makes it negative);
* R↑_i = 4s↑_i, R↓_i = 4s↓_i, and the bidirectional repeatability
  R_i = max(2s↑_i + 2s↓_i + |B_i|, R↑_i, R↓_i).

Over the axis:

* B = max |B_i|, and the mean reversal B̄ = mean of the B_i (signed);
* R↑ = max R↑_i, R↓ = max R↓_i, R = max R_i (the largest R_i, which is never less than R↑
  or R↓ and exceeds both where the reversal counts);
* E↑ = max x̄↑ − min x̄↑, E↓ likewise, E = max(x̄↑, x̄↓) − min(x̄↑, x̄↓) over both directions
  together (its extremes may lie in different directions: E is then more than E↑ and E↓);
* M = max x̄_i − min x̄_i;
* A↑ = max(x̄↑ + 2s↑) − min(x̄↑ − 2s↑), A↓ likewise, A = max(x̄ + 2s) − min(x̄ − 2s) over both
  directions together.

Definitions: /work/shared/reference/metrology.md (ISO 230-2) and ISO 230-2:2014, clause 3.
Pure: arrays in, a frozen result out; no I/O.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from station.errors import StationError
from station.text import format_figure

APPROACHES = 5
"""The approaches ISO 230-2 asks for at each target in each direction."""
TARGETS_MIN = 5
"""The fewest targets ISO 230-2 asks for (and at least 5 per metre of travel)."""
UP, DOWN = "up", "down"
DIRECTION_WORDS = {"up": UP, "+": UP, "down": DOWN, "-": DOWN}
"""How a table may write an approach's direction (any case): up/+ moving in the positive
direction, down/- in the negative."""


def direction_of(text: str) -> str | None:
    """``up`` or ``down`` for a direction as a table writes it (:data:`DIRECTION_WORDS`), None
    for anything else."""
    return DIRECTION_WORDS.get(text.strip().lower())


@dataclass(frozen=True)
class TargetFigures:
    """One target position: its approaches up and down and what ISO 230-2 derives from them."""

    target: float
    n_up: int
    n_down: int
    mean_up: float
    mean_down: float
    s_up: float
    s_down: float

    @property
    def mean(self) -> float:
        """The bidirectional mean deviation x̄_i."""
        return (self.mean_up + self.mean_down) / 2.0

    @property
    def reversal(self) -> float:
        """B_i = x̄↑_i − x̄↓_i (signed)."""
        return self.mean_up - self.mean_down

    @property
    def r_up(self) -> float:
        """R↑_i = 4 s↑_i."""
        return 4.0 * self.s_up

    @property
    def r_down(self) -> float:
        """R↓_i = 4 s↓_i."""
        return 4.0 * self.s_down

    @property
    def r(self) -> float:
        """R_i = max(2s↑_i + 2s↓_i + |B_i|, R↑_i, R↓_i)."""
        return max(2.0 * self.s_up + 2.0 * self.s_down + abs(self.reversal), self.r_up, self.r_down)

    def as_json(self) -> dict[str, Any]:
        """``target``, ``mean_up``, ``mean_down``, ``s_up``, ``s_down``, ``reversal``, ``R``,
        then ``mean``, ``R_up``, ``R_down``, ``n_up``, ``n_down``."""
        return {
            "target": self.target,
            "mean_up": self.mean_up,
            "mean_down": self.mean_down,
            "s_up": self.s_up,
            "s_down": self.s_down,
            "reversal": self.reversal,
            "R": self.r,
            "mean": self.mean,
            "R_up": self.r_up,
            "R_down": self.r_down,
            "n_up": self.n_up,
            "n_down": self.n_down,
        }


Extreme = tuple[float, float, str]
"""A value, the target it lies at and the direction (``up``, ``down``, or ``both`` for x̄_i)."""


def _largest(values: Iterable[Extreme]) -> Extreme:
    return max(values, key=lambda e: e[0])


def _smallest(values: Iterable[Extreme]) -> Extreme:
    return min(values, key=lambda e: e[0])


@dataclass(frozen=True)
class AxisPositioning:
    """The ISO 230-2 figures of one axis (see the module), from its targets in ascending order;
    ``resolution`` and ``unit`` only shape the report."""

    targets: tuple[TargetFigures, ...]
    resolution: float | None = None
    unit: str = ""

    # -- per direction, the points the figures are extremes of ------------------------------

    def _means(self, *directions: str) -> list[Extreme]:
        found: list[Extreme] = []
        for t in self.targets:
            if UP in directions:
                found.append((t.mean_up, t.target, UP))
            if DOWN in directions:
                found.append((t.mean_down, t.target, DOWN))
        return found

    def _bands(self, sign: float, *directions: str) -> list[Extreme]:
        """x̄ + 2s (``sign`` +1) or x̄ − 2s (−1) of each target in ``directions``."""
        found: list[Extreme] = []
        for t in self.targets:
            if UP in directions:
                found.append((t.mean_up + sign * 2.0 * t.s_up, t.target, UP))
            if DOWN in directions:
                found.append((t.mean_down + sign * 2.0 * t.s_down, t.target, DOWN))
        return found

    def span(self, points: Sequence[Extreme]) -> tuple[float, Extreme, Extreme]:
        """max − min of ``points``, with the largest and the smallest."""
        high, low = _largest(points), _smallest(points)
        return high[0] - low[0], high, low

    # -- the figures ---------------------------------------------------------------------

    @property
    def b(self) -> float:
        """B = max |B_i|."""
        return max(abs(t.reversal) for t in self.targets)

    @property
    def b_mean(self) -> float:
        """B̄ = the mean of the B_i (signed)."""
        return sum(t.reversal for t in self.targets) / len(self.targets)

    @property
    def r_up(self) -> float:
        """R↑ = max R↑_i."""
        return max(t.r_up for t in self.targets)

    @property
    def r_down(self) -> float:
        """R↓ = max R↓_i."""
        return max(t.r_down for t in self.targets)

    @property
    def r(self) -> float:
        """R = max R_i."""
        return max(t.r for t in self.targets)

    @property
    def e_up(self) -> float:
        """E↑ = max x̄↑ − min x̄↑."""
        return self.span(self._means(UP))[0]

    @property
    def e_down(self) -> float:
        """E↓ = max x̄↓ − min x̄↓."""
        return self.span(self._means(DOWN))[0]

    @property
    def e(self) -> float:
        """E = max(x̄↑, x̄↓) − min(x̄↑, x̄↓), both directions together."""
        return self.span(self._means(UP, DOWN))[0]

    @property
    def m(self) -> float:
        """M = max x̄_i − min x̄_i."""
        means = [t.mean for t in self.targets]
        return max(means) - min(means)

    def a_of(self, *directions: str) -> tuple[float, Extreme, Extreme]:
        """A over ``directions``: max(x̄ + 2s) − min(x̄ − 2s), with where each lies."""
        high = _largest(self._bands(1.0, *directions))
        low = _smallest(self._bands(-1.0, *directions))
        return high[0] - low[0], high, low

    @property
    def a_up(self) -> float:
        """A↑ = max(x̄↑ + 2s↑) − min(x̄↑ − 2s↑)."""
        return self.a_of(UP)[0]

    @property
    def a_down(self) -> float:
        """A↓ = max(x̄↓ + 2s↓) − min(x̄↓ − 2s↓)."""
        return self.a_of(DOWN)[0]

    @property
    def a(self) -> float:
        """A = max(x̄ + 2s) − min(x̄ − 2s), both directions together."""
        return self.a_of(UP, DOWN)[0]

    # -- output --------------------------------------------------------------------------

    def as_json(self) -> dict[str, Any]:
        """``B``, ``B_mean``, ``R``, ``R_up``, ``R_down``, ``E``, ``E_up``, ``E_down``, ``M``,
        ``A``, ``A_up``, ``A_down``, ``unit`` and ``targets`` (each :meth:`TargetFigures.
        as_json`)."""
        return {
            "B": self.b,
            "B_mean": self.b_mean,
            "R": self.r,
            "R_up": self.r_up,
            "R_down": self.r_down,
            "E": self.e,
            "E_up": self.e_up,
            "E_down": self.e_down,
            "M": self.m,
            "A": self.a,
            "A_up": self.a_up,
            "A_down": self.a_down,
            "unit": self.unit,
            "targets": [t.as_json() for t in self.targets],
        }

    def notes(self) -> list[str]:
        """What falls short of the standard's test (fewer targets or approaches)."""
        notes = []
        if len(self.targets) < TARGETS_MIN:
            notes.append(
                f"only {len(self.targets)} targets: ISO 230-2 asks for at least {TARGETS_MIN} "
                "(and 5 per metre of travel)."
            )
        few = [t for t in self.targets if min(t.n_up, t.n_down) < APPROACHES]
        if few:
            notes.append(
                f"{len(few)} target(s) approached fewer than {APPROACHES} times in a direction "
                f"(first: {few[0].target:g}): ISO 230-2 asks for {APPROACHES} each way."
            )
        return notes

    def lines(self) -> list[str]:
        """The figures as plain report lines: the table of targets, then each figure with
        where its extremes lie (``100↑``: the target 100 approached moving up)."""

        def g(value: float, signed: bool = False) -> str:
            return format_figure(value, self.resolution, signed=signed)

        def at(point: Extreme) -> str:
            return f"{point[1]:g}{ {UP: '↑', DOWN: '↓'}.get(point[2], '') }"

        approaches = sum(t.n_up + t.n_down for t in self.targets)
        unit = f" in {self.unit}" if self.unit else ""
        lines = [
            f"AXIS POSITIONING (ISO 230-2): {len(self.targets)} targets, {approaches} approaches",
            f"  deviations (actual - target){unit}; ↑ moving up, ↓ moving down",
            f"  {'target':>8} {'mean↑':>10} {'mean↓':>10} {'s↑':>9} {'s↓':>9} "
            f"{'B_i':>10} {'R_i':>9}",
        ]
        for t in self.targets:
            lines.append(
                f"  {t.target:>8g} {g(t.mean_up, True):>10} {g(t.mean_down, True):>10} "
                f"{g(t.s_up):>9} {g(t.s_down):>9} {g(t.reversal, True):>10} {g(t.r):>9}"
            )
        worst_b = max(self.targets, key=lambda t: abs(t.reversal))
        worst_r = max(self.targets, key=lambda t: t.r)
        if worst_r.r > max(worst_r.r_up, worst_r.r_down):
            source = "2s↑ + 2s↓ + |B_i|"
        else:
            source = "4s↑" if worst_r.r_up >= worst_r.r_down else "4s↓"
        _, high_e, low_e = self.span(self._means(UP, DOWN))
        _, high_m, low_m = self.span([(t.mean, t.target, "both") for t in self.targets])
        _, high_a, low_a = self.a_of(UP, DOWN)
        lines += [
            f"  B = {g(self.b)}  reversal, the largest |B_i| (at {worst_b.target:g}); "
            f"mean B = {g(self.b_mean, True)}",
            f"  R = {g(self.r)}  repeatability, the largest R_i (at {worst_r.target:g}: {source})",
            f"      R↑ = {g(self.r_up)}  R↓ = {g(self.r_down)}",
            f"  E = {g(self.e)}  systematic error (mean {at(high_e)} - mean {at(low_e)})",
            f"      E↑ = {g(self.e_up)}  E↓ = {g(self.e_down)}",
            f"  M = {g(self.m)}  mean bidirectional error (mean at {high_m[1]:g} - mean at "
            f"{low_m[1]:g})",
            f"  A = {g(self.a)}  accuracy (mean+2s {at(high_a)} - mean-2s {at(low_a)})",
            f"      A↑ = {g(self.a_up)}  A↓ = {g(self.a_down)}",
        ]
        lines.extend(f"  note: {note}" for note in self.notes())
        return lines


def axis_positioning(
    targets: Sequence[float] | np.ndarray,
    up: Sequence[bool] | np.ndarray,
    deviations: Sequence[float] | np.ndarray,
    *,
    resolution: float | None = None,
    unit: str = "",
) -> AxisPositioning:
    """The ISO 230-2 figures of the approaches given as three aligned sequences: each one's
    target, whether it was approached moving up (else down), and its deviation (actual −
    target). StationError, naming the target, when one is approached from one direction only
    or fewer than twice in a direction (its s needs two)."""
    where = np.asarray(targets, dtype=float)
    rising = np.asarray(up, dtype=bool)
    x = np.asarray(deviations, dtype=float)
    if not (len(where) == len(rising) == len(x)):
        raise ValueError("targets, directions and deviations must be aligned")
    if not len(x):
        raise StationError("no approach to a target yet: approach each one up and down.")
    if not (np.isfinite(where).all() and np.isfinite(x).all()):
        raise StationError("a target or a deviation is not a finite number.")
    figures = []
    for target in np.unique(where).tolist():
        here = where == target
        ups, downs = x[here & rising], x[here & ~rising]
        if not len(ups) or not len(downs):
            have, lack = (DOWN, UP) if not len(ups) else (UP, DOWN)
            raise StationError(
                f"target {target:g} is approached {have} only, never {lack}: approach each "
                f"target from both directions, {APPROACHES} times each."
            )
        for name, values in ((UP, ups), (DOWN, downs)):
            if len(values) < 2:
                raise StationError(
                    f"target {target:g} has 1 approach {name}: its standard deviation needs at "
                    f"least 2 (ISO 230-2 asks for {APPROACHES})."
                )
        figures.append(
            TargetFigures(
                target=float(target),
                n_up=len(ups),
                n_down=len(downs),
                mean_up=float(ups.mean()),
                mean_down=float(downs.mean()),
                s_up=_sd(ups),
                s_down=_sd(downs),
            )
        )
    return AxisPositioning(tuple(figures), resolution, unit)


def _sd(values: np.ndarray) -> float:
    """The sample standard deviation (n − 1); 0 for values that do not vary (not float noise)."""
    if float(np.ptp(values)) == 0.0:
        return 0.0
    return float(values.std(ddof=1))


def standard_cycle(count: int) -> list[tuple[int, str]]:
    """The approaches of one run of ISO 230-2's standard (linear) test cycle over ``count``
    targets, in order: targets 1 to ``count`` moving up, then ``count`` to 1 moving down
    (each as its 0-based index and ``up``/``down``); the axis overshoots the last target before
    it turns, so the first approach down comes from above it."""
    if count < 1:
        raise StationError("the test cycle needs at least one target.")
    return [(i, UP) for i in range(count)] + [(i, DOWN) for i in reversed(range(count))]


def cycle_approach(index: int, count: int) -> tuple[int, str]:
    """The target (0-based) and the direction of the ``index``-th approach (0-based) of a run
    of the standard cycle over ``count`` targets; beyond the run's 2·``count`` approaches it
    starts again."""
    return standard_cycle(count)[index % (2 * count)]
