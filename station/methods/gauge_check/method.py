"""The gauge-check method: the readings of its one channel judged as a Type-1 study
(:mod:`station.analysis.gauge_check`) against the reference size and tolerance typed at the
session's input step (or ``reference`` / ``tolerance`` from ``station analyze``).

Its capability analysis is the readings' against x_m ± 0.1·T at 1.33, so that the verdict every
front end shows *is* the study's: Cp = 0.2·T / 6s = Cg and Cpk = (0.1·T − |x̄ − x_m|) / 3s =
Cgk. A finished session files its study in the gauge register under the gauge id typed in it,
with the line and device channel it was read on.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from station.analysis.capability import SpecLimits
from station.analysis.gauge_check import CAPABLE_AT, GaugeCheck, gauge_check
from station.errors import StationError
from station.methods.capability import capability_of
from station.methods.contract import DemoDisplay, DemoRig, Judgement, Method, MethodInputs
from station.methods.sessions import (
    is_number,
    load_session_source,
    session_inputs,
    typed_values,
)
from station.methods.text import fitted
from station.procedures import AnalysisNeeds
from station.session.gauge_register import filed_line, port_of, record_check, register_path

if TYPE_CHECKING:
    from station.instruments.simulator import GaugeSpec
    from station.session.model import Session

FIELDS = ("reference", "tolerance")
"""The number fields its input step must have."""
DEMO_REFERENCE = 0.1
DEMO_TOLERANCE = 0.004
DEMO_GAUGE = "DEMO-IND-1"


def _index(value: float | None) -> str:
    return "undefined" if value is None else f"{value:.2f}"


def _bench_display(model: Any, placement: int | None, unit: str) -> DemoDisplay:
    """What the simulated bench's labels say: the indicator's id, the block's size."""
    return DemoDisplay(
        label="Gauge block and indicator (simulated)",
        text=f"indicator {DEMO_GAUGE}, block {model.reference:g} {unit}, "
        f"tolerance {DEMO_TOLERANCE:g} {unit}",
        values={"gauge": DEMO_GAUGE, "reference": model.reference, "tolerance": DEMO_TOLERANCE},
        hint="type the indicator's id, the block's size and the tolerance shown above",
    )


class GaugeCheckMethod(Method):
    """A Type-1 study of one indicator on one reference."""

    name = "gauge_check"
    title = "GAUGE CHECK REPORT"
    needs = AnalysisNeeds(
        facet="counts",
        facet_words="a cycles step (the repeated readings)",
        numbers=FIELDS,
        numbers_words="an input step with number fields 'reference' and 'tolerance'",
        limits=False,
    )
    json_key = "gauge_check"
    options = FIELDS
    files_in_register = True
    demo_words = "an indicator over a surface plate and a gauge block"

    def study(self, inputs: MethodInputs) -> tuple[str, GaugeCheck]:
        """The channel read and its Type-1 study (StationError naming what is missing)."""
        typed = typed_values(inputs.input_events, *FIELDS)
        reference = inputs.option("reference")
        tolerance = inputs.option("tolerance")
        reference = typed.get("reference") if reference is None else reference
        tolerance = typed.get("tolerance") if tolerance is None else tolerance
        if not is_number(reference) or not is_number(tolerance):
            if inputs.session is None:
                raise StationError(
                    "--procedure gauge_check on a CSV needs --reference X_M (the reference's "
                    "size) and --tolerance T (the tolerance the gauge will judge)."
                )
            raise StationError("the session has no reference size and tolerance typed in yet.")
        if not tolerance > 0:
            raise StationError(f"the tolerance T {tolerance:g} must be greater than 0.")
        channels = [name for name, values in inputs.channels.items() if len(values)]
        if inputs.session is None and len(inputs.channels) != 1:
            raise StationError(
                "a gauge-check table has one column of readings; it has "
                f"{', '.join(inputs.channels)}."
            )
        if not channels:
            raise StationError("the session has no accepted readings of the reference yet.")
        channel = channels[0]
        config = inputs.config
        return channel, gauge_check(
            inputs.channels[channel],
            float(reference),
            float(tolerance),
            resolution=config.resolution,
            unit=config.unit,
        )

    def batch(self, inputs: MethodInputs) -> Judgement:
        """The study, and its verdict as capability against x_m ± 0.1·T at 1.33."""
        channel, study = self.study(inputs)
        band = 0.1 * study.tolerance
        limits = SpecLimits(
            lsl=study.reference - band, usl=study.reference + band, nominal=study.reference
        )
        judged = replace(
            inputs.config,
            limits={channel: limits},
            default_limits=None,
            threshold=CAPABLE_AT,
            nominal={channel: study.reference},
        )
        analysis = capability_of(inputs, [channel], judged)
        notes = [
            f"  The verdict above judges {channel} against x_m ± 0.1·T at {CAPABLE_AT}:",
            "  its Cp is Cg and its Cpk is Cgk.",
        ]
        header = inputs.header
        if header is not None and header.get("session"):
            notes.append(f"  {filed_line(str(header['session']))}")
        return Judgement(analysis, study, (fitted([*study.lines(), *notes], inputs.width),))

    def json(self, result: Any) -> dict[str, Any]:
        """Cg, Cgk, the bias and its test, the resolution against T."""
        return result.as_json()

    def count(self, result: Any) -> str:
        """``25 readings``."""
        return f"{result.n} readings"

    def file_in_register(self, path: Path, register: Path | None = None) -> list[str]:
        """File the study of the finished session at ``path`` in the gauge register under the
        gauge id typed at its input step, dated by the session's creation (its calibration due
        date too, when typed), with the line and device channel it was read on."""
        source = load_session_source(path)
        session = source.session
        channel, study = self.study(session_inputs(source))
        target = register or register_path()
        entry = record_gauge_check(
            session, study, register=target, port=port_of(session.header, channel)
        )
        gauge = typed_values(session.input_events, *FIELDS).get("gauge")
        return [
            f"Gauge check of {gauge}: {entry['result']} on {entry['date']} "
            f"(Cg {_index(study.cg)}, Cgk {_index(study.cgk)}); filed in the gauge register "
            f"{target}."
        ]

    def demo_rig(self, gauge: GaugeSpec, seed: int, *, stroke_points: int) -> DemoRig:
        """One indicator over a surface plate (rest 0, where it is zeroed), then a gauge block
        of 0.1 in re-seated for every reading."""
        from station.instruments.gauge_bench import GaugeBenchModel

        return DemoRig(
            GaugeBenchModel(DEMO_REFERENCE, gauge=gauge),
            "a simulated indicator over a surface plate and a 0.1 in gauge block (seeded)",
            channel_map={"1": "x"},
            display=_bench_display,
        )


def record_gauge_check(
    session: Session,
    study: GaugeCheck,
    *,
    register: Path | None = None,
    port: dict[str, str] | None = None,
) -> dict[str, Any]:
    """File a finished gauge-check session's study in the gauge register under the gauge id
    typed at its input step, dated by the session's creation (its calibration due date too,
    when typed; ``port``: the line and device channel the gauge was read on). Returns the
    entry; StationError without a gauge id."""
    values = typed_values(session.input_events, *FIELDS)
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


METHOD = GaugeCheckMethod()
