"""The rest of the report's method as analysis kinds of the registry (:mod:`station.verdicts`):
the gauge check (a Type-1 study before a verdict), per-joint troubleshooting (§1.2, §2.8) and
the gain schedule (Part IV, §4.3).

Each kind reads a session file or a CSV table through :class:`~station.verdicts.KindInputs`:

* ``gauge_check``: the readings of the one channel, the reference size and the tolerance
  (typed at the session's input step, or ``options`` ``reference`` / ``tolerance`` from
  ``station analyze``), the resolution and unit of the config. Its :class:`Analysis` is the
  readings' capability against x_m ± 0.1·T at 1.33, so that the verdict every front end shows
  *is* the study's: Cp = 0.2·T / 6s = Cg and Cpk = (0.1·T − |x̄ − x_m|) / 3s = Cgk. A finished
  session files its study in the gauge register (:func:`file_gauge_check`).
* ``joint_troubleshooting``: the x, y, z readings labelled by the joint (the repeat block's
  repetition in a session, the ``joint`` column of a CSV), and the lever arm typed per joint
  (a ``lever`` input or column). Its :class:`Analysis` is the returns of every joint pooled.
* ``gain_schedule``: the position ``q`` and the gains typed at each position (or the columns
  of a CSV). It judges no readings: its report is the fit alone (no :class:`Analysis`).

Imported by :mod:`station.verdicts` (at its end), which is all it takes to register them.
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from station.analysis.capability import SpecLimits
from station.analysis.gain_schedule import GainSchedule, fit_schedule
from station.analysis.gauge_check import CAPABLE_AT, GaugeCheck, gauge_check
from station.analysis.joints import JointsAnalysis, analyze_joints
from station.analysis.summary import Analysis, analyze
from station.errors import StationError
from station.procedures import analysis_needs
from station.session import method_reports
from station.session.gauge_register import filed_line, register_path
from station.session.tables import require_columns
from station.verdicts import (
    AnalysisKind,
    Judgement,
    KindInputs,
    LiveCycles,
    load_session_source,
    register,
    report_session,
)

# -- typed values ------------------------------------------------------------------------------


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def typed_values(events: Sequence[Mapping[str, Any]], *fields: str) -> dict[str, Any]:
    """The values of the last input event holding all ``fields`` (empty when none does)."""
    for event in reversed(events):
        values = event.get("values") or {}
        if all(name in values for name in fields):
            return dict(values)
    return {}


def _readings(inputs: KindInputs, channels: Sequence[str]) -> dict[str, np.ndarray]:
    return {name: np.asarray(inputs.channels[name], dtype=float) for name in channels}


def _pooled(inputs: KindInputs, channels: Sequence[str], config: Any) -> Analysis:
    """The capability analysis of ``channels`` (the report's statistics), without the
    repeatability hints: a kind's own block says what its figures point to."""
    cycles = None if inputs.cycles is None else {c: inputs.cycles[c] for c in channels}
    times = None
    if inputs.times is not None and all(c in inputs.times for c in channels):
        times = {c: inputs.times[c] for c in channels}
    analysis = analyze(
        _readings(inputs, channels),
        config,
        excluded_cycles=inputs.excluded_cycles,
        cycles=cycles,
        times=times,
    )
    return replace(analysis, given_hints=())


def fitted(lines: Sequence[str], width: int) -> tuple[str, ...]:
    """The report lines, each longer than ``width`` wrapped under its own indent (the TUI's
    summary column is narrower than the 80 columns of a printed report)."""
    out: list[str] = []
    for line in lines:
        if len(line) <= width:
            out.append(line)
            continue
        indent = " " * (len(line) - len(line.lstrip()))
        out.extend(
            textwrap.wrap(
                line.strip(),
                width=max(width, 40),
                initial_indent=indent,
                subsequent_indent=indent + "  ",
            )
        )
    return tuple(out)


# -- gauge check -------------------------------------------------------------------------------


def _gauge_check(inputs: KindInputs) -> Judgement:
    options = inputs.options or {}
    typed = typed_values(inputs.input_events, "reference", "tolerance")
    reference = options.get("reference", typed.get("reference"))
    tolerance = options.get("tolerance", typed.get("tolerance"))
    if not _is_number(reference) or not _is_number(tolerance):
        if inputs.header is None:
            raise StationError(
                "--procedure gauge_check on a CSV needs --reference X_M (the reference's size) "
                "and --tolerance T (the tolerance the gauge will judge)."
            )
        raise StationError("the session has no reference size and tolerance typed in yet.")
    if not tolerance > 0:
        raise StationError(f"the tolerance T {tolerance:g} must be greater than 0.")
    channels = [name for name, values in inputs.channels.items() if len(values)]
    if inputs.header is None and len(inputs.channels) != 1:
        raise StationError(
            f"a gauge-check table has one column of readings; it has {', '.join(inputs.channels)}."
        )
    if not channels:
        raise StationError("the session has no accepted readings of the reference yet.")
    channel = channels[0]
    config = inputs.config
    study = gauge_check(
        inputs.channels[channel],
        float(reference),
        float(tolerance),
        resolution=config.resolution,
        unit=config.unit,
    )
    # Limits x_m ± 0.1·T at 1.33: the capability the verdict shows is the study's Cg and Cgk.
    band = 0.1 * float(tolerance)
    limits = SpecLimits(lsl=reference - band, usl=reference + band, nominal=float(reference))
    judged = replace(
        config,
        limits={channel: limits},
        default_limits=None,
        threshold=CAPABLE_AT,
        nominal={channel: float(reference)},
    )
    analysis = _pooled(inputs, [channel], judged)
    notes = [
        f"  The verdict above judges {channel} against x_m ± 0.1·T at {CAPABLE_AT}:",
        "  its Cp is Cg and its Cpk is Cgk.",
    ]
    if inputs.header is not None and inputs.header.get("session"):
        notes.append(f"  {filed_line(str(inputs.header['session']))}")
    return Judgement(analysis, study, (fitted([*study.lines(), *notes], inputs.width),))


def file_gauge_check(path: Path, *, register_file: Path | None = None) -> list[str]:
    """File the study of the finished gauge-check session at ``path`` in the gauge register
    (under the gauge id typed at its input step, with the line and device channel it was read
    on); the sentence to show. StationError when it cannot."""
    source = load_session_source(path)
    report = report_session(source)
    study: GaugeCheck = report.result
    session = source.session
    channel = next(iter(source.channels))
    port = None
    for recorded in (session.header.get("instruments") or {}).get("ports") or ():
        for device, mapped in dict(recorded.get("map") or {}).items():
            if mapped == channel and port is None:
                port = {"url": str(recorded.get("url")), "device": str(device)}
    target = register_file or register_path()
    entry = method_reports.record_gauge_check(session, study, register=target, port=port)
    gauge = typed_values(session.input_events, "reference", "tolerance").get("gauge")
    return [
        f"Gauge check of {gauge}: {entry['result']} on {entry['date']} "
        f"(Cg {_index(study.cg)}, Cgk {_index(study.cgk)}); filed in the gauge register {target}."
    ]


def _index(value: float | None) -> str:
    return "undefined" if value is None else f"{value:.2f}"


# -- per-joint troubleshooting -----------------------------------------------------------------


def _joint_inputs(
    inputs: KindInputs,
) -> tuple[np.ndarray, dict[str, np.ndarray], dict[int, float] | None]:
    """Joint of each return, readings x, y, z and lever arms (None unless every joint has
    one), from the session's repeat block or the CSV's columns."""
    if inputs.table is not None:
        joints, readings, levers = method_reports.table_joint_inputs(inputs.table)
        return np.asarray(joints), readings, levers
    placements, readings, _ = inputs.accuracy_inputs()
    levers: dict[int, float] = {}
    for event in inputs.input_events:
        value, placement = (event.get("values") or {}).get("lever"), event.get("placement")
        if isinstance(placement, int) and _is_number(value) and value > 0:
            levers[placement] = float(value)
    complete = set(np.asarray(placements).tolist()) <= set(levers)
    return np.asarray(placements), readings, levers if complete else None


def _joint_troubleshooting(inputs: KindInputs) -> Judgement:
    joints, readings, levers = _joint_inputs(inputs)
    result = analyze_joints(joints, readings, lever_arms=levers)
    axes = [axis for axis in ("x", "y", "z") if axis in inputs.channels]
    if inputs.table is not None:
        # The CSV's columns: the readings as the kind reads them (not the joint column).
        inputs = replace(inputs, channels=readings, cycles=None, times=None)
        axes = list(readings)
    analysis = _pooled(inputs, axes, inputs.config) if axes else None
    return Judgement(analysis, result, (fitted(result.lines(inputs.config.unit), inputs.width),))


# -- gain schedule -----------------------------------------------------------------------------


def _gain_inputs(inputs: KindInputs) -> tuple[Any, dict[str, Any]]:
    if inputs.table is not None:
        table = inputs.table
        q = require_columns(table, ("q",), "a gains table")["q"]
        gains = {n: v for n, v in table.channels.items() if n.lower() != "q"}
        if not gains:
            raise StationError(f"{table.path}: no gain columns beside q; add one per gain.")
        return q, gains
    return method_reports.gain_inputs(inputs.input_events)


def _gain_schedule(inputs: KindInputs) -> Judgement:
    positions, gains = _gain_inputs(inputs)
    order = (inputs.options or {}).get("order", "auto")
    schedule = fit_schedule(positions, gains, order)
    lines = method_reports.gain_schedule_lines(schedule)
    return Judgement(None, schedule, (fitted(lines, inputs.width),))


# -- the kinds ---------------------------------------------------------------------------------


register(
    AnalysisKind(
        name="gauge_check",
        title="GAUGE CHECK REPORT",
        batch=_gauge_check,
        live=LiveCycles,
        needs=analysis_needs("gauge_check"),
        json_key="gauge_check",
        json=GaugeCheck.as_json,
        count=lambda study: f"{study.n} readings",
        finished=lambda path: file_gauge_check(path),
    )
)
register(
    AnalysisKind(
        name="joint_troubleshooting",
        title="PER-JOINT TROUBLESHOOTING REPORT",
        batch=_joint_troubleshooting,
        live=LiveCycles,
        needs=analysis_needs("joint_troubleshooting"),
        json=JointsAnalysis.as_json,
        count=lambda result: f"{len(result.joints)} joints",
    )
)
register(
    AnalysisKind(
        name="gain_schedule",
        title="GAIN SCHEDULE REPORT",
        batch=_gain_schedule,
        live=LiveCycles,
        needs=analysis_needs("gain_schedule"),
        json=GainSchedule.as_json,
        count=lambda schedule: f"{len(schedule.positions)} positions",
    )
)
