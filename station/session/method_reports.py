"""What the gauge check, per-joint troubleshooting and gain schedule read and write beyond the
plain readings (their analysis kinds are in :mod:`station.method_kinds`):

* :func:`record_gauge_check` files a finished gauge check in the gauge register, under the gauge
  id typed at its input step (``gauge``, ``calibration_due``);
* :func:`table_joint_inputs` reads a per-joint CSV (``joint,x,y,z[,lever]``);
* :func:`gain_inputs` reads the positions and gains typed in a gain-schedule session (input
  events with a number ``q`` and other numbers), and :func:`gain_schedule_lines` is the fit's
  report block.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from station.errors import StationError
from station.session.gauge_register import record_check, register_path
from station.session.tables import require_columns

if TYPE_CHECKING:
    from station.analysis.gain_schedule import GainSchedule
    from station.analysis.gauge_check import GaugeCheck
    from station.session.model import Session

JOINT_COLUMNS = ("joint", "x", "y", "z")


def _input_values(session: Session, *fields: str) -> dict[str, Any]:
    """The values of the last input event holding all ``fields``."""
    for event in reversed(session.input_events):
        values = event.get("values") or {}
        if all(name in values for name in fields):
            return dict(values)
    return {}


def record_gauge_check(
    session: Session,
    study: GaugeCheck,
    *,
    register: Path | None = None,
    port: Mapping[str, str] | None = None,
) -> dict[str, Any]:
    """File a finished gauge-check session's study in the gauge register under the gauge id
    typed at its input step, dated by the session's creation (its calibration due date too,
    when typed; ``port``: the line and device channel the gauge was read on). Returns the
    entry; StationError without a gauge id."""
    values = _input_values(session, "reference", "tolerance")
    gauge = str(values.get("gauge") or "").strip()
    if not gauge:
        raise StationError(f"{session.path}: the gauge check names no gauge id to register.")
    when = dt.date.fromisoformat(str(session.created)[:10])
    return record_check(
        register or register_path(),
        gauge,
        study,
        when=when,
        calibration_due=values.get("calibration_due") or None,
        session=session.session_id,
        port=port,
    )


def table_joint_inputs(table: Any) -> tuple[Any, dict[str, Any], dict[int, float] | None]:
    """Joint labels, readings x, y, z and lever arms (an optional ``lever`` column, one value
    per joint) of a CSV with columns ``joint,x,y,z[,lever]``."""
    columns = require_columns(table, JOINT_COLUMNS, "a per-joint table")
    readings = {axis: columns[axis] for axis in ("x", "y", "z")}
    if "lever" not in {name.lower() for name in table.channels}:
        return columns["joint"], readings, None
    lever = require_columns(table, ("lever",), "the lever arms")["lever"]
    levers: dict[int, float] = {}
    for number, value in zip(columns["joint"], lever, strict=True):
        if number != np.round(number):
            break  # analyze_joints says what is wrong with the joint column
        known = levers.setdefault(int(number), float(value))
        if known != value:
            raise StationError(
                f"{table.path}: joint {int(number)} has two lever arms ({known:g} and "
                f"{value:g}); give one per joint."
            )
    return columns["joint"], readings, levers


def gain_schedule_lines(schedule: GainSchedule) -> list[str]:
    """The schedule's report section (without plots: those are the command's)."""
    lines = [f"GAIN SCHEDULE: {len(schedule.positions)} positions"]
    for name, fit in schedule.fits.items():
        loo = "n/a" if fit.loo_rmse is None else f"{fit.loo_rmse:.4g}"
        shown = "".join(ch if ch.isprintable() else "?" for ch in name)
        lines.append(f"  {shown}: order {fit.order} ({fit.chosen_by}), leave-one-out RMSE {loo}")
        terms = [f"a{i} = {c:+.6g}" for i, c in enumerate(fit.coefficients)]
        lines.extend("    " + "   ".join(terms[i : i + 4]) for i in range(0, len(terms), 4))
        lines.extend(f"    WARNING: {warning}" for warning in fit.warnings)
    return lines


def gain_inputs(
    events: Sequence[Mapping[str, Any]],
) -> tuple[list[float], dict[str, list[float]]]:
    """Positions and gains typed in a gain-schedule session: its input ``events`` with a
    number ``q`` and other numbers (a position typed again replaces the earlier one)."""
    by_position: dict[float, dict[str, float]] = {}
    for event in events:
        values = event.get("values") or {}
        q = values.get("q")
        gains = {
            k: float(v)
            for k, v in values.items()
            if k != "q" and isinstance(v, int | float) and not isinstance(v, bool)
        }
        if isinstance(q, int | float) and not isinstance(q, bool) and gains:
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
