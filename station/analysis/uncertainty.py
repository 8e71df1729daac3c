"""A measurement-uncertainty budget, GUM style (JCGM 100:2008), and the decision of a value
against its limits (ISO 14253-1, JCGM 106:2012). Every verdict of a value against limits goes
through :func:`decide`; every budget through :func:`evaluate`.

A :class:`Budget` is a tuple of :class:`Contribution` s, each a standard uncertainty u_i with its
sensitivity c_i and degrees of freedom ν_i (∞ for a Type B input known exactly enough).
:func:`evaluate` gives the :class:`BudgetResult`:

    u_c² = Σ (c_i u_i)²                          (GUM 5.1.2, uncorrelated inputs)
    ν_eff = u_c⁴ / Σ (c_i u_i)⁴ / ν_i              (Welch–Satterthwaite, GUM G.4.1)
    k = t_p(⌊ν_eff⌋) at a confidence p, or as given; U = k · u_c    (GUM G.4, 6.2)

The constructors turn what a budget line states into u_i: a Type A mean (:func:`type_a`, s/√n
on n − 1 degrees of freedom), a half-width with its distribution (:func:`from_half_width`:
rectangular a/√3, triangular a/√6, arcsine a/√2, normal a/k), a certificate's U at k
(:func:`from_expanded`), and the usual lines of a dial-indicator channel: :func:`resolution`
(r/2 rectangular), :func:`repeatability` (a Type-1 check's s on n − 1), :func:`temperature`
(L·α·ΔT) and :func:`cosine_error`.

No uncertainty library is used, on purpose. ``uncertainties`` (3.2) propagates standard
uncertainties but keeps no degrees of freedom, so it cannot give ν_eff or a k at a confidence,
which is the point here; Sandia's ``suncal`` does, but brings matplotlib, sympy, pint, markdown
and PyYAML for what is a sum of squares; ``metas-unclib`` runs on .NET. The budget is linear
in its inputs, so the two sums above and scipy's Student t are the whole computation.

Every figure here is finite or a clear error: a negative or NaN uncertainty, a zero or infinite
coverage factor, an unknown distribution, a sensitivity that is not a number and limits with
LSL ≥ USL are refused with a :class:`~station.errors.StationError` naming the input.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from enum import StrEnum
from statistics import NormalDist
from typing import Any

import numpy as np

from station.errors import StationError

DIVISORS: dict[str, float] = {
    "rectangular": math.sqrt(3.0),
    "triangular": math.sqrt(6.0),
    "arcsine": math.sqrt(2.0),
    "normal": 2.0,
}
"""The divisor from a half-width a to the standard uncertainty, per distribution (GUM 4.3.7,
4.3.9). For ``normal`` the half-width is taken as an expanded uncertainty at k = 2 (about 95 %,
how certificates state it); :func:`from_half_width` takes another ``k``."""

DEFAULT_K = 2.0
"""The coverage factor when neither a k nor a confidence is given (about 95 % on ν_eff = ∞)."""

MAGNITUDE = 1e150
"""The largest contribution |c|·u taken (the station's bound on readings and limits): U and the
guard bands stay finite."""

STEEL_EXPANSION = 11.5e-6
"""Linear expansion coefficient of steel per °C, for :func:`temperature` (the reference's α)."""


@dataclass(frozen=True)
class Contribution:
    """One line of a budget: the input's standard uncertainty ``u`` (in its own unit), the
    ``sensitivity`` c (output unit per input unit) and the degrees of freedom ``dof`` of u
    (``math.inf`` when it is known well: most Type B lines)."""

    name: str
    u: float
    sensitivity: float = 1.0
    dof: float = math.inf

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise StationError("a budget input has no name; give each input a 'name'.")
        _number(self.name, "u", self.u)
        if not (self.u >= 0 and math.isfinite(self.u)):
            raise StationError(
                f"input {self.name!r}: u must be a finite number 0 or more, not {self.u!r}."
            )
        _number(self.name, "sensitivity", self.sensitivity)
        if not math.isfinite(self.sensitivity):
            raise StationError(
                f"input {self.name!r}: sensitivity must be a finite number, not "
                f"{self.sensitivity!r}."
            )
        _number(self.name, "dof", self.dof)
        if not self.dof >= 1:
            raise StationError(
                f"input {self.name!r}: dof must be 1 or more (or inf), not {self.dof!r}."
            )

        if not abs(self.sensitivity) * self.u <= MAGNITUDE:
            raise StationError(
                f"input {self.name!r}: |sensitivity| × u is beyond {MAGNITUDE:g}; check the "
                "unit of both."
            )

    @property
    def ui(self) -> float:
        """The contribution to the output, |c| · u, in the output's unit."""
        return abs(self.sensitivity) * self.u


def _number(name: str, key: str, value: object) -> None:
    # A bool is an int to Python, but `sensitivity = true` is a slip, not 1.
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise StationError(f"input {name!r}: {key} must be a number, not {value!r}.")
    if math.isnan(value):
        raise StationError(f"input {name!r}: {key} is NaN; give a number.")


def type_a(name: str, readings: Sequence[float], sensitivity: float = 1.0) -> Contribution:
    """The Type A uncertainty of the mean of ``readings``: s/√n on n − 1 degrees of freedom."""
    values = list(readings)
    for value in values:
        _number(name, "readings", value)
        if not math.isfinite(value):
            raise StationError(f"input {name!r}: readings hold {value!r}; give finite numbers.")
    if len(values) < 2:
        raise StationError(
            f"input {name!r}: readings need at least 2 values for a spread, not {len(values)}."
        )
    n = len(values)
    mean = math.fsum(values) / n
    s = math.sqrt(math.fsum((v - mean) ** 2 for v in values) / (n - 1))
    return Contribution(name, s / math.sqrt(n), sensitivity, float(n - 1))


def from_half_width(
    name: str,
    half_width: float,
    distribution: str,
    sensitivity: float = 1.0,
    dof: float = math.inf,
    k: float | None = None,
) -> Contribution:
    """A Type B line from the half-width ``a`` of ``distribution`` (see :data:`DIVISORS`);
    ``k`` only for ``normal``: the half-width is then U at that k."""
    _number(name, "half_width", half_width)
    if not half_width >= 0 or not math.isfinite(half_width):
        raise StationError(
            f"input {name!r}: half_width must be a finite number 0 or more, not {half_width!r}."
        )
    if not isinstance(distribution, str) or distribution not in DIVISORS:
        raise StationError(
            f"input {name!r}: distribution {distribution!r} is not one of {', '.join(DIVISORS)}."
        )
    divisor = DIVISORS[distribution]
    if k is not None:
        if distribution != "normal":
            raise StationError(
                f"input {name!r}: k goes with a normal half-width only, not a {distribution} one."
            )
        divisor = check_coverage(k, f"input {name!r}: k")
    return Contribution(name, half_width / divisor, sensitivity, dof)


def from_expanded(
    name: str, expanded: float, k: float, sensitivity: float = 1.0, dof: float = math.inf
) -> Contribution:
    """A Type B line from an expanded uncertainty U at coverage ``k`` (a certificate): U/k."""
    _number(name, "expanded", expanded)
    if not expanded >= 0 or not math.isfinite(expanded):
        raise StationError(
            f"input {name!r}: expanded must be a finite number 0 or more, not {expanded!r}."
        )
    return Contribution(name, expanded / check_coverage(k, f"input {name!r}: k"), sensitivity, dof)


def resolution(step: float, name: str = "resolution") -> Contribution:
    """A digital gauge's step r: rectangular of half-width r/2, u = r/√12."""
    return from_half_width(name, step / 2.0, "rectangular")


def repeatability(sd: float, n: int, name: str = "repeatability") -> Contribution:
    """One reading's repeatability from a Type-1 check: its sample SD s of n readings, used as
    u of a single reading on n − 1 degrees of freedom (a pooled s, GUM H.1)."""
    return Contribution(name, sd, 1.0, float(n - 1))


def temperature(
    length: float,
    delta_t: float,
    alpha: float = STEEL_EXPANSION,
    distribution: str = "rectangular",
    name: str = "temperature",
) -> Contribution:
    """A fixture arm of ``length`` that may be ±``delta_t`` °C off its reference temperature
    moves up to length·α·ΔT: that half-width with its ``distribution`` (arcsine for a
    temperature cycling between the bounds)."""
    return from_half_width(name, abs(length * alpha * delta_t), distribution)


def cosine_error(travel: float, angle: float, name: str = "cosine error") -> Contribution:
    """A plunger ``angle`` radians off the direction of ``travel`` reads travel·(1 − cos θ)
    short. The error is one-sided and θ is rarely known better than a bound, so the error is
    taken as rectangular from 0 to that figure: u = travel·(1 − cos θ)/√12."""
    return from_half_width(name, abs(travel) * (1.0 - math.cos(angle)) / 2.0, "rectangular")


def check_coverage(k: object, what: str = "k") -> float:
    """``k`` when it is a finite coverage factor above 0; otherwise a StationError naming
    ``what``."""
    if isinstance(k, bool) or not isinstance(k, int | float) or not math.isfinite(k) or k <= 0:
        raise StationError(f"{what} must be a finite number above 0, not {k!r}.")
    return float(k)


def check_confidence(confidence: object, what: str = "confidence") -> float:
    """``confidence`` when it is a probability strictly between 0 and 1."""
    if (
        isinstance(confidence, bool)
        or not isinstance(confidence, int | float)
        or not 0 < confidence < 1
    ):
        raise StationError(
            f"{what} must be a probability between 0 and 1 (e.g. 0.95), not {confidence!r}."
        )
    return float(confidence)


@dataclass(frozen=True)
class Budget:
    """The contributions to one measured value (one channel's reading), in ``unit``."""

    contributions: tuple[Contribution, ...]
    unit: str = ""

    def __post_init__(self) -> None:
        if not self.contributions:
            raise StationError("the budget has no inputs; give at least one.")
        names = [c.name for c in self.contributions]
        repeated = sorted({name for name in names if names.count(name) > 1})
        if repeated:
            raise StationError(
                f"input {repeated[0]!r} is given twice; give each input a name of its own."
            )


@dataclass(frozen=True)
class Line:
    """One contribution as evaluated: ``ui`` = |c|·u and its ``share`` of u_c² (0 to 1)."""

    name: str
    u: float
    sensitivity: float
    ui: float
    dof: float
    share: float


@dataclass(frozen=True)
class BudgetResult:
    """The evaluated budget: combined standard uncertainty ``u_c``, effective degrees of
    freedom ``nu_eff`` (``math.inf`` when every line has ∞), the coverage factor ``k`` and the
    expanded uncertainty ``U`` = k·u_c; ``confidence`` when k came from one."""

    u_c: float
    nu_eff: float
    k: float
    U: float
    confidence: float | None
    lines: tuple[Line, ...]
    unit: str = ""

    def as_json(self) -> dict[str, Any]:
        """``{"u_c", "nu_eff", "k", "U", "confidence", "unit", "contributions": [{"name", "u",
        "sensitivity", "ui", "dof", "share"}]}``: ∞ degrees of freedom as null (JSON has no
        infinity). ``station budget --json`` and ``analyze --json`` both print this."""
        return {
            "u_c": self.u_c,
            "nu_eff": _finite(self.nu_eff),
            "k": self.k,
            "U": self.U,
            "confidence": self.confidence,
            "unit": self.unit,
            "contributions": [
                {
                    "name": line.name,
                    "u": line.u,
                    "sensitivity": line.sensitivity,
                    "ui": line.ui,
                    "dof": _finite(line.dof),
                    "share": line.share,
                }
                for line in self.lines
            ],
        }


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None


@dataclass(frozen=True)
class GaugeRecord:
    """What the gauge register said of a channel's gauge when the session began, for its
    budget: the calibration certificate's expanded uncertainty ``certificate_U`` at
    ``certificate_k`` (None: no certificate recorded), and the latest Type-1 check's sample SD
    ``repeatability_sd`` of ``repeatability_n`` readings (None: no check recorded)."""

    gauge: str = ""
    certificate_U: float | None = None
    certificate_k: float | None = None
    repeatability_sd: float | None = None
    repeatability_n: int | None = None


def channel_budget(
    step: float | None,
    gauge: GaugeRecord | None = None,
    zero_uncertainty: float | None = None,
    unit: str = "",
) -> Budget | None:
    """The measurement budget of one reading of a dial-indicator channel, from what the session
    records: the gauge ``step`` (r/2 rectangular), the gauge's certificate (U/k), its repeatability
    from the latest Type-1 check (s on n − 1), and the zero's own standard uncertainty (its
    readings' standard error with their rounding, as the zero event records it). None when
    the session records none of them.

    The step and the Type-1 s are both kept although s already holds some rounding: GUM F.2.2.1
    allows either; keeping both can only overstate u_c, never hide the step. The zero's
    rest-to-rest draw (:mod:`station.analysis.zeros`) is not a line here: it moves the mean of
    a session, not the measurement of one reading against the zero taken.
    """
    lines: list[Contribution] = []
    if step is not None and step > 0:
        lines.append(resolution(step, "gauge step (r/2 rectangular)"))
    if gauge is not None:
        if gauge.certificate_U is not None and gauge.certificate_k is not None:
            lines.append(
                from_expanded(
                    f"certificate (U at k = {gauge.certificate_k:g})",
                    gauge.certificate_U,
                    gauge.certificate_k,
                )
            )
        if (
            gauge.repeatability_sd is not None
            and gauge.repeatability_n is not None
            and gauge.repeatability_n >= 2
        ):
            lines.append(
                repeatability(
                    gauge.repeatability_sd,
                    gauge.repeatability_n,
                    f"repeatability (Type-1, n = {gauge.repeatability_n})",
                )
            )
    if zero_uncertainty is not None and math.isfinite(zero_uncertainty) and zero_uncertainty >= 0:
        lines.append(Contribution("zero", zero_uncertainty))
    return Budget(tuple(lines), unit) if lines else None


def evaluate(
    budget: Budget | Iterable[Contribution],
    *,
    k: float | None = None,
    confidence: float | None = None,
) -> BudgetResult:
    """Combine the budget (see the module); U at coverage ``k`` or at ``confidence`` (k is then
    Student's t at ν_eff truncated to a whole number, GUM G.4), else at k = 2."""
    if not isinstance(budget, Budget):
        budget = Budget(tuple(budget))
    if k is not None and confidence is not None:
        raise StationError("give a coverage factor k or a confidence, not both.")
    shares = _relative_squares(budget.contributions)
    largest = max(c.ui for c in budget.contributions)
    u_c = largest * math.sqrt(math.fsum(shares))
    nu_eff = welch_satterthwaite(budget.contributions)
    if confidence is not None:
        coverage = coverage_factor(check_confidence(confidence), nu_eff)
    else:
        coverage = check_coverage(DEFAULT_K if k is None else k)
    total = math.fsum(shares)
    lines = tuple(
        Line(c.name, c.u, c.sensitivity, c.ui, float(c.dof), share / total if total else 0.0)
        for c, share in zip(budget.contributions, shares, strict=True)
    )
    return BudgetResult(u_c, nu_eff, coverage, coverage * u_c, confidence, lines, budget.unit)


def _relative_squares(contributions: Sequence[Contribution]) -> list[float]:
    # (c_i u_i / max c u)²: the sums below are scale-free, so taking them relative to the largest
    # line keeps a budget in nanometres from underflowing its fourth powers (and one in
    # micro-inches written in metres from overflowing them).
    largest = max((c.ui for c in contributions), default=0.0)
    if largest == 0:
        return [0.0 for _ in contributions]
    return [(c.ui / largest) ** 2 for c in contributions]


def welch_satterthwaite(contributions: Iterable[Contribution]) -> float:
    """ν_eff = u_c⁴ / Σ (c_i u_i)⁴/ν_i; ∞ when every line with a share has ν = ∞ (or u_c = 0)."""
    items = list(contributions)
    squares = _relative_squares(items)
    variance = math.fsum(squares)
    denominator = math.fsum(
        square**2 / c.dof for c, square in zip(items, squares, strict=True) if math.isfinite(c.dof)
    )
    if denominator == 0 or variance == 0:
        return math.inf
    return variance**2 / denominator


def coverage_factor(confidence: float, nu_eff: float) -> float:
    """The two-sided coverage factor at ``confidence``: Student's t at ⌊ν_eff⌋ degrees of
    freedom (the normal quantile for ν_eff = ∞)."""
    from scipy import stats

    p = (1.0 + check_confidence(confidence)) / 2.0
    if math.isinf(nu_eff):
        return NormalDist().inv_cdf(p)
    return float(stats.t.ppf(p, math.floor(nu_eff)))


class Rule(StrEnum):
    """A decision rule (JCGM 106 §8): ``guarded`` acceptance shrinks the limits by U to accept
    and widens them by U to reject (ISO 14253-1, the default); ``simple`` acceptance compares
    the value with the limits themselves (up to 50 % false-accept risk at a limit)."""

    GUARDED = "guarded"
    SIMPLE = "simple"


class Outcome(StrEnum):
    """The verdict of a value against its limits."""

    PASS = "PASS"
    FAIL = "FAIL"
    INDETERMINATE = "INDETERMINATE"


@dataclass(frozen=True)
class Decision:
    """A ``value`` judged against ``lsl``/``usl`` (None: no limit on that side) by ``rule``:
    the ``verdict`` and the probability of conformance ``p_conformance`` with a normal
    measurement model, Φ((USL − y)/u_c) − Φ((LSL − y)/u_c)."""

    value: float
    verdict: Outcome
    p_conformance: float
    lsl: float | None
    usl: float | None
    rule: Rule


def check_limits(lsl: float | None, usl: float | None) -> None:
    """Refuse limits that cannot hold a value: none at all, not finite, or LSL ≥ USL."""
    if lsl is None and usl is None:
        raise StationError("no limits to decide against; give a lower limit, an upper or both.")
    for name, limit in (("LSL", lsl), ("USL", usl)):
        if limit is not None and not math.isfinite(limit):
            raise StationError(f"the {name} must be a finite number, not {limit!r}.")
    if lsl is not None and usl is not None and not lsl < usl:
        raise StationError(f"the LSL {lsl:g} is not below the USL {usl:g}; check the limits.")


def acceptance_zone(
    lsl: float | None, usl: float | None, U: float, rule: Rule = Rule.GUARDED
) -> tuple[float | None, float | None] | None:
    """The values a rule accepts: [LSL + U, USL − U] guarded, [LSL, USL] simple (None for a
    side without a limit); None when the guard bands leave nothing (2U ≥ USL − LSL)."""
    check_limits(lsl, usl)
    guard = U if Rule(rule) is Rule.GUARDED else 0.0
    low = None if lsl is None else lsl + guard
    high = None if usl is None else usl - guard
    if low is not None and high is not None and low > high:
        return None
    return low, high


def decide(
    value: float,
    lsl: float | None,
    usl: float | None,
    result: BudgetResult,
    rule: Rule | str = Rule.GUARDED,
) -> Decision:
    """Judge ``value`` against its limits with the evaluated budget ``result`` (its U for the
    guard band, its u_c for the probability of conformance).

    Guarded: PASS inside [LSL + U, USL − U], FAIL below LSL − U or above USL + U, otherwise
    INDETERMINATE. Simple: PASS inside [LSL, USL], otherwise FAIL.
    """
    rule = Rule(rule)
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise StationError(f"the value {value!r} to decide on is not a finite number.")
    check_limits(lsl, usl)
    guard = result.U if rule is Rule.GUARDED else 0.0
    below = lsl is not None and value < lsl - guard
    above = usl is not None and value > usl + guard
    inside = (lsl is None or value >= lsl + guard) and (usl is None or value <= usl - guard)
    if below or above:
        verdict = Outcome.FAIL
    elif inside:
        verdict = Outcome.PASS
    else:
        verdict = Outcome.INDETERMINATE if rule is Rule.GUARDED else Outcome.FAIL
    return Decision(value, verdict, p_conformance(value, lsl, usl, result.u_c), lsl, usl, rule)


def p_conformance(value: float, lsl: float | None, usl: float | None, u_c: float) -> float:
    """The probability that the true value lies within the limits, the measured ``value``
    being normal with standard deviation ``u_c`` (JCGM 106 §7.3); with u_c = 0, 1 inside and 0
    outside."""
    if u_c == 0:
        inside = (lsl is None or value >= lsl) and (usl is None or value <= usl)
        return 1.0 if inside else 0.0
    normal = NormalDist(value, u_c)
    upper = 1.0 if usl is None else normal.cdf(usl)
    lower = 0.0 if lsl is None else normal.cdf(lsl)
    return max(0.0, upper - lower)


@dataclass(frozen=True)
class ReadingDecisions:
    """Every reading of a channel judged against its limits by ``rule`` with one evaluated
    budget (:func:`judge_readings`): how many PASS, FAIL and INDETERMINATE, the cycles of the
    last two, and the ``zone`` the rule accepts (None when the guard bands leave nothing)."""

    rule: Rule
    U: float
    passed: int
    failed: int
    indeterminate: int
    cycles_failed: tuple[int, ...]
    cycles_indeterminate: tuple[int, ...]
    zone: tuple[float | None, float | None] | None

    def as_json(self) -> dict[str, Any]:
        """``{"rule", "U", "acceptance_zone", "pass", "fail", "indeterminate",
        "cycles_fail", "cycles_indeterminate"}``."""
        return {
            "rule": self.rule.value,
            "U": self.U,
            "acceptance_zone": None if self.zone is None else list(self.zone),
            "pass": self.passed,
            "fail": self.failed,
            "indeterminate": self.indeterminate,
            "cycles_fail": list(self.cycles_failed),
            "cycles_indeterminate": list(self.cycles_indeterminate),
        }


def judge_readings(
    values: Sequence[float] | np.ndarray,
    cycles: Sequence[int] | np.ndarray,
    lsl: float | None,
    usl: float | None,
    result: BudgetResult,
    rule: Rule | str = Rule.GUARDED,
) -> ReadingDecisions:
    """:func:`decide` on every reading (labelled by ``cycles``) at once, with the same
    ``result``: the figure a report shows is the figure the decisions took."""
    rule = Rule(rule)
    check_limits(lsl, usl)
    array = np.asarray(values, dtype=float)
    labels = np.asarray(cycles, dtype=np.int64)
    guard = result.U if rule is Rule.GUARDED else 0.0
    fail = np.zeros(array.shape, bool)
    inside = np.ones(array.shape, bool)
    if lsl is not None:
        fail |= array < lsl - guard
        inside &= array >= lsl + guard
    if usl is not None:
        fail |= array > usl + guard
        inside &= array <= usl - guard
    passed = inside & ~fail
    if rule is Rule.SIMPLE:
        fail = ~passed
    between = ~passed & ~fail
    return ReadingDecisions(
        rule=rule,
        U=result.U,
        passed=int(passed.sum()),
        failed=int(fail.sum()),
        indeterminate=int(between.sum()),
        cycles_failed=tuple(int(c) for c in labels[fail]),
        cycles_indeterminate=tuple(int(c) for c in labels[between]),
        zone=acceptance_zone(lsl, usl, result.U, rule),
    )
