"""The capability verdict as a word: provisional below the minimum count, never contradicted by
the Cpk shown beside it.

* **Provisional.** Below the procedure's minimum count of readings (25 for the report's
  procedures, ``--min-n`` for a CSV) the verdict is ``PROVISIONAL: 9 of 25``: with 9 readings a
  Cpk of 1.3 is only known to lie somewhere above about 0.7 (see ``Capability.cpk_lower``), so
  "CAPABLE" would promise more than the data hold.
* **Unrounded comparison.** The verdict compares the unrounded Cpk with the threshold, and
  :func:`cpk_text` shows as many decimals as it takes for the shown figure to sit on the same
  side of the threshold: a Cpk of 0.9996 is shown as "0.9996 < 1", never as "1.00 ... NOT
  CAPABLE".

:func:`judge_verdict` gives the :class:`Verdict`; :func:`verdict_line` the one line the
dashboard, the summary and the reports print.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from station.analysis.capability import Capability

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

    ``word`` is CAPABLE, NOT CAPABLE, PROVISIONAL or UNDEFINED; ``label`` adds the count to a
    provisional word ("PROVISIONAL: 9 of 25"). ``capable`` is the unrounded comparison
    Cpk ≥ threshold (None without a Cpk), kept for a provisional verdict too: it is where the
    figures point so far. ``cpk_text`` is the Cpk as shown (see :func:`cpk_text`), ``relation``
    ``>=`` or ``<``; ``text`` is the whole line without the "VERDICT:" prefix.
    """

    word: str
    label: str
    capable: bool | None
    provisional: bool
    n: int
    min_n: int
    cpk: float | None
    cpk_text: str
    threshold: float
    relation: str
    text: str


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
    """The verdict of a channel's capability: PROVISIONAL while ``capability.n < min_n`` (and a
    Cpk exists), else CAPABLE / NOT CAPABLE from the unrounded Cpk, else UNDEFINED with the
    capability's reason."""
    if min_n < 0:
        raise ValueError("the minimum count cannot be negative")
    n, cpk, threshold = capability.n, capability.cpk, capability.threshold
    threshold_text = f"{threshold:g}"
    if cpk is None or not math.isfinite(cpk):
        reason = capability.message or "no verdict"
        return Verdict(
            word="UNDEFINED",
            label="UNDEFINED",
            capable=None,
            provisional=False,
            n=n,
            min_n=min_n,
            cpk=None,
            cpk_text="undefined",
            threshold=threshold,
            relation="",
            text=f"UNDEFINED ({reason})",
        )
    capable = cpk >= threshold
    shown = cpk_text(cpk, threshold)
    relation = ">=" if capable else "<"
    comparison = f"Cpk {shown} {relation} {threshold_text}"
    if n < min_n:
        label = f"PROVISIONAL: {n} of {min_n}"
        text = (
            f"{label} readings (Cpk {shown} {relation} {threshold_text} so far; "
            f"{min_n - n} more before a verdict)"
        )
        return Verdict(
            word="PROVISIONAL",
            label=label,
            capable=capable,
            provisional=True,
            n=n,
            min_n=min_n,
            cpk=cpk,
            cpk_text=shown,
            threshold=threshold,
            relation=relation,
            text=text,
        )
    word = "CAPABLE" if capable else "NOT CAPABLE"
    return Verdict(
        word=word,
        label=word,
        capable=capable,
        provisional=False,
        n=n,
        min_n=min_n,
        cpk=cpk,
        cpk_text=shown,
        threshold=threshold,
        relation=relation,
        text=f"{word} ({comparison})",
    )


def verdict_line(capability: Capability, min_n: int = DEFAULT_MIN_N) -> str:
    """The verdict line every front end prints: ``VERDICT: CAPABLE (Cpk 1.17 >= 1)``,
    ``VERDICT: PROVISIONAL: 9 of 25 readings (...)``, ``VERDICT: UNDEFINED (reason)``."""
    return f"VERDICT: {judge_verdict(capability, min_n).text}"
