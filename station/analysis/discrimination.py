"""Whether the gauge can tell the spread it measures apart, and what follows when it cannot.

A dial indicator rounds every reading to its step r: a reading y stands for any value in
[y − r/2, y + r/2]. When the spread of the process is about a step or less, the readings take a
handful of values and the usual statistics stop meaning what they say (``reference/metrology.md``,
"Coarse readings"; ``reference/spc-extensions.md`` §5):

* **Inadequate discrimination** (AIAG SPC and MSA manuals): fewer than ``MIN_POSSIBLE_RANGES``
  (5) possible values of the range — multiples of the step, 0, r, 2r, … — inside the range (or
  moving-range) chart's upper limit; or, Wheeler's reading of the same fact, a within sigma
  below one gauge step, where the chart's limits fall inside what the gauge can resolve and
  points one increment apart are not signals. :func:`discrimination` judges both; every consumer
  (the hints, the normality test, the percentile indices, the JSON) asks it.
* **Control limits never narrower than the gauge can tell apart** (:func:`limit_half_width`):
  the half-width of the location chart's limits is at least ``LIMIT_FLOOR_STEPS`` (1.5) gauge
  steps: one step, plus the half step the rounding may have moved the centre's nearest reading.
  A reading one step from the value nearest the centre line is then never beyond a limit.
* **Zone lines with the rounding counted** (:func:`rounding_margin`): a reading counts beyond
  the centre line or the 1- and 2-sigma lines only when it is beyond by more than half a step,
  that is when every value that rounds to it would be; and "within 1 sigma" only when every such
  value is. With fine readings (r ≪ σ) the margin changes nothing.

* **No shape from rounded readings** (:attr:`Discrimination.resolves_shape`): a test of
  normality and the percentile (non-normal) indices need the readings' shape, which rounding
  hides: none is given when the discrimination is inadequate or the readings' sd is under
  ``SHAPE_MIN_SIGMA_STEPS`` (2) steps. In simulation (150 samples of 30 normal readings
  rounded at sd 1, 1.5, 2, 2.5, 3, 4 steps) Shapiro–Wilk rejected 91, 42, 17, 11, 9 and 7 % of
  them (nominally 5 %), and the Johnson SU fit of the percentile method gave Ppk up to 6e10 at
  1 step and 3e4 at 1.5, none beyond twice the true value from 2 steps on
  (``reference/spc-extensions.md`` §5 notes the ties from σ/4 on; the test still runs there,
  with that note).

In simulation (200 × 30 stable readings rounded at 0.35 and 0.5 step of spread, see
``tests/analysis/test_discrimination.py``) these keep every rule set's false-alarm chance at or
below the chance on fine readings (:mod:`station.analysis.false_alarms`); without them some
alarm fired in 57 % (0.5 step) to 90 % (0.35 step) of such sessions.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from station.analysis.descriptive import as_readings
from station.text import format_spread

#: AIAG: at least this many possible range values inside the range chart's limits.
MIN_POSSIBLE_RANGES = 5
#: Below this sd in gauge steps, no normality test and no percentile index (see above).
SHAPE_MIN_SIGMA_STEPS = 2.0
#: The location chart's half-width is at least this many gauge steps (1 step + ½ step rounding).
LIMIT_FLOOR_STEPS = 1.5


def limit_half_width(
    sigma: float, subgroup: int = 1, resolution: float | None = None, multiple: float = 3.0
) -> float:
    """The half-width of the location chart's limits: ``multiple``·σ/√subgroup, but never less
    than ``LIMIT_FLOOR_STEPS`` gauge steps (one step plus the half step a reading may have been
    rounded by), so that a reading one step from the value nearest the centre line is never
    beyond a limit. Without a resolution the floor is 0."""
    half_width = multiple * sigma / math.sqrt(subgroup)
    if resolution:
        half_width = max(half_width, LIMIT_FLOOR_STEPS * resolution)
    return half_width


def rounding_margin(resolution: float | None) -> float:
    """How far beyond a zone line a reading must lie to count as beyond it: half a gauge step
    (the rounding), so that every value that rounds to the reading is beyond; 0 without a
    resolution."""
    return resolution / 2 if resolution else 0.0


@dataclass(frozen=True)
class Discrimination:
    """How well the gauge step resolves one channel's spread.

    ``distinct``: distinct readings at the step; ``sigma_steps``: the sigma judged (within, else
    overall) in gauge steps; ``sd_steps``: the readings' own sd in gauge steps;
    ``possible_ranges``: range values a step apart (0, r, 2r, …) inside
    the range or moving-range chart's UCL (None for an S chart, whose points are not multiples
    of the step); ``adequate``: False when either falls short (see the module docstring)."""

    resolution: float
    n: int
    distinct: int
    sigma_steps: float | None
    possible_ranges: int | None
    range_chart: str
    adequate: bool
    sd_steps: float | None = None

    @property
    def resolves_shape(self) -> bool:
        """True when the readings' shape (normality, percentiles) can be judged: adequate
        discrimination and an sd of at least ``SHAPE_MIN_SIGMA_STEPS`` steps."""
        return (
            self.adequate and self.sd_steps is not None and (self.sd_steps >= SHAPE_MIN_SIGMA_STEPS)
        )

    def shape_reason(self) -> str:
        """Why the readings' shape is not judged (for the normality line of a report)."""
        values = f"{self.distinct} value{'s' if self.distinct != 1 else ''}"
        sd = "" if self.sd_steps is None else f", sd {self.sd_steps:.2g} steps"
        return (
            f"the gauge rounded the readings to {values}{sd}: ties from the rounding, not the "
            "process, would decide a test of their shape, which needs adequate discrimination "
            f"and an sd of {SHAPE_MIN_SIGMA_STEPS:g} steps or more"
        )

    def sentence(self, name: str, unit: str = "") -> str | None:
        """The one sentence every screen and report carries when the gauge is too coarse
        (None when it is not)."""
        if self.adequate:
            return None
        step = f"{format_spread(self.resolution, self.resolution)} {unit}".rstrip()
        figures = [f"{self.distinct} distinct reading{'s' if self.distinct != 1 else ''}"]
        if self.sigma_steps is not None:
            figures.append(f"sigma within {self.sigma_steps:.2g} steps")
        if self.possible_ranges is not None:
            figures.append(
                f"{self.possible_ranges} possible {self.range_chart}s inside their chart's limits"
            )
        return (
            f"{name}: the gauge step {step} is too coarse for this spread "
            f"({', '.join(figures)}; AIAG asks for {MIN_POSSIBLE_RANGES} possible ranges, "
            "Wheeler for a sigma of a step or more): readings a step apart are not signals, so "
            f"the control limits are held at least {LIMIT_FLOOR_STEPS:g} steps from the centre "
            "and no normality test or percentile index is given; use a finer indicator to judge "
            "the spread."
        )


def discrimination(
    values: Iterable[float] | np.ndarray,
    resolution: float | None,
    *,
    sigma: float | None = None,
    range_ucl: float | None = None,
    range_chart: str = "moving range",
) -> Discrimination | None:
    """Whether the gauge step ``resolution`` resolves the readings' spread (None without a
    resolution or with fewer than 2 readings).

    ``sigma`` is the within sigma of the chart (the readings' own sd when None); ``range_ucl``
    the upper limit of its range or moving-range chart (``range_chart`` names it), whose
    possible values a step apart are counted (AIAG). Inadequate when fewer than
    ``MIN_POSSIBLE_RANGES`` fit, or when sigma is below one step (Wheeler).
    """
    array = as_readings(values)
    if not resolution or array.size < 2:
        return None
    steps = np.floor(array / resolution + 0.5)
    distinct = int(np.unique(steps).size)
    sd = float(np.std(array, ddof=1))
    if sigma is None:
        sigma = sd
    sigma_steps = sigma / resolution if math.isfinite(sigma) else None
    possible = None
    if range_ucl is not None and math.isfinite(range_ucl):
        # 0, r, 2r, ... up to the UCL; a hair of tolerance for a UCL computed as 4.0000000001 r.
        possible = int(math.floor(range_ucl / resolution + 1e-9)) + 1
    adequate = (sigma_steps is None or sigma_steps >= 1.0) and (
        possible is None or possible >= MIN_POSSIBLE_RANGES
    )
    return Discrimination(
        resolution=float(resolution),
        n=int(array.size),
        distinct=distinct,
        sigma_steps=sigma_steps,
        possible_ranges=possible,
        range_chart=range_chart,
        adequate=adequate,
        sd_steps=sd / resolution if math.isfinite(sd) else None,
    )
