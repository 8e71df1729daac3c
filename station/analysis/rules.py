"""Run rules on a control chart: the report's four, Western Electric and Nelson.

Every rule looks at the plotted points (individuals or subgroup means) against the centre line
and the sigma of the plotted statistic, sigma = (UCL - centre) / 3. Comparisons are strict, as
in qcc: a point exactly on a limit is not beyond it, a point exactly on the centre line is on
neither side (it breaks a run), and a point exactly at +-1 sigma counts as "within 1 sigma".

qcc semantics (``reference/standards.md`` §2.5, qcc 3.x ``R/rules.R``): a rule flags the point
that completes its pattern and every later point that keeps the pattern going. "k of m" rules
look at the window of m points ending at the current point and flag it when at least k of them
are beyond the zone on one side *and* the current point is one of them.

The report (§2.7.4) lists four signs without defining them further. Our reading:

* report-1, "one point above the UCL or below the LCL": a point beyond the 3-sigma limits.
* report-2, "seven points in the row going up or down": a trend, seven consecutive points each
  higher (or each lower) than the one before (six rises or six falls in a row). A flat step
  breaks it. This is Nelson 3 with seven points instead of six.
* report-3, "fifteen points in the row going up and down": an oscillation, fifteen consecutive
  points alternating up, down, up ... (thirteen changes of direction in a row). "Up or down"
  in rule 2 is a trend, so "up and down" must be the other pattern a chart shows over time;
  this is Nelson 4 with fifteen points instead of fourteen.
* report-4, "two points out of three are in zone C": two of three consecutive points beyond
  2 sigma on the same side (Western Electric 2). The report's "zone C" is read as the outer
  zone between 2 and 3 sigma: two of three points in the zone nearest the centre line is what
  a stable process does most of the time, so it cannot be a sign of trouble. The report
  follows the lettering some SPC software uses, from the centre outward.

Rounded readings (a gauge ``resolution`` given): a reading y stands for every value within half a
step of it, so it counts beyond the centre line or a 1- or 2-sigma line only when it is beyond
by more than half a step, and within 1 sigma only when all of its half-step interval is (see
:mod:`station.analysis.discrimination`); the 3-sigma limits themselves are held at least 1.5
steps from the centre where they are computed. With fine readings the margin changes nothing;
with a spread of a step or less it stops a one-step difference from raising an alarm.

Alarms: one :class:`Alarm` per rule per contiguous run of flagged points on the same side;
``points`` lists every flagged point of that run (1-based), ``text`` is a sentence for the
technician. Given the cycle numbers behind each point (``cycles``), an alarm also lists them and,
when each point is one cycle (single readings), its sentence names the cycles ("Cycle 7 is above
..."): after a rejected cycle, the 6th point is cycle 7.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import FrozenInstanceError, dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from station.analysis.descriptive import as_readings
from station.analysis.discrimination import rounding_margin
from station.errors import StationError
from station.text import format_figure

RULE_SETS: tuple[str, ...] = ("report", "western-electric", "nelson")


class Alarm:
    """One signal: the rule id (``"report-1"``, ``"we-2"``, ``"nelson-7"``), the flagged points
    (1-based, in order), a sentence saying what was seen and where to look (``text``), and the
    cycle numbers behind the flagged points, ascending (``cycles``; empty when the caller gave
    none).

    ``text`` may be given as a function that writes the sentence from the alarm itself (its
    points and cycles): it is called the first time the sentence is read. A long record raises
    tens of thousands of alarms and most are counted, not read; writing each sentence up front
    cost more than finding them, and one writer serves every alarm of a rule.
    Immutable; equal when rule, points, cycles and sentence are.
    """

    __slots__ = ("rule", "points", "cycles", "_text")

    rule: str
    points: tuple[int, ...]
    cycles: tuple[int, ...]
    _text: str | Callable[[Alarm], str]

    def __init__(
        self,
        rule: str,
        points: tuple[int, ...],
        text: str | Callable[[Alarm], str],
        cycles: tuple[int, ...] = (),
    ) -> None:
        object.__setattr__(self, "rule", rule)
        object.__setattr__(self, "points", points)
        object.__setattr__(self, "cycles", cycles)
        object.__setattr__(self, "_text", text)

    @property
    def text(self) -> str:
        """The sentence for the technician (written on first use when it was deferred)."""
        text = self._text
        if not isinstance(text, str):
            text = text(self)
            object.__setattr__(self, "_text", text)
        return text

    def __setattr__(self, name: str, value: Any) -> None:
        raise FrozenInstanceError(f"cannot assign to field {name!r}")

    def __delattr__(self, name: str) -> None:
        raise FrozenInstanceError(f"cannot delete field {name!r}")

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Alarm):
            return NotImplemented
        return (self.rule, self.points, self.cycles) == (
            other.rule,
            other.points,
            other.cycles,
        ) and self.text == other.text

    def __hash__(self) -> int:
        return hash((self.rule, self.points, self.cycles))

    def __repr__(self) -> str:
        return (
            f"Alarm(rule={self.rule!r}, points={self.points!r}, text={self.text!r}, "
            f"cycles={self.cycles!r})"
        )

    def __reduce__(self) -> tuple[Any, ...]:
        return (Alarm, (self.rule, self.points, self.text, self.cycles))


class PointCycles(Sequence[tuple[int, ...]]):
    """The cycle numbers behind each of the first ``points`` chart points: one cycle per point
    for single readings, the ``subgroup`` consecutive cycles of each subgroup mean.

    Kept as one array and looked up on demand: the rules look up only the points of their
    alarms, and building a tuple per point of a million-point chart cost more than the rules
    themselves.
    """

    def __init__(self, cycles: Sequence[int] | np.ndarray, subgroup: int, points: int) -> None:
        self._cycles = np.asarray(cycles, dtype=np.int64)
        self.subgroup = subgroup
        self._points = points
        self._ascending: bool | None = None

    def __len__(self) -> int:
        return self._points

    def __getitem__(self, index):
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(self._points))]
        if index < 0:
            index += self._points
        if not 0 <= index < self._points:
            raise IndexError(index)
        start = index * self.subgroup
        return tuple(self._cycles[start : start + self.subgroup].tolist())

    def span(self, first: int, last: int) -> tuple[int, ...]:
        """The cycles behind points ``first`` to ``last`` (0-based, inclusive), ascending and
        each once: a slice of the array when the cycles ascend, as a record's do."""
        if self._ascending is None:
            self._ascending = bool(np.all(np.diff(self._cycles) > 0))
        chunk = self._cycles[first * self.subgroup : (last + 1) * self.subgroup].tolist()
        return tuple(chunk) if self._ascending else tuple(sorted(set(chunk)))


def flag_runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """The runs of consecutive True items of ``flags``: (first, last) 0-based, inclusive."""
    index = np.flatnonzero(flags)
    if not index.size:
        return []
    breaks = np.flatnonzero(np.diff(index) != 1)
    starts = index[np.concatenate(([0], breaks + 1))]
    ends = index[np.concatenate((breaks, [index.size - 1]))]
    return list(zip(starts.tolist(), ends.tolist(), strict=True))


# A rule's flags: one boolean array per direction (+1 above/rising, -1 below/falling, 0 none).
Flags = dict[int, "np.ndarray"]


@dataclass(frozen=True)
class _Context:
    points: np.ndarray
    center: float
    sigma: float
    margin: float = 0.0
    """Half a gauge step: how far beyond a zone line a rounded reading must be to count."""

    def beyond(self, multiple: float) -> Flags:
        # The control limits (3 sigma) already keep the gauge's floor; the zone lines inside
        # them are judged with the rounding counted against the claim.
        line = multiple * self.sigma + (self.margin if multiple < SIGMA_LIMIT else 0.0)
        return {1: self.points > self.center + line, -1: self.points < self.center - line}

    def within(self, multiple: float) -> np.ndarray:
        """Points whose whole rounding interval lies within ``multiple`` sigma of the centre
        (inclusive, as qcc); none when the band is no wider than the rounding itself."""
        band = multiple * self.sigma - self.margin
        if self.margin and band <= 0:
            return np.zeros(self.points.size, dtype=bool)
        return np.abs(self.points - self.center) <= band


#: The multiple of sigma the control limits sit at.
SIGMA_LIMIT = 3.0


def _runs(condition: np.ndarray, length: int) -> np.ndarray:
    """True where ``condition`` has held for at least ``length`` consecutive items up to here."""
    index = np.arange(condition.size)
    last_break = np.maximum.accumulate(np.where(condition, -1, index))
    return (index - last_break) >= length


def _window_counts(condition: np.ndarray, width: int) -> np.ndarray:
    """How many of the ``width`` items ending here hold; 0 before a full window exists."""
    totals = np.concatenate(([0], np.cumsum(condition, dtype=np.int64)))
    counts = np.zeros(condition.size, dtype=np.int64)
    if condition.size >= width:
        counts[width - 1 :] = totals[width:] - totals[:-width]
    return counts


def _beyond_limits(ctx: _Context) -> Flags:
    return ctx.beyond(SIGMA_LIMIT)


def _k_of_m(k: int, m: int, multiple: float) -> Callable[[_Context], Flags]:
    def rule(ctx: _Context) -> Flags:
        flags = ctx.beyond(multiple)
        return {side: cond & (_window_counts(cond, m) >= k) for side, cond in flags.items()}

    return rule


def _same_side(length: int) -> Callable[[_Context], Flags]:
    def rule(ctx: _Context) -> Flags:
        return {side: _runs(cond, length) for side, cond in ctx.beyond(0.0).items()}

    return rule


def _shift_to_points(flags_on_steps: np.ndarray, offset: int, size: int) -> np.ndarray:
    """Flags indexed by difference (or change of direction) moved onto the point that ends it."""
    shifted = np.zeros(size, dtype=bool)
    shifted[offset : offset + flags_on_steps.size] = flags_on_steps
    return shifted


def _trend(length: int) -> Callable[[_Context], Flags]:
    def rule(ctx: _Context) -> Flags:
        steps = np.diff(ctx.points)
        size = ctx.points.size
        return {
            1: _shift_to_points(_runs(steps > 0, length - 1), 1, size),
            -1: _shift_to_points(_runs(steps < 0, length - 1), 1, size),
        }

    return rule


def _alternating(length: int) -> Callable[[_Context], Flags]:
    def rule(ctx: _Context) -> Flags:
        directions = np.sign(np.diff(ctx.points))
        turns = directions[1:] * directions[:-1] < 0
        return {0: _shift_to_points(_runs(turns, length - 2), 2, ctx.points.size)}

    return rule


def _within_one_sigma(length: int) -> Callable[[_Context], Flags]:
    def rule(ctx: _Context) -> Flags:
        return {0: _runs(ctx.within(1.0), length)}

    return rule


def _outside_both_sides(length: int) -> Callable[[_Context], Flags]:
    def rule(ctx: _Context) -> Flags:
        side = ctx.beyond(1.0)
        above, below = side[1], side[-1]
        full = _window_counts(above | below, length) == length
        mixed = (_window_counts(above, length) > 0) & (_window_counts(below, length) > 0)
        return {0: full & mixed}

    return rule


Formatter = Callable[[float], str]
# A pattern phrase for the alarm text: (side, context, number formatter) -> words.
Pattern = Callable[[int, "_Context", Formatter], str]


def _side_word(side: int) -> str:
    return "above" if side > 0 else "below"


@dataclass(frozen=True)
class _Kind:
    """One kind of signal, shared by the rule sets that use it (WE 2 is Nelson 5 is report 4)."""

    description: str
    check: Callable[[_Context], Flags]
    pattern: Pattern | None  # None: the beyond-the-limits rule, which has its own sentence
    advice: str = ""

    def text(self, subject: str, plural: bool, side: int, ctx: _Context, fmt: Formatter) -> str:
        """The alarm sentence for a run of flagged points on one side, named by ``subject``."""
        if self.pattern is None:
            limit = ctx.center + 3 * ctx.sigma * side
            return (
                f"{subject} {'are' if plural else 'is'} {_side_word(side)} the "
                f"{'upper' if side > 0 else 'lower'} control limit ({fmt(limit)}): "
                f"look for a cause at {'those cycles' if plural else 'that cycle'}."
            )
        advice = self.advice.format(direction="up" if side > 0 else "down")
        verb = "each end" if plural else "completes"
        return f"{subject} {verb} {self.pattern(side, ctx, fmt)}: {advice}."


def _zone_pattern(k: int, m: int, multiple: int) -> Pattern:
    def pattern(side: int, ctx: _Context, fmt: Formatter) -> str:
        line = ctx.center + multiple * ctx.sigma * side
        where = _side_word(side)
        return (
            f"{k} of {m} points beyond {multiple} sigma {where} the centre line "
            f"({where} {fmt(line)})"
        )

    return pattern


def _side_pattern(length: int) -> Pattern:
    return lambda side, ctx, fmt: (
        f"{length} points in a row {_side_word(side)} the centre line ({fmt(ctx.center)})"
    )


def _trend_pattern(length: int) -> Pattern:
    return lambda side, ctx, fmt: (
        f"{length} points in a row, each {'higher' if side > 0 else 'lower'} than the one before"
    )


def _fixed_pattern(words: str) -> Pattern:
    return lambda side, ctx, fmt: words


_SHIFT = (
    "the process may have shifted {direction}; look for a change in set-up, fixture or temperature"
)
_DRIFT = (
    "something is drifting {direction}; look for warm-up, wear, or a fixture or gauge working loose"
)
_OSCILLATION = (
    "look for over-correction or two causes taking turns, such as two fixtures, two approach "
    "directions or backlash"
)

_BEYOND_LIMITS = _Kind(
    "One point beyond the 3-sigma control limits (above the UCL or below the LCL).",
    _beyond_limits,
    None,
)
_TWO_OF_THREE = _Kind(
    "Two of three points in a row beyond 2 sigma on the same side of the centre line.",
    _k_of_m(2, 3, 2.0),
    _zone_pattern(2, 3, 2),
    _SHIFT,
)
_FOUR_OF_FIVE = _Kind(
    "Four of five points in a row beyond 1 sigma on the same side of the centre line.",
    _k_of_m(4, 5, 1.0),
    _zone_pattern(4, 5, 1),
    _SHIFT,
)


def _same_side_kind(length: int, words: str) -> _Kind:
    return _Kind(
        f"{words} points in a row on the same side of the centre line.",
        _same_side(length),
        _side_pattern(length),
        _SHIFT,
    )


def _trend_kind(length: int, description: str) -> _Kind:
    return _Kind(description, _trend(length), _trend_pattern(length), _DRIFT)


def _oscillation_kind(length: int, description: str) -> _Kind:
    return _Kind(
        description,
        _alternating(length),
        _fixed_pattern(f"{length} points in a row alternating up and down"),
        _OSCILLATION,
    )


_RULES: dict[str, tuple[tuple[str, _Kind], ...]] = {
    "report": (
        ("report-1", _BEYOND_LIMITS),
        (
            "report-2",
            _trend_kind(7, "Seven points in a row going up or down, each beyond the last."),
        ),
        (
            "report-3",
            _oscillation_kind(15, "Fifteen points in a row going up and down, alternating."),
        ),
        (
            "report-4",
            _Kind(
                "Two of three points in zone C: beyond 2 sigma on the same side of the centre.",
                _TWO_OF_THREE.check,
                _TWO_OF_THREE.pattern,
                _SHIFT,
            ),
        ),
    ),
    "western-electric": (
        ("we-1", _BEYOND_LIMITS),
        ("we-2", _TWO_OF_THREE),
        ("we-3", _FOUR_OF_FIVE),
        ("we-4", _same_side_kind(8, "Eight")),
    ),
    "nelson": (
        ("nelson-1", _BEYOND_LIMITS),
        ("nelson-2", _same_side_kind(9, "Nine")),
        ("nelson-3", _trend_kind(6, "Six points in a row steadily increasing or decreasing.")),
        ("nelson-4", _oscillation_kind(14, "Fourteen points in a row alternating up and down.")),
        ("nelson-5", _TWO_OF_THREE),
        ("nelson-6", _FOUR_OF_FIVE),
        (
            "nelson-7",
            _Kind(
                "Fifteen points in a row within 1 sigma of the centre line (either side).",
                _within_one_sigma(15),
                _fixed_pattern("15 points in a row within 1 sigma of the centre line"),
                "the spread is smaller than the limits assume; check that the limits are "
                "current and that readings from different set-ups are not averaged together",
            ),
        ),
        (
            "nelson-8",
            _Kind(
                "Eight points in a row beyond 1 sigma, on both sides, none within 1 sigma.",
                _outside_both_sides(8),
                _fixed_pattern(
                    "8 points in a row beyond 1 sigma on both sides, none near the centre line"
                ),
                "look for two sources taking turns, such as two fixtures or two approach "
                "directions",
            ),
        ),
    ),
}


def _rules_of(rule_set: str) -> tuple[tuple[str, _Kind], ...]:
    try:
        return _RULES[rule_set]
    except (KeyError, TypeError):
        known = ", ".join(RULE_SETS)
        raise StationError(f"unknown rule set {rule_set!r}: use one of {known}") from None


#: Every rule's name in words, for alarm lists, reports and journal events.
RULE_NAMES: dict[str, str] = {
    "report-1": "a point beyond the control limits",
    "report-2": "seven points in a row going up or down",
    "report-3": "fifteen points in a row alternating up and down",
    "report-4": "two of three points beyond 2 sigma on one side",
    "we-1": "a point beyond the control limits",
    "we-2": "two of three points beyond 2 sigma on one side",
    "we-3": "four of five points beyond 1 sigma on one side",
    "we-4": "eight points in a row on one side of the centre line",
    "nelson-1": "a point beyond the control limits",
    "nelson-2": "nine points in a row on one side of the centre line",
    "nelson-3": "six points in a row steadily rising or falling",
    "nelson-4": "fourteen points in a row alternating up and down",
    "nelson-5": "two of three points beyond 2 sigma on one side",
    "nelson-6": "four of five points beyond 1 sigma on one side",
    "nelson-7": "fifteen points in a row within 1 sigma of the centre line",
    "nelson-8": "eight points in a row beyond 1 sigma, on both sides",
    "ewma": "the EWMA beyond its limits (a drift of the mean)",
}
_SET_WORDS = {"report": "report rule", "we": "Western Electric rule", "nelson": "Nelson rule"}


@lru_cache(maxsize=256)
def rule_name(rule_id: str) -> str:
    """A rule id in words: ``report-1`` → "report rule 1 (a point beyond the control limits)";
    an unknown id is returned as it is."""
    words = RULE_NAMES.get(rule_id)
    if words is None:
        return rule_id
    family, _, number = rule_id.partition("-")
    if not number:
        return f"drift rule ({words})" if rule_id == "ewma" else words
    return f"{_SET_WORDS.get(family, family)} {number} ({words})"


def rule_descriptions(rule_set: str) -> list[tuple[str, str]]:
    """(rule id, one-line description) of every rule in the set, for help screens and reports."""
    return [(rule_id, kind.description) for rule_id, kind in _rules_of(rule_set)]


def _formatter(resolution: float | None, unit: str | None) -> Formatter:
    """A control line in the alarm's sentence as every figure is written
    (:func:`~station.text.format_figure`: signed, one decimal beyond the gauge step), with the
    unit."""
    return lambda value: format_figure(value, resolution, unit=unit or "")


def _subject(first: int, last: int) -> str:
    """``Point 7``, ``Points 7 and 8``, ``Points 7 to 12``: a run of points by its ends."""
    if last == first:
        return f"Point {first}"
    if last == first + 1:
        return f"Points {first} and {last}"
    return f"Points {first} to {last}"


def number_list(numbers: Sequence[int]) -> str:
    """Ascending numbers as words, consecutive runs of three or more joined: ``7``, ``7 and 9``,
    ``2, 4 to 6 and 8``."""
    runs: list[list[int]] = []
    for number in numbers:
        if runs and number == runs[-1][-1] + 1:
            runs[-1].append(number)
        else:
            runs.append([number])
    parts: list[str] = []
    for run in runs:
        if len(run) >= 3:
            parts.append(f"{run[0]} to {run[-1]}")
        else:
            parts.extend(str(n) for n in run)
    return parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + " and " + parts[-1]


def cycle_subject(cycles: Sequence[int]) -> str:
    """``Cycle 7``, ``Cycles 7 and 9``, ``Cycles 2, 4 to 6 and 8``: cycles ascending, each once."""
    word = "Cycle" if len(cycles) == 1 else "Cycles"
    if cycles[-1] - cycles[0] == len(cycles) - 1:
        # Consecutive (each once, ascending): the list in words needs no walk through them.
        if len(cycles) >= 3:
            return f"{word} {cycles[0]} to {cycles[-1]}"
        if len(cycles) == 2:
            return f"{word} {cycles[0]} and {cycles[1]}"
        return f"{word} {cycles[0]}"
    return f"{word} {number_list(cycles)}"


def _cycles_behind(
    cycles: Sequence[Sequence[int]], first: int, last: int
) -> tuple[tuple[int, ...], bool]:
    """The cycles behind points ``first`` to ``last`` (0-based) ascending, and whether every
    point is one cycle (then the sentence names cycles)."""
    if isinstance(cycles, PointCycles):
        return cycles.span(first, last), cycles.subgroup == 1
    behind = [cycles[i] for i in range(first, last + 1)]
    labels = tuple(sorted({int(c) for group in behind for c in group}))
    return labels, all(len(group) == 1 for group in behind)


@dataclass(frozen=True)
class _Sentence:
    """Writes the sentence of any alarm of one rule on one side of the chart, from the alarm's
    own points and cycles (naming the cycles when every point is one cycle)."""

    kind: _Kind
    side: int
    ctx: _Context
    fmt: Formatter
    names_cycles: bool

    def __call__(self, alarm: Alarm) -> str:
        first, last = alarm.points[0], alarm.points[-1]
        subject = cycle_subject(alarm.cycles) if self.names_cycles else _subject(first, last)
        return self.kind.text(subject, last > first, self.side, self.ctx, self.fmt)


def check_rules(
    points: Iterable[float] | np.ndarray,
    center: float | None,
    sigma: float | None,
    rule_set: str = "report",
    *,
    unit: str | None = None,
    resolution: float | None = None,
    first_point: int = 1,
    cycles: Sequence[Sequence[int]] | None = None,
) -> list[Alarm]:
    """Every alarm of the rule set on the plotted points, ordered by first point then rule.

    ``sigma`` is the sigma of the plotted statistic, (UCL - centre) / 3 (see
    ``ControlChart.point_sigma``). With no centre or sigma (a chart without limits) there is
    nothing to check and the list is empty. The control lines in the text are written at the
    gauge ``resolution`` (one decimal beyond its step) with ``unit`` after them, and the zone
    lines count the readings' rounding to that step (see the module docstring).
    ``first_point`` is the chart number of ``points[0]``: the live form checks only the last
    window of a long chart and still names the points as the chart numbers them.
    ``cycles`` gives, for each of ``points`` in order, the cycle numbers behind it (one for
    single readings, a subgroup's for subgroup means): each alarm then lists them in
    ``cycles``, and names the cycles in its sentence when every point is one cycle.
    """
    rules = _rules_of(rule_set)
    values = as_readings(points, what="point")
    if cycles is not None and len(cycles) != values.size:
        raise StationError(
            f"{len(cycles)} cycle labels were given for {values.size} chart points: "
            "give one per point"
        )
    if center is None or sigma is None or values.size == 0:
        return []
    if not (math.isfinite(center) and math.isfinite(sigma)) or sigma < 0:
        raise StationError(
            f"control limits with centre {center} and sigma {sigma} cannot be checked: "
            "sigma must be a finite number >= 0"
        )
    ctx = _Context(values, float(center), float(sigma), rounding_margin(resolution))
    fmt = _formatter(resolution, unit)
    found: list[Alarm] = []
    keys: list[int] = []  # first point, then the rule's place in the set: the order shown
    offset = first_point  # 0-based index in ``points`` → point number
    for order, (rule_id, kind) in enumerate(rules):
        for side, flags in kind.check(ctx).items():
            # Sentences are written when read (see Alarm), by one writer per rule and side.
            by_points = _Sentence(kind, side, ctx, fmt, names_cycles=False)
            by_cycles = _Sentence(kind, side, ctx, fmt, names_cycles=True)
            for start, end in flag_runs(flags):
                labels: tuple[int, ...] = ()
                single = False
                if cycles is not None:
                    labels, single = _cycles_behind(cycles, start, end)
                first = start + offset
                found.append(
                    Alarm(
                        rule_id,
                        tuple(range(first, end + offset + 1)),
                        by_cycles if single else by_points,
                        labels,
                    )
                )
                keys.append(first * len(rules) + order)
    return [found[i] for i in np.argsort(keys, kind="stable").tolist()]
