"""The rest of the report's method as analysis kinds: gauge check, per-joint troubleshooting and
the gain schedule, from a session file or from a CSV table.

For each kind, the same four things the analysis-kind registry asks of every kind:

* **batch** from a session (:func:`gauge_check_from_session`, :func:`joints_from_session`,
  :func:`gain_schedule_from_session`) or from plain arrays (the CSV tables of
  ``station analyze``);
* **text** sections (:func:`gauge_check_lines`, :func:`joints_lines`, :func:`gain_schedule_lines`);
* the **JSON** document (:func:`gauge_check_document`, :func:`joints_document`,
  :func:`gain_schedule_document`);
* the **count** of what the session measured (:func:`method_count`).

What each reads from a session:

* ``gauge_check``: the accepted readings of the procedure's (first) channel, and the input step
  whose fields are ``reference`` and ``tolerance`` (plus ``gauge`` and ``calibration_due``,
  which :func:`record_gauge_check` files in the gauge register); the resolution from the header.
* ``joint_troubleshooting``: the accepted readings of x, y, z, each labelled by the repetition
  of the ``repeat`` block it was captured in (the event's ``placement``: the joint number), and
  the lever arm typed per joint (an input field ``lever`` in the same repetition).
* ``gain_schedule``: every input event whose values hold a number ``q`` and other numbers (the
  gains), one per position.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from station.errors import StationError

if TYPE_CHECKING:
    from station.analysis.gain_schedule import GainSchedule
    from station.analysis.gauge_check import GaugeCheck
    from station.analysis.joints import JointsAnalysis
    from station.session.model import Session

METHOD_KINDS: tuple[str, ...] = ("gauge_check", "joint_troubleshooting", "gain_schedule")
JOINT_COLUMNS = ("joint", "x", "y", "z")


# --------------------------------------------------------------------------------------------
# Gauge check


def gauge_check_document(
    values: Sequence[float] | Any,
    reference: float,
    tolerance: float,
    resolution: float | None = None,
    *,
    unit: str = "",
) -> dict[str, Any]:
    """``{"procedure": "gauge_check", "gauge_check": {cg, cgk, bias, bias_p,
    resolution_ratio, capable, ...}}`` of repeated readings of a reference."""
    from station.analysis.gauge_check import gauge_check

    study = gauge_check(values, reference, tolerance, resolution=resolution, unit=unit)
    return {"procedure": "gauge_check", "gauge_check": study.as_json()}


def gauge_check_lines(study: GaugeCheck) -> list[str]:
    """The gauge check's report section."""
    return study.lines()


def _input_values(session: Session, *fields: str) -> dict[str, Any]:
    """The values of the last input event holding all ``fields``."""
    for event in reversed(session.input_events):
        values = event.get("values") or {}
        if all(name in values for name in fields):
            return dict(values)
    return {}


def gauge_check_from_session(session: Session) -> GaugeCheck:
    """The Type-1 study of a gauge-check session: its accepted readings against the reference
    and tolerance typed at its input step. StationError when either is missing."""
    from station.analysis.gauge_check import gauge_check

    values = _input_values(session, "reference", "tolerance")
    reference, tolerance = values.get("reference"), values.get("tolerance")
    if not isinstance(reference, int | float) or not isinstance(tolerance, int | float):
        raise StationError(
            f"{session.path}: the session has no reference size and tolerance typed in yet."
        )
    channels = session.channel_values()
    channel = next((c for c in session.channels if len(channels.get(c, ()))), None)
    if channel is None:
        raise StationError(f"{session.path}: the session has no accepted readings yet.")
    resolution = session.header.get("resolution")
    return gauge_check(
        channels[channel],
        float(reference),
        float(tolerance),
        resolution=float(resolution) if isinstance(resolution, int | float) else None,
        unit=session.unit,
    )


def record_gauge_check(
    session: Session, study: GaugeCheck, *, register: Path | None = None
) -> dict[str, Any]:
    """File a finished gauge-check session's study in the gauge register under the gauge id
    typed at its input step, dated by the session's creation (its calibration due date too,
    when typed). Returns the entry; StationError without a gauge id."""
    from station.session.gauge_register import record_check, register_path

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
    )


# --------------------------------------------------------------------------------------------
# Per-joint troubleshooting


def joints_document(
    joint: Sequence[int] | Any,
    readings: Mapping[str, Any],
    lever_arms: Mapping[int, float] | None = None,
) -> dict[str, Any]:
    """``{"procedure": "joint_troubleshooting", "joints": [...], "suspect": J | null, ...}``."""
    from station.analysis.joints import analyze_joints

    result = analyze_joints(joint, readings, lever_arms=lever_arms)
    return {"procedure": "joint_troubleshooting", **result.as_json()}


def joints_lines(result: JointsAnalysis, unit: str = "") -> list[str]:
    """The per-joint report section."""
    return result.lines(unit)


def table_joint_inputs(table: Any) -> tuple[Any, dict[str, Any], dict[int, float] | None]:
    """Joint labels, readings x, y, z and lever arms (an optional ``lever`` column, one value
    per joint) of a CSV with columns ``joint,x,y,z[,lever]``."""
    import numpy as np

    from station.session.tables import require_columns

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


def joints_from_session(session: Session) -> JointsAnalysis:
    """The per-joint analysis of a troubleshooting session: readings grouped by the repeat
    block's repetition (the joint), lever arms from the ``lever`` inputs when every joint has
    one. StationError without readings at a joint yet."""
    import numpy as np

    from station.analysis.joints import analyze_joints

    numbers = [n for n in session.accepted_cycles if session.cycles[n].placement is not None]
    numbers = [n for n in numbers if {"x", "y", "z"} <= set(session.cycles[n].readings)]
    if not numbers:
        raise StationError(f"{session.path}: the session has no accepted returns of a joint yet.")
    joints = np.asarray([session.cycles[n].placement for n in numbers])
    readings = {
        axis: np.asarray([session.cycles[n].readings[axis].value for n in numbers])
        for axis in ("x", "y", "z")
    }
    levers: dict[int, float] = {}
    for event in session.input_events:
        value, placement = (event.get("values") or {}).get("lever"), event.get("placement")
        if isinstance(placement, int) and isinstance(value, int | float) and value > 0:
            levers[placement] = float(value)
    complete = set(joints.tolist()) <= set(levers)
    return analyze_joints(joints, readings, lever_arms=levers if complete else None)


# --------------------------------------------------------------------------------------------
# Gain schedule


def gain_schedule_document(schedule: GainSchedule, source: str = "") -> dict[str, Any]:
    """``{"procedure": "gain_schedule", "positions", "domain", "gains": {NAME: {order,
    coefficients, loo_rmse, residuals, ...}}}``."""
    return {"procedure": "gain_schedule", "source": source, **schedule.as_json()}


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


def session_gain_inputs(session: Session) -> tuple[list[float], dict[str, list[float]]]:
    """Positions and gains typed in a gain-schedule session (input events with a number ``q``
    and other numbers; a position typed again replaces the earlier one)."""
    by_position: dict[float, dict[str, float]] = {}
    for event in session.input_events:
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
        raise StationError(f"{session.path}: the session has no tuned gains typed in yet.")
    # The gains in the order they were first typed (the procedure's field order).
    names = list(dict.fromkeys(name for gains in by_position.values() for name in gains))
    positions = sorted(by_position)
    missing = [(q, n) for q in positions for n in names if n not in by_position[q]]
    if missing:
        q, name = missing[0]
        raise StationError(f"{session.path}: position {q:g} has no {name} typed in.")
    return positions, {n: [by_position[q][n] for q in positions] for n in names}


def gain_schedule_from_session(session: Session, order: int | str = "auto") -> GainSchedule:
    """The fitted schedule of a gain-schedule session."""
    from station.analysis.gain_schedule import fit_schedule

    positions, gains = session_gain_inputs(session)
    return fit_schedule(positions, gains, order)  # type: ignore[arg-type]


# --------------------------------------------------------------------------------------------
# Counts


def method_count(kind: str, result: Any) -> str:
    """``30 readings``, ``3 joints`` or ``9 positions``: what the session measured."""
    if kind == "gauge_check":
        return f"{result.n} readings"
    if kind == "joint_troubleshooting":
        return f"{len(result.joints)} joints"
    if kind == "gain_schedule":
        return f"{len(result.positions)} positions"
    raise ValueError(f"{kind!r} is not one of {', '.join(METHOD_KINDS)}")
