"""Position stabilisation time and position overshoot (ISO 9283:1998 §7.4, §7.5) from the
indicators' trace of each return to the fixture.

Definitions (reference/standards.md §1.4 and reference/metrology.md; the ISO text itself was
not retrievable, so these follow its published summary): the *final position* is where the
robot comes to rest, here the mean of the trace's last ``tail`` seconds (the stillness the
arrival trigger waited for). The *band* is a sphere of radius ``band`` about it. Along the
trace, d_j = ‖p_j − p_final‖:

* the **stabilisation time** runs from the first entry into the band to the last one, after
  which the trace stays inside to its end (0 when the robot never leaves the band again after
  entering it). Between two points the trace is taken as a straight line, and an entry is
  where that line crosses into the band: a robot that swings through its final position
  between two points has entered it, though neither point lies inside. A trace whose last
  point lies outside the band never settled: it has no time, and says so; one whose first
  point is already inside the band did not show its entry, and has no time either;
* the **overshoot** is the largest d_j from the first entry on (a distance, ISO's figure), and
  per axis the largest excursion past the final position, on the far side from where the axis
  came (0 when it never went past).

A trace is sampled: the entry lies between the last point outside and the first inside, and
likewise the moment it stays, so each end of a time is known to one sampling interval and the
time to ± two, and a peak between two points is not seen. Every figure here says its sampling
interval.

Pure functions over numpy arrays, results as frozen dataclasses; no I/O.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from station.errors import StationError

BAND_NOISE_FACTOR = 5.0
"""Without a stated band, its radius is this many times the indicators' noise at rest (σ
pooled over every trace's still tail): a still robot's distance from its final position,
three noisy axes, stays inside 5σ but for about one point in 10⁵."""
BAND_MIN_STEPS = 2.0
"""... and never below this many gauge steps: readings one step apart are no motion."""
CYCLES = 3
"""The cycles the standard asks for stabilisation time and overshoot (reference/standards.md
§1.5); the mean over them is reported."""


@dataclass(frozen=True)
class Band:
    """The band's radius and, in words, what it rests on (a stated limit, or k × the noise)."""

    radius: float
    basis: str
    stated: bool
    noise: float | None = None
    """The indicators' noise at rest (σ) the band was taken from, where it was."""


@dataclass(frozen=True)
class ReturnSettling:
    """One return's stabilisation time and overshoot (see the module).

    ``time`` is None when the figure does not exist for this trace, and ``problem`` says why
    (it never entered the band, its entry was not seen, or it never stayed in the band).
    ``overshoot`` (a distance) and ``overshoot_axes`` are None when it never entered."""

    cycle: int
    time: float | None
    overshoot: float | None
    overshoot_axes: tuple[float, ...] | None
    interval: float
    """The trace's sampling interval (the median spacing of its points), s."""
    points: int
    final: tuple[float, ...]
    problem: str = ""
    time_max: float | None = None
    """When the trace moved more than the band between two points before its entry and passed
    near enough to have crossed it unseen: the time had the robot entered then (the time is
    then known only to lie between ``time`` and this); None otherwise."""

    @property
    def settled(self) -> bool:
        """True when the return has a stabilisation time."""
        return self.time is not None


def sampling_interval(t: Any) -> float:
    """The median spacing of the times ``t`` (s); nan with fewer than two."""
    times = np.asarray(t, dtype=float)
    if times.size < 2:
        return math.nan
    return float(np.median(np.diff(times)))


def final_position(t: Any, values: Any, tail: float) -> np.ndarray:
    """The mean of the points of the trace's last ``tail`` seconds (at least its last point):
    where the robot came to rest."""
    times = np.asarray(t, dtype=float)
    rows = np.asarray(values, dtype=float)
    kept = times >= times[-1] - tail
    return np.asarray(rows[kept].mean(axis=0), dtype=float)


def rest_deviations(t: Any, values: Any, tail: float) -> np.ndarray:
    """The deviations of the trace's last ``tail`` seconds from their mean, per axis (the
    indicators' noise at rest)."""
    times = np.asarray(t, dtype=float)
    rows = np.asarray(values, dtype=float)
    kept = rows[times >= times[-1] - tail]
    return np.asarray(kept - kept.mean(axis=0), dtype=float)


def noise_band(traces: Sequence[tuple[Any, Any]], tail: float, resolution: float) -> Band:
    """The band from the indicators' noise at rest: ``BAND_NOISE_FACTOR`` × σ pooled over the
    still tails of ``traces`` (``(t, values)`` each; per axis, n − 1 per tail and axis), and no
    narrower than ``BAND_MIN_STEPS`` gauge steps."""
    squares, freedom = 0.0, 0
    for t, values in traces:
        deviations = rest_deviations(t, values, tail)
        squares += float(np.sum(deviations**2))
        freedom += max(0, deviations.shape[0] - 1) * deviations.shape[1]
    sigma = math.sqrt(squares / freedom) if freedom else None
    floor = BAND_MIN_STEPS * resolution
    if sigma is None or BAND_NOISE_FACTOR * sigma < floor:
        noise = "the noise at rest unknown" if sigma is None else f"σ {sigma:.3g} at rest"
        return Band(
            floor,
            f"{BAND_MIN_STEPS:g} gauge steps (the indicators' noise, {noise}, is below "
            f"{floor / BAND_NOISE_FACTOR:.3g}: the band is no narrower than the readings can "
            "tell)",
            stated=False,
            noise=sigma,
        )
    return Band(
        BAND_NOISE_FACTOR * sigma,
        f"{BAND_NOISE_FACTOR:g} × the indicators' noise at rest (σ {sigma:.3g}, pooled over "
        f"the last {tail:g} s of every return, {freedom} degrees of freedom)",
        stated=False,
        noise=sigma,
    )


def stated_band(radius: float) -> Band:
    """A band stated by the user (e.g. the manufacturer's limit)."""
    if not (math.isfinite(radius) and radius > 0):
        raise StationError(f"the stabilisation band must be a size over 0, not {radius:g}.")
    return Band(radius, "a stated limit", stated=True)


def return_settling(
    cycle: int,
    t: Any,
    values: Any,
    band: float,
    *,
    final: Sequence[float] | None = None,
    tail: float = 0.0,
) -> ReturnSettling:
    """The stabilisation time and overshoot of one return's trace: ``t`` the times (s, rising),
    ``values`` one row per time, one column per axis; ``final`` the final position (else the
    mean of the last ``tail`` seconds: :func:`final_position`)."""
    times = np.asarray(t, dtype=float)
    rows = np.asarray(values, dtype=float)
    if rows.ndim != 2 or rows.shape[0] != times.size or times.size < 2:
        raise StationError(
            f"the trace of cycle {cycle} holds {times.size} points: a settling needs at least two."
        )
    rest = (
        np.asarray(final, dtype=float) if final is not None else final_position(times, rows, tail)
    )
    interval = sampling_interval(times)
    distance = np.sqrt(np.sum((rows - rest) ** 2, axis=1))
    inside = distance <= band
    final_tuple = tuple(float(v) for v in rest)

    def made(
        time: float | None,
        overshoot: float | None,
        axes: tuple[float, ...] | None,
        problem: str = "",
        time_max: float | None = None,
    ) -> ReturnSettling:
        return ReturnSettling(
            cycle, time, overshoot, axes, interval, int(times.size), final_tuple, problem, time_max
        )

    relative = rows - rest
    if inside[0]:
        # Its approach is not in the trace: when it came in is unknown.
        side0 = np.zeros(rows.shape[1])
        return made(
            None,
            float(distance.max()),
            _past(relative, side0),
            "its trace starts inside the band, so its entry was not seen",
        )
    entered = None
    for j in range(times.size - 1):
        s = _crossing_in(relative[j], relative[j + 1], band)
        if s is not None:
            entered = (j, float(times[j] + s * (times[j + 1] - times[j])))
            break
    if entered is None:
        return made(None, None, None, "it never came within the band")
    j, t_entry = entered
    # What comes after the entry: the points from the end of the segment it entered on.
    after = slice(j + 1, None)
    # Past the final position: on the far side from where each axis came (its first point).
    axes = _past(relative[after], np.sign(-relative[0]))
    overshoot = float(distance[after].max())
    if not inside[-1]:
        return made(
            None,
            overshoot,
            axes,
            "it was outside the band at the end of its trace: it never settled",
        )
    outside = np.flatnonzero(~inside[after])
    unseen = _unseen_entry(relative[: j + 1], band)
    if outside.size == 0:
        t_stay = t_entry
    else:
        last = j + 1 + int(outside[-1])
        back = _crossing_in(relative[last], relative[last + 1], band)
        assert back is not None  # from a point outside to one inside: it crosses
        t_stay = float(times[last] + back * (times[last + 1] - times[last]))
    longest = None if unseen is None else t_stay - float(times[unseen])
    return made(t_stay - t_entry, overshoot, axes, time_max=longest)


def _unseen_entry(relative: np.ndarray, band: float) -> int | None:
    """The first point of the earliest stretch before the entry's (``relative``: the points up
    to the start of the segment the entry was found on) where the robot moved more than the
    band between two points and came within the band plus half that move of the final
    position: a path that bends between the points may have entered there, unseen. The stretch
    just before the entry's is left out: an entry there is within a sampling interval."""
    for k in range(relative.shape[0] - 2):
        a, b = relative[k], relative[k + 1]
        step = float(np.linalg.norm(b - a))
        if step > band and _closest(a, b) <= band + step / 2:
            return k
    return None


def _closest(a: np.ndarray, b: np.ndarray) -> float:
    """The distance of the straight line from ``a`` to ``b`` from the origin (the final
    position)."""
    v = b - a
    square = float(v @ v)
    s = 0.0 if square == 0.0 else min(1.0, max(0.0, -float(a @ v) / square))
    return float(np.linalg.norm(a + s * v))


def _past(relative: np.ndarray, side: np.ndarray) -> tuple[float, ...]:
    """Per axis, the largest excursion of ``relative`` (points less the final position) on
    the ``side`` (+1, −1; 0: none) past the final position; 0 when it never went past."""
    return tuple(float(max(0.0, v)) for v in (relative * side).max(axis=0))


def _crossing_in(a: np.ndarray, b: np.ndarray, radius: float) -> float | None:
    """Where (0..1) the straight line from ``a`` to ``b`` (points less the final position)
    first comes within ``radius``; None when it does not. Between two points the trace is
    taken as straight: a robot passing through its final position between two points far
    apart still entered the band."""
    if float(a @ a) <= radius**2:
        return 0.0
    v = b - a
    square = float(v @ v)
    if square == 0.0:
        return None
    half = float(a @ v)
    disc = half**2 - square * (float(a @ a) - radius**2)
    if disc < 0:
        return None
    s = (-half - math.sqrt(disc)) / square
    return s if 0.0 <= s <= 1.0 else None


@dataclass(frozen=True)
class Stabilisation:
    """The stabilisation time and overshoot over the returns (see the module).

    The mean and the largest time exist only when every return settled (a return that never
    stayed in the band has no time, so neither has their mean); the overshoots are over the
    returns that entered the band. ``interval`` is the coarsest sampling interval of the
    traces: each time is known to ± it. ``*_ci`` are 95 % confidence intervals of the means
    (Student's t over the returns; None with fewer than two)."""

    band: Band
    returns: tuple[ReturnSettling, ...]
    interval: float
    axes: tuple[str, ...]
    unit: str
    resolution: float
    mean_time: float | None
    max_time: float | None
    mean_overshoot: float | None
    max_overshoot: float | None
    mean_time_ci: tuple[float, float] | None
    mean_overshoot_ci: tuple[float, float] | None

    @property
    def unsettled(self) -> tuple[ReturnSettling, ...]:
        """The returns without a stabilisation time."""
        return tuple(r for r in self.returns if not r.settled)

    def as_json(self) -> dict[str, Any]:
        """``station analyze --json``'s ``stabilisation``."""
        return {
            "band": self.band.radius,
            "band_basis": self.band.basis,
            "band_stated": self.band.stated,
            "noise": self.band.noise,
            "sampling_interval": self.interval,
            "unit": self.unit,
            "axes": list(self.axes),
            "returns": [
                {
                    "cycle": r.cycle,
                    "time": r.time,
                    "overshoot": r.overshoot,
                    "overshoot_axes": None if r.overshoot_axes is None else list(r.overshoot_axes),
                    "sampling_interval": r.interval,
                    "points": r.points,
                    "settled": r.settled,
                    "time_max": r.time_max,
                    "problem": r.problem or None,
                }
                for r in self.returns
            ],
            "mean_time": self.mean_time,
            "max_time": self.max_time,
            "mean_time_ci": None if self.mean_time_ci is None else list(self.mean_time_ci),
            "mean_overshoot": self.mean_overshoot,
            "max_overshoot": self.max_overshoot,
            "mean_overshoot_ci": (
                None if self.mean_overshoot_ci is None else list(self.mean_overshoot_ci)
            ),
        }


def mean_interval(values: Sequence[float], confidence: float = 0.95) -> tuple[float, float] | None:
    """Student's t confidence interval of the mean of ``values`` (None with fewer than two)."""
    if len(values) < 2:
        return None
    from scipy import stats

    data = np.asarray(values, dtype=float)
    half = float(stats.t.ppf(0.5 + confidence / 2, data.size - 1)) * float(
        data.std(ddof=1) / math.sqrt(data.size)
    )
    centre = float(data.mean())
    return centre - half, centre + half


def stabilisation(
    returns: Sequence[ReturnSettling],
    band: Band,
    *,
    axes: Sequence[str],
    unit: str,
    resolution: float,
) -> Stabilisation:
    """The statistics over ``returns`` (see :class:`Stabilisation`)."""
    if not returns:
        raise StationError("no return's trace is recorded yet: capture a cycle.")
    times = [r.time for r in returns if r.time is not None]
    every = len(times) == len(returns)
    overshoots = [r.overshoot for r in returns if r.overshoot is not None]
    intervals = [r.interval for r in returns if math.isfinite(r.interval)]
    return Stabilisation(
        band=band,
        returns=tuple(returns),
        interval=max(intervals) if intervals else math.nan,
        axes=tuple(axes),
        unit=unit,
        resolution=resolution,
        mean_time=float(np.mean(times)) if every else None,
        max_time=max(times) if every else None,
        mean_overshoot=float(np.mean(overshoots)) if overshoots else None,
        max_overshoot=max(overshoots) if overshoots else None,
        mean_time_ci=mean_interval(times) if every else None,
        mean_overshoot_ci=mean_interval(overshoots),
    )


# -- the report's block ------------------------------------------------------------------------


def time_decimals(interval: float) -> int:
    """Decimals that show a time to its sampling interval (0.01 s: 2), at least one."""
    if not (math.isfinite(interval) and interval > 0):
        return 3
    return max(1, math.ceil(-math.log10(interval) - 1e-9))


def lines(result: Stabilisation) -> list[str]:
    """The report's block: the band and its basis, each return, the statistics, each time with
    its sampling interval and each mean with its confidence interval."""
    from station.text import format_spread

    unit, res = result.unit, result.resolution
    step = result.interval
    places = time_decimals(step)

    def seconds(value: float) -> str:
        return f"{value:.{places}f}"

    def size(value: float | None) -> str:
        return format_spread(value, res)

    out = [
        "ISO 9283 POSITION STABILISATION TIME AND OVERSHOOT (§7.4, §7.5)",
        f"  band: {size(result.band.radius)} {unit} about the final position (the mean of "
        f"its still tail), {result.band.basis}",
        f"  traces sampled every {seconds(step)} s: each end of a time is found within one "
        f"sampling interval, so a time is known to ± {seconds(2 * step)} s, and a peak "
        "between two points is not seen",
        f"  {'cycle':>5}  {'time (s)':>14}  {'overshoot':>10}  past " + " / ".join(result.axes),
    ]
    for r in result.returns:
        if r.time is None:
            shown = f"no time: {r.problem}"
            if r.overshoot is not None:
                shown += f"; overshoot {size(r.overshoot)} {unit}"
            out.append(f"  {r.cycle:>5}  {shown}")
            continue
        assert r.overshoot is not None and r.overshoot_axes is not None
        time_text = f"{seconds(r.time)} ± {seconds(2 * r.interval)}"
        past = " ".join(size(v) for v in r.overshoot_axes)
        out.append(f"  {r.cycle:>5}  {time_text:>14}  {size(r.overshoot):>10}  {past}")
        if r.time_max is not None:
            out.append(
                f"         or up to {seconds(r.time_max)} s: before its entry the trace moved "
                "more than the band between two points near the final position, and may have "
                "crossed it unseen, and overshot more after it (read the indicators faster, "
                "or widen the band)"
            )
    n = len(result.returns)
    unsettled = result.unsettled
    if unsettled:
        out.append(
            f"  stabilisation time: none over the returns: {len(unsettled)} of {n} have no "
            "time (see above), so neither has their mean or the largest"
        )
    elif result.mean_time is not None and result.max_time is not None:
        interval = result.mean_time_ci
        ci = (
            f"95 % confidence {seconds(interval[0])} to {seconds(interval[1])} s over {n} returns"
            if interval is not None
            else "one return: no confidence interval"
        )
        out.append(
            f"  stabilisation time: mean {seconds(result.mean_time)} s ({ci}), largest "
            f"{seconds(result.max_time)} s; each ± {seconds(2 * step)} s (two sampling intervals)"
        )
        doubtful = [r.cycle for r in result.returns if r.time_max is not None]
        if doubtful:
            out.append(
                f"  (cycles {', '.join(map(str, doubtful))} may have entered the band unseen, "
                "earlier: their times, the mean and the largest may be longer, as said above)"
            )
    if result.mean_overshoot is not None and result.max_overshoot is not None:
        interval = result.mean_overshoot_ci
        entered = sum(1 for r in result.returns if r.overshoot is not None)
        ci = (
            f"95 % confidence {size(interval[0])} to {size(interval[1])} over {entered} returns"
            if interval is not None
            else "one return: no confidence interval"
        )
        noise = (
            f", each ± the indicators' noise (σ {result.band.noise:.3g})"
            if result.band.noise is not None
            else ""
        )
        out.append(
            f"  overshoot: mean {size(result.mean_overshoot)} {unit} ({ci}), largest "
            f"{size(result.max_overshoot)} {unit}; as sampled every {seconds(step)} s{noise}"
        )
    if n < CYCLES:
        out.append(f"  fewer than the {CYCLES} cycles the standard measures.")
    return out


__all__ = [
    "BAND_MIN_STEPS",
    "BAND_NOISE_FACTOR",
    "Band",
    "CYCLES",
    "ReturnSettling",
    "Stabilisation",
    "final_position",
    "lines",
    "mean_interval",
    "noise_band",
    "rest_deviations",
    "return_settling",
    "sampling_interval",
    "stabilisation",
    "stated_band",
    "time_decimals",
]
