"""The capability verdict as a word that states its confidence: provisional below the minimum
count, settled only when the confidence bound says so, never contradicted by the figures beside it.

* **The decision** (issue 20). A Cpk from 30 readings is an estimate: Table 2-1's 1.17 is only
  known to lie between 0.90 and 1.44 (one-sided 95 % bounds, Bissell 1990), and a robot whose
  true Cpk is exactly 1.0 shows a Cpk of 1 or more in about half of its 30-reading sessions. So
  the verdict is

  - ``CAPABLE`` when the one-sided lower bound (``Capability.cpk_lower``) reaches the threshold,
  - ``NOT CAPABLE`` when the one-sided upper bound (``Capability.cpk_upper``) is below it,
  - ``INCONCLUSIVE`` otherwise, with the readings that would settle it at the observed Cpk
    (:func:`station.analysis.capability.readings_needed`).

  Each bound is at the analysis' confidence (95 % unless set), so a robot exactly at the
  threshold is called CAPABLE (or NOT CAPABLE) in about 5 % of sessions. Bissell's bound is a
  normal approximation: simulated at 30 readings a robot of true Cpk 1.0 far from centre is
  called CAPABLE in 5.3 % of sessions, a centred one in 2.3 % (``tests/analysis/test_verdict.py``).
  The report's own point-estimate rule (capable when Cpk >= threshold) is shown beside the
  word, never instead of it: ``by the report's rule: capable, Cpk 1.17 >= 1``.
* **Provisional.** Below the procedure's minimum count of readings (25 for the report's
  procedures, ``--min-n`` for a CSV) the verdict is ``PROVISIONAL: 9 of 25``, whatever the
  bounds say.
* **Unrounded comparison.** Every comparison uses the unrounded figures, and :func:`cpk_text`
  shows as many decimals as it takes for a shown figure to sit on the same side of the threshold
  as the unrounded one: a Cpk of 0.9996 is shown as "0.9996 < 1", never as "1.00".

:func:`judge_verdict` gives the :class:`Verdict`; :func:`verdict_line` the one line the
dashboard, the summary and the reports print.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

from station.analysis.capability import Capability, readings_needed

#: The decision rule's name in the JSON document: one-sided Bissell bounds against the threshold.
DECISION_RULE = "bissell-one-sided-bounds"

CAPABLE, NOT_CAPABLE, INCONCLUSIVE = "CAPABLE", "NOT CAPABLE", "INCONCLUSIVE"
PROVISIONAL, UNDEFINED = "PROVISIONAL", "UNDEFINED"

#: The minimum count of readings for a final verdict when the procedure names none (the
#: report's "25 to 30 cycles", §2.6).
DEFAULT_MIN_N = 25

#: The fewest decimals an index is shown with (the report's precision).
INDEX_DECIMALS = 2
#: The most decimals :func:`cpk_text` will use before it gives up and shows the figure in full.
MAX_DECIMALS = 12


@dataclass(frozen=True)
class Verdict:
    """The verdict of one channel.

    ``word`` is CAPABLE, NOT CAPABLE, INCONCLUSIVE, PROVISIONAL or UNDEFINED; ``label`` adds the
    count to a provisional word ("PROVISIONAL: 9 of 25"). ``rule_capable`` is the report's own
    point-estimate rule, the unrounded Cpk ≥ threshold (None without a Cpk), kept for a
    provisional verdict too: it is where the figures point so far. ``lower`` and ``upper`` are
    the one-sided bounds at ``confidence`` the decision weighed; ``readings_needed`` is how many
    readings would settle an INCONCLUSIVE verdict at the observed Cpk (None otherwise, or when
    no count would). ``cpk_text`` is the Cpk as shown (see :func:`cpk_text`), ``relation``
    ``>=`` or ``<`` (the report's rule); ``text`` is the whole line without "VERDICT:".
    """

    word: str
    label: str
    rule_capable: bool | None
    provisional: bool
    n: int
    min_n: int
    cpk: float | None
    cpk_text: str
    threshold: float
    relation: str
    text: str
    lower: float | None = None
    upper: float | None = None
    confidence: float = 0.95
    readings_needed: int | None = None
    rule: str = DECISION_RULE

    @property
    def rule_text(self) -> str:
        """The report's point-estimate rule in words: ``by the report's rule: capable, Cpk 1.17
        >= 1`` (empty without a Cpk)."""
        if self.rule_capable is None:
            return ""
        said = "capable" if self.rule_capable else "not capable"
        comparison = f"Cpk {self.cpk_text} {self.relation} {self.threshold:g}"
        return f"by the report's rule: {said}, {comparison}"


def confidence_text(confidence: float) -> str:
    """A confidence level as a percentage: 0.95 -> "95%", 0.975 -> "97.5%"."""
    return f"{confidence * 100:.10g}%"


def cpk_text(cpk: float, threshold: float, decimals: int = INDEX_DECIMALS) -> str:
    """``cpk`` with the fewest decimals (at least ``decimals``) that keep the shown figure on the
    same side of ``threshold`` as the unrounded one: 1.17 → "1.17", 0.9996 → "0.9996" against 1.

    A figure that rounds onto the wrong side even at ``MAX_DECIMALS`` is shown in full
    (``repr``), which is exact.
    """
    above = cpk >= threshold
    for places in range(decimals, MAX_DECIMALS + 1):
        shown = f"{cpk:.{places}f}"
        if (float(shown) >= threshold) == above:
            return shown
    return repr(float(cpk))


def judge_verdict(capability: Capability, min_n: int = DEFAULT_MIN_N) -> Verdict:
    """The verdict of a channel's capability (see the module docstring): PROVISIONAL while
    ``capability.n < min_n`` (and a Cpk exists); else CAPABLE when ``capability.cpk_lower``
    reaches the threshold, NOT CAPABLE when ``capability.cpk_upper`` is below it, INCONCLUSIVE
    between; UNDEFINED without a Cpk, with the capability's reason."""
    if min_n < 0:
        raise ValueError("the minimum count cannot be negative")
    n, cpk, threshold = capability.n, capability.cpk, capability.threshold
    threshold_text = f"{threshold:g}"
    if cpk is None or not math.isfinite(cpk):
        reason = capability.message or "no verdict"
        return Verdict(
            word=UNDEFINED,
            label=UNDEFINED,
            rule_capable=None,
            provisional=False,
            n=n,
            min_n=min_n,
            cpk=None,
            cpk_text="undefined",
            threshold=threshold,
            relation="",
            text=f"{UNDEFINED} ({reason})",
            confidence=capability.confidence,
        )
    rule_capable = cpk >= threshold
    shown = cpk_text(cpk, threshold)
    relation = ">=" if rule_capable else "<"
    lower, upper = capability.cpk_lower, capability.cpk_upper
    settled: dict[str, Any] = {
        "n": n,
        "min_n": min_n,
        "cpk": cpk,
        "cpk_text": shown,
        "threshold": threshold,
        "relation": relation,
        "rule_capable": rule_capable,
        "lower": lower,
        "upper": upper,
        "confidence": capability.confidence,
    }
    if n < min_n:
        label = f"{PROVISIONAL}: {n} of {min_n}"
        text = (
            f"{label} readings (Cpk {shown} {relation} {threshold_text} so far; "
            f"{min_n - n} more before a verdict)"
        )
        return Verdict(word=PROVISIONAL, label=label, provisional=True, text=text, **settled)
    level = f"Bissell {confidence_text(capability.confidence)}"
    if lower is not None and lower >= threshold:
        word, needed = CAPABLE, None
        reason = f"{level} lower bound {cpk_text(lower, threshold)} >= {threshold_text}"
    elif upper is not None and upper < threshold:
        word, needed = NOT_CAPABLE, None
        reason = f"{level} upper bound {cpk_text(upper, threshold)} < {threshold_text}"
    else:
        word = INCONCLUSIVE
        needed = readings_needed(cpk, threshold, capability.confidence)
        bounds = f"{_bound_text(lower, threshold)} to {_bound_text(upper, threshold)}"
        reason = f"{level} bounds {bounds} straddle {threshold_text}: " + (
            f"{needed} readings would settle it at this Cpk"
            if needed is not None
            else "no count of readings would settle it at this Cpk"
        )
    verdict = Verdict(
        word=word,
        label=word,
        provisional=False,
        text="",
        readings_needed=needed,
        **settled,
    )
    text = f"{word} (Cpk {shown}; {reason}; {verdict.rule_text})"
    return replace(verdict, text=text)


def _bound_text(bound: float | None, threshold: float) -> str:
    return "undefined" if bound is None else cpk_text(bound, threshold)


def verdict_line(capability: Capability, min_n: int = DEFAULT_MIN_N) -> str:
    """The verdict line every front end prints: ``VERDICT: INCONCLUSIVE (Cpk 1.17, 95% bounds
    0.90 to 1.44 straddle 1; ...; by the report's rule: capable, Cpk 1.17 >= 1)``,
    ``VERDICT: PROVISIONAL: 9 of 25 readings (...)``, ``VERDICT: UNDEFINED (reason)``."""
    return f"VERDICT: {judge_verdict(capability, min_n).text}"
