"""The gain-schedule method: the position ``q`` and the gains typed at each position (or the
columns of a CSV), fitted against the position. It judges no readings: its report is the fit
alone (no capability analysis)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from station.analysis.gain_schedule import GainSchedule, fit_schedule
from station.errors import StationError
from station.methods.contract import Judgement, Method, MethodInputs
from station.methods.sessions import is_number
from station.methods.text import fitted
from station.procedures import AnalysisNeeds
from station.session.tables import require_columns


def gain_inputs(
    events: Sequence[Mapping[str, Any]],
) -> tuple[list[float], dict[str, list[float]]]:
    """Positions and gains typed in a gain-schedule session: its input ``events`` with a
    number ``q`` and other numbers (a position typed again replaces the earlier one)."""
    by_position: dict[float, dict[str, float]] = {}
    for event in events:
        values = event.get("values") or {}
        q = values.get("q")
        gains = {k: float(v) for k, v in values.items() if k != "q" and is_number(v)}
        if is_number(q) and gains:
            by_position[float(q)] = gains
    if not by_position:
        raise StationError("the session has no tuned gains typed in yet.")
    # The gains in the order they were first typed (the procedure's field order).
    names = list(dict.fromkeys(name for gains in by_position.values() for name in gains))
    positions = sorted(by_position)
    missing = [(q, n) for q in positions for n in names if n not in by_position[q]]
    if missing:
        q, name = missing[0]
        raise StationError(f"position {q:g} has no {name} typed in.")
    return positions, {n: [by_position[q][n] for q in positions] for n in names}


def gain_schedule_lines(schedule: GainSchedule) -> list[str]:
    """The schedule's report section (without plots: those are ``station gains``')."""
    lines = [f"GAIN SCHEDULE: {len(schedule.positions)} positions"]
    for name, fit in schedule.fits.items():
        loo = "n/a" if fit.loo_rmse is None else f"{fit.loo_rmse:.4g}"
        shown = "".join(ch if ch.isprintable() else "?" for ch in name)
        lines.append(f"  {shown}: order {fit.order} ({fit.chosen_by}), leave-one-out RMSE {loo}")
        terms = [f"a{i} = {c:+.6g}" for i, c in enumerate(fit.coefficients)]
        lines.extend("    " + "   ".join(terms[i : i + 4]) for i in range(0, len(terms), 4))
        lines.extend(f"    WARNING: {warning}" for warning in fit.warnings)
    return lines


class GainScheduleMethod(Method):
    """Gains tuned per position, fitted against the position."""

    name = "gain_schedule"
    title = "GAIN SCHEDULE REPORT"
    reads_columns_by_name = True
    needs = AnalysisNeeds(
        numbers=("q",),
        more_numbers=1,
        numbers_words="an input step with a number field 'q' (the position) and one number "
        "field per gain",
        limits=False,
    )
    options = ("order",)

    def batch(self, inputs: MethodInputs) -> Judgement:
        """The fit of each gain against q (``order``: a fixed order, else chosen)."""
        positions: Any
        gains: Mapping[str, Any]
        if inputs.table is not None:
            table = inputs.table
            q = require_columns(table, ("q",), "a gains table")["q"]
            gains = {n: v for n, v in table.channels.items() if n.lower() != "q"}
            if not gains:
                raise StationError(f"{table.path}: no gain columns beside q; add one per gain.")
            positions = q
        else:
            positions, gains = gain_inputs(inputs.input_events)
        schedule = fit_schedule(positions, gains, inputs.option("order") or "auto")
        return Judgement(None, schedule, (fitted(gain_schedule_lines(schedule), inputs.width),))

    def json(self, result: Any) -> dict[str, Any]:
        """The fit of each gain (at the document's top level)."""
        return result.as_json()

    def count(self, result: Any) -> str:
        """``5 positions``."""
        return f"{len(result.positions)} positions"


METHOD = GainScheduleMethod()
