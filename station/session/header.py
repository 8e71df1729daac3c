"""The session header, typed: what line 1 of a session file says and what it implies.

The engine writes the header from a set-up; the analysis of a running session and the batch
analysis of its file both read their settings through :func:`analysis_config`, so the two agree.
This module is the one place that turns a header mapping into limits and an analysis
configuration (the session package never reaches up into the engine for it).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from station.analysis.capability import SpecLimits
from station.analysis.phases import DEFAULT_FREEZE_AFTER, baseline_from_json
from station.analysis.summary import AnalysisConfig
from station.analysis.uncertainty import GaugeRecord
from station.analysis.verdict import DEFAULT_MIN_N
from station.analysis.zeros import ZeroDraw


def header_limits(header: Mapping[str, Any]) -> dict[str, SpecLimits]:
    """The spec limits a session header records, as a :class:`SpecLimits` per channel it
    measures; a channel with neither an LSL nor a USL has none."""
    channels = header.get("channels")
    return {
        str(channel): SpecLimits(
            lsl=spec.get("lsl"), usl=spec.get("usl"), nominal=spec.get("nominal")
        )
        for channel, spec in dict(header.get("limits") or {}).items()
        if (channels is None or channel in channels)
        and isinstance(spec, Mapping)
        and (spec.get("lsl") is not None or spec.get("usl") is not None)
    }


def zero_uncertainties(zeroes: Iterable[Mapping[str, Any]]) -> dict[str, float]:
    """Each channel's zero uncertainty from a session's ``zero`` events (the last one of a
    channel is the zero in force; an old event without ``uncertainty`` says nothing)."""
    found: dict[str, float] = {}
    for event in zeroes:
        for channel, spec in dict(event.get("channels") or {}).items():
            value = spec.get("uncertainty") if isinstance(spec, Mapping) else None
            if isinstance(value, int | float) and not isinstance(value, bool) and value >= 0:
                found[str(channel)] = float(value)
            else:
                found.pop(str(channel), None)
    return found


def _figure(value: object) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        return None
    return float(value)


def gauge_records(header: Mapping[str, Any]) -> dict[str, GaugeRecord]:
    """Per channel, what the gauge register said of its gauge when the session began (the
    header's ``gauge_checks`` snapshot): the certificate's U and k, the latest Type-1 check's
    SD and count. A session's budget rests on that snapshot, never on the register of today,
    so a report printed later gives the same U. Channels with nothing usable are left out."""
    found: dict[str, GaugeRecord] = {}
    for channel, status in dict(header.get("gauge_checks") or {}).items():
        if not isinstance(status, Mapping):
            continue
        certificate = status.get("certificate")
        expanded = k = None
        if isinstance(certificate, Mapping):
            expanded, k = _figure(certificate.get("U")), _figure(certificate.get("k"))
            if expanded is None or expanded < 0 or k is None or k <= 0:
                expanded = k = None
        sd, n = _figure(status.get("sd")), status.get("n")
        count = n if isinstance(n, int) and not isinstance(n, bool) and n >= 2 else None
        if sd is None or sd < 0 or count is None:
            sd = count = None
        if expanded is None and sd is None:
            continue
        found[str(channel)] = GaugeRecord(
            gauge=str(status.get("gauge") or ""),
            certificate_U=expanded,
            certificate_k=k,
            repeatability_sd=sd,
            repeatability_n=count,
        )
    return found


def _zero_draw(spec: object) -> ZeroDraw:
    """One channel's entry of a ``zero`` event as a :class:`ZeroDraw` (weight 0 until readings
    are counted under it). A gauge's own zero command takes its reading of that moment: m = 1."""
    if not isinstance(spec, Mapping) or spec.get("method") == "device":
        return ZeroDraw(readings=1, within_sd=None, weight=0)
    values = [
        float(v)
        for v in spec.get("values") or ()
        if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
    ]
    count = spec.get("n")
    m = count if isinstance(count, int) and not isinstance(count, bool) and count >= 1 else None
    if m is None:
        m = len(values) or 1
    within = None
    if len(values) >= 2:
        mean = sum(values) / len(values)
        within = math.sqrt(sum((v - mean) ** 2 for v in values) / (len(values) - 1))
    return ZeroDraw(readings=m, within_sd=within, weight=0)


def zero_draws(events: Iterable[Mapping[str, Any]]) -> dict[str, tuple[ZeroDraw, ...]]:
    """Per channel, the zeros a session's readings were taken under, in order, each weighted by
    the ``reading`` events (or streamed ``samples`` events) of the channel that followed it
    before the channel's next zero; a zero no reading followed is left out. A channel the
    session never zeroed has no entry: its readings are the gauge's own values."""
    found: dict[str, list[ZeroDraw]] = {}
    for event in events:
        kind = event.get("type")
        if kind == "zero":
            for channel, spec in dict(event.get("channels") or {}).items():
                found.setdefault(str(channel), []).append(_zero_draw(spec))
        elif kind in ("reading", "samples"):
            named = event.get("channels")
            channels = named if isinstance(named, dict | list | tuple) else ()
            for channel in channels:
                draws = found.get(str(channel))
                if draws:
                    last = draws[-1]
                    draws[-1] = ZeroDraw(last.readings, last.within_sd, last.weight + 1)
    return {
        channel: used
        for channel, draws in found.items()
        if (used := tuple(d for d in draws if d.weight > 0))
    }


def _draws_in_force(zeroes: Iterable[Mapping[str, Any]]) -> dict[str, tuple[ZeroDraw, ...]]:
    """Per channel, the zero in force (its last ``zero`` event) as the one draw its readings
    carry: what the zero events alone can say, without the readings that weight each zero."""
    found: dict[str, tuple[ZeroDraw, ...]] = {}
    for event in zeroes:
        for channel, spec in dict(event.get("channels") or {}).items():
            draw = _zero_draw(spec)
            found[str(channel)] = (ZeroDraw(draw.readings, draw.within_sd, 1),)
    return found


def analysis_config(
    header: Mapping[str, Any],
    zeroes: Iterable[Mapping[str, Any]] = (),
    events: Iterable[Mapping[str, Any]] | None = None,
) -> AnalysisConfig:
    """The :class:`AnalysisConfig` a session header implies: its limits, resolution, unit, rule
    set and threshold (single readings, subgroup 1), the gauges' register snapshot (for the
    measurement budget); ``zeroes`` (the session's ``zero`` events) give each channel's zero
    uncertainty; ``events`` (all of them, when known) weight each zero by the readings taken
    under it, else the zero in force is the one draw (the running engine's view)."""
    zeroes = list(zeroes)
    resolution = header.get("resolution")
    # Streamed strokes are judged one straightness per stroke: their verdict is final from the
    # strokes the procedure's stroke step asks for, not from its count of cycles.
    minimum = header.get("strokes_min", header.get("cycles_min"))
    freeze = header.get("freeze_after")
    return AnalysisConfig(
        limits=header_limits(header),
        resolution=float(resolution) if isinstance(resolution, int | float) else None,
        unit=str(header.get("unit") or ""),
        rule_set=str(header.get("rules") or "report"),
        threshold=float(header.get("threshold") or 1.0),
        min_n=minimum if isinstance(minimum, int) and minimum >= 0 else DEFAULT_MIN_N,
        freeze_after=freeze if isinstance(freeze, int) and freeze >= 2 else DEFAULT_FREEZE_AFTER,
        baseline=baseline_from_json(header.get("baseline")),
        zero_uncertainty=zero_uncertainties(zeroes),
        zero_draws=_draws_in_force(zeroes) if events is None else zero_draws(events),
        gauges=gauge_records(header),
        decision_rule=str(header.get("decision_rule") or "guarded"),
    )


@dataclass(frozen=True)
class SessionHeader:
    """The fields of a session header that the engine and the analyses read."""

    procedure_id: str
    procedure_version: str
    procedure_sha256: str
    analysis: str | None
    """The method the procedure declared when the session began (None in old files)."""
    robot: str
    operator: str
    unit: str
    resolution: float | None
    channels: tuple[str, ...]
    trigger: str
    ports: tuple[Mapping[str, Any], ...]
    cycles_target: int | None
    placements_target: int | None
    strokes_target: int | None
    rules: str
    threshold: float
    deadband: float | None
    """The travel deadband the stroke split used (linearity), in the session's unit."""
    raw: Mapping[str, Any]

    @classmethod
    def from_mapping(cls, header: Mapping[str, Any]) -> SessionHeader:
        """Read a header mapping (line 1 of a session file)."""
        procedure = dict(header.get("procedure") or {})
        instruments = dict(header.get("instruments") or {})

        def count(key: str) -> int | None:
            value = header.get(key)
            return value if isinstance(value, int) and not isinstance(value, bool) else None

        resolution = header.get("resolution")
        deadband = header.get("deadband")
        return cls(
            procedure_id=str(procedure.get("id") or ""),
            procedure_version=str(procedure.get("version") or ""),
            procedure_sha256=str(procedure.get("sha256") or ""),
            analysis=str(procedure["analysis"]) if procedure.get("analysis") else None,
            robot=str(header.get("robot") or ""),
            operator=str(header.get("operator") or ""),
            unit=str(header.get("unit") or ""),
            resolution=float(resolution) if isinstance(resolution, int | float) else None,
            channels=tuple(str(c) for c in header.get("channels") or ()),
            trigger=str(instruments.get("trigger") or "poll"),
            ports=tuple(dict(p) for p in instruments.get("ports") or () if isinstance(p, Mapping)),
            cycles_target=count("cycles_target"),
            placements_target=count("placements_target"),
            strokes_target=count("strokes_target"),
            rules=str(header.get("rules") or "report"),
            threshold=float(header.get("threshold") or 1.0),
            deadband=float(deadband) if isinstance(deadband, int | float) else None,
            raw=header,
        )

    @property
    def limits(self) -> dict[str, SpecLimits]:
        """Spec limits per channel (:func:`header_limits`)."""
        return header_limits(self.raw)

    @property
    def config(self) -> AnalysisConfig:
        """The analysis configuration (:func:`analysis_config`)."""
        return analysis_config(self.raw)
