"""The budget file: a measurement-uncertainty budget written as TOML, read into a
:class:`~station.analysis.uncertainty.Budget`.

::

    unit = "in"            # optional: the unit of the output (shown beside U)
    confidence = 0.95      # optional: k from Student's t at ν_eff; or k = 2; not both

    [[input]]
    name = "certificate"
    expanded = 0.00005     # U ...
    k = 2                  # ... at this coverage factor: u = U/k

    [[input]]
    name = "resolution"
    half_width = 0.00005   # a ...
    distribution = "rectangular"   # ... rectangular | triangular | arcsine | normal

    [[input]]
    name = "repeatability"
    readings = [0.1002, 0.1001, 0.1003]   # Type A: u = s/√n on n − 1 degrees of freedom

    [[input]]
    name = "zero"
    u = 0.00002            # a standard uncertainty as it is
    sensitivity = 1        # optional, default 1
    dof = 9                # optional, default ∞ (not with readings: they give their own)

Each input gives exactly one of ``u``, ``half_width`` (+ ``distribution``), ``expanded`` (+ ``k``)
or ``readings``. A ``normal`` half-width may carry its own ``k`` (else 2). Anything else is
refused with one sentence naming the file and the input.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from station.analysis.uncertainty import (
    Budget,
    Contribution,
    check_confidence,
    check_coverage,
    from_expanded,
    from_half_width,
    type_a,
)
from station.errors import StationError

_TOP_KEYS = frozenset({"unit", "k", "confidence", "input", "title"})
_INPUT_KEYS = frozenset(
    {"name", "u", "half_width", "distribution", "expanded", "k", "readings", "sensitivity", "dof"}
)
_FORMS = ("u", "half_width", "expanded", "readings")
"""The ways an input states its uncertainty; exactly one per input."""


@dataclass(frozen=True)
class BudgetFile:
    """A budget file as read: the budget, and the file's own ``k`` or ``confidence`` (None
    when it names neither)."""

    budget: Budget
    k: float | None
    confidence: float | None
    title: str = ""


def parse_budget(text: str, source: str = "budget") -> BudgetFile:
    """Read the TOML ``text`` of a budget file; ``source`` (its name) starts every error."""
    try:
        table = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise StationError(f"{source} is not valid TOML ({error}).") from None
    except RecursionError:
        raise StationError(f"{source} nests arrays or tables too deeply to read.") from None
    try:
        return _budget_file(table)
    except StationError as error:
        raise StationError(f"{source}: {error.message}") from None


def _budget_file(table: Mapping[str, Any]) -> BudgetFile:
    unknown = sorted(set(table) - _TOP_KEYS)
    if unknown:
        raise StationError(
            f"unknown key {unknown[0]!r}; a budget file holds {', '.join(sorted(_TOP_KEYS))}."
        )
    unit = table.get("unit", "")
    title = table.get("title", "")
    for key, value in (("unit", unit), ("title", title)):
        if not isinstance(value, str):
            raise StationError(f"'{key}' must be text, not {value!r}.")
    if "k" in table and "confidence" in table:
        raise StationError("give 'k' or 'confidence', not both.")
    k = check_coverage(table["k"], "'k'") if "k" in table else None
    confidence = (
        check_confidence(table["confidence"], "'confidence'") if "confidence" in table else None
    )
    inputs = table.get("input")
    if not isinstance(inputs, list) or not inputs:
        raise StationError("no [[input]] tables; give one per contribution to the budget.")
    contributions = tuple(_contribution(entry, index) for index, entry in enumerate(inputs, 1))
    return BudgetFile(Budget(contributions, unit), k, confidence, title)


def _contribution(entry: object, index: int) -> Contribution:
    if not isinstance(entry, Mapping):
        raise StationError(f"input {index} is not a table; write each as [[input]].")
    name = entry.get("name")
    if not isinstance(name, str) or not name.strip():
        raise StationError(f"input {index} has no 'name'; give each input a name.")
    label = f"input {name!r}"
    unknown = sorted(set(entry) - _INPUT_KEYS)
    if unknown:
        raise StationError(
            f"{label}: unknown key {unknown[0]!r}; an input holds {', '.join(sorted(_INPUT_KEYS))}."
        )
    forms = [form for form in _FORMS if form in entry]
    if len(forms) != 1:
        given = " and ".join(forms) if forms else "none"
        raise StationError(f"{label}: give exactly one of {', '.join(_FORMS)} (given: {given}).")
    sensitivity = entry.get("sensitivity", 1.0)
    dof = entry.get("dof", math.inf)
    form = forms[0]
    if "k" in entry and form not in ("expanded", "half_width"):
        raise StationError(f"{label}: 'k' goes with 'expanded' or a normal 'half_width'.")
    if "distribution" in entry and form != "half_width":
        raise StationError(f"{label}: 'distribution' goes with 'half_width'.")
    if form == "u":
        return Contribution(name, entry["u"], sensitivity, dof)
    if form == "half_width":
        if "distribution" not in entry:
            raise StationError(
                f"{label}: a half_width needs its 'distribution' "
                "(rectangular, triangular, arcsine or normal)."
            )
        return from_half_width(
            name, entry["half_width"], entry["distribution"], sensitivity, dof, entry.get("k")
        )
    if form == "expanded":
        if "k" not in entry:
            raise StationError(f"{label}: an expanded uncertainty needs its coverage factor 'k'.")
        return from_expanded(name, entry["expanded"], entry["k"], sensitivity, dof)
    if "dof" in entry:
        raise StationError(f"{label}: readings give their own dof (n − 1); leave 'dof' out.")
    readings = entry["readings"]
    if not isinstance(readings, list):
        raise StationError(f"{label}: readings must be a list of numbers, not {readings!r}.")
    return type_a(name, readings, sensitivity)
