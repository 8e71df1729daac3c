"""The gauge linearity and bias study as a method: the readings of one indicator at each
reference master (a placement of the procedure's repeated block, its size typed there; or the
``reference,value`` rows of a CSV) judged by :func:`~station.methods.gauge_linearity.study.
linearity_study`, with the tolerance and the process variation typed at the session's input
step (or ``--tolerance`` / ``--process-variation``). It judges no readings by capability: its
verdict is its own (ACCEPTABLE, NOT ACCEPTABLE or INCONCLUSIVE). A finished study files itself
in the gauge register, beside the gauge's Type-1 checks."""

from __future__ import annotations

import csv
import datetime as dt
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from station.analysis.diagnostics import two_digits
from station.errors import StationError
from station.methods.contract import (
    Chart,
    ChartKit,
    DemoDisplay,
    DemoRig,
    Judgement,
    Method,
    MethodInputs,
    MethodVerdict,
    PlacementWords,
)
from station.methods.gauge_linearity.live import live_about_masters
from station.methods.gauge_linearity.study import (
    ALPHA,
    BIAS_SHARE,
    MASTERS_MIN,
    LinearityStudy,
    linearity_study,
)
from station.methods.live import LiveAboutGroups
from station.methods.sessions import (
    is_number,
    load_session_source,
    placement_readings,
    session_inputs,
    session_source,
    typed_values,
)
from station.methods.tables import export_comments, number
from station.methods.text import fitted
from station.procedures import AnalysisNeeds
from station.session.gauge_register import port_of, record_study, register_path
from station.session.tables import require_columns
from station.text import format_figure

if TYPE_CHECKING:
    from _typeshed import SupportsWrite

    from station.analysis.summary import AnalysisConfig
    from station.instruments.simulator import GaugeSpec
    from station.session.model import Session

NAME = "gauge_linearity"
TABLE_COLUMNS = ("reference", "value")
"""The columns of its CSV table: one row per reading, with the size of the master read."""
DEMO_REFERENCES = (0.1, 0.3, 0.5, 0.7, 0.9)
"""The demo bench's gauge blocks (in): a 1 in indicator's travel, end to end."""
DEMO_SLOPE = 0.0008
"""The demo indicator's linearity error: its bias grows by 0.0008 in per inch of size."""
DEMO_GAUGE = "DEMO-IND-1"
DEMO_TOLERANCE = 0.004


def _typed(inputs: MethodInputs, name: str) -> float | None:
    """The command line's ``name``, else the session's typed one (None: neither)."""
    given = inputs.option(name)
    if given is None:
        given = typed_values(inputs.input_events, name).get(name)
    return float(given) if is_number(given) else None


def _readings(inputs: MethodInputs) -> tuple[np.ndarray, np.ndarray]:
    """The size of the master of each reading, and the reading (a session's or a CSV's)."""
    if inputs.table is not None:
        columns = require_columns(inputs.table, TABLE_COLUMNS, "a gauge linearity table")
        return columns["reference"], columns["value"]
    assert inputs.session is not None
    channel = next((name for name, values in inputs.channels.items() if len(values)), None)
    if channel is None:
        raise StationError("the session has no accepted readings of a reference master yet.")
    placements, readings, typed = placement_readings(
        inputs.session, (channel,), what="a reference master"
    )
    sizes = []
    for placement in placements.tolist():
        size = (typed.get(placement) or {}).get("reference")
        if not is_number(size):
            raise StationError(f"master {placement} has no reference size typed in yet.")
        sizes.append(float(size))
    return np.asarray(sizes), readings[channel]


def bias_chart(study: LinearityStudy, references: Any, values: Any, kit: ChartKit) -> Any:
    """Every reading's bias against its master's size, each master's mean bias, the fitted
    line with its 95 % confidence band, bias = 0, and the bias allowed (with a tolerance)."""
    from scipy import stats  # on first use: see station/README.md

    x = np.asarray(references, dtype=float)
    y = np.asarray(values, dtype=float) - x
    unit = kit.label(study.unit)
    suffix = f" ({unit})" if unit else ""
    figure = kit.figure()
    axes = figure.add_subplot()
    axes.scatter(x, y, s=10, color=kit.point, alpha=0.5, label="bias of a reading")
    sizes = [m.reference for m in study.masters]
    axes.scatter(
        sizes, [m.bias for m in study.masters], s=40, color=kit.centre, marker="D",
        label="mean bias of a master",
    )  # fmt: skip
    grid = np.linspace(min(sizes), max(sizes), 101)
    line = study.intercept + study.slope * grid
    x_bar = float(x.mean())
    sxx = float(np.sum((x - x_bar) ** 2))
    half = (
        float(stats.t.ppf(1 - ALPHA / 2, study.n - 2))
        * study.s
        * np.sqrt(1.0 / study.n + (grid - x_bar) ** 2 / sxx)
    )
    axes.plot(grid, line, color=kit.centre, label=f"fitted bias (slope {two_digits(study.slope)})")
    axes.fill_between(grid, line - half, line + half, color=kit.centre, alpha=0.15, label="95 %")
    axes.axhline(0.0, color="grey", linestyle=":", label="bias = 0")
    if study.allowed_bias is not None:
        for sign in (-1, 1):
            axes.axhline(
                sign * study.allowed_bias,
                color=kit.limit,
                linestyle="--",
                label=f"allowed ±{kit.number(study.allowed_bias, signed=False)}"
                if sign > 0
                else None,
            )
    axes.set_title(f"Bias against the reference size: {study.verdict}")
    axes.set_xlabel("reference size" + suffix)
    axes.set_ylabel("bias" + suffix)
    kit.legend(axes)
    return figure


def _master_display(model: Any, placement: int | None, unit: str) -> DemoDisplay | None:
    """What the simulated bench's label says: the master under the spindle, and its size."""
    if placement is None:
        return DemoDisplay(
            label="Indicator on the bench (simulated)",
            text=f"indicator {DEMO_GAUGE}, tolerance {DEMO_TOLERANCE:g} {unit}",
            values={"gauge": DEMO_GAUGE, "tolerance": DEMO_TOLERANCE},
            hint="type the indicator's id and the tolerance shown above",
        )
    size = model.references[min(placement, len(model.references)) - 1]
    return DemoDisplay(
        label="Reference master (simulated)",
        text=f"master {placement}: {size:g} {unit}",
        values={"reference": size},
        hint="type the master's size shown above",
    )


class GaugeLinearity(Method):
    """A linearity and bias study of one indicator over its travel."""

    name = NAME
    title = "GAUGE LINEARITY AND BIAS REPORT"
    reads_columns_by_name = True
    needs = AnalysisNeeds(
        facet="counts",
        facet_in_block=True,
        facet_words="a repeat block (one per reference master) holding a cycles step",
        numbers=("reference",),
        numbers_words="an input step with a number field 'reference' (the master's size)",
        limits=False,
    )
    json_key = NAME
    options = ("tolerance", "process_variation")
    export_layout = "wide"
    drift_chart = False
    files_in_register = True
    placement_words = PlacementWords(
        label="Masters",
        noun="reference masters",
        hint=f"reference masters spanning the range; AIAG asks for {MASTERS_MIN} or more "
        "({low} to {target})",
        too_few="Give at least 1 reference master (AIAG asks for 5 or more).",
    )
    demo_words = "an indicator over a surface plate and five gauge blocks"

    def live(
        self, config: AnalysisConfig, channels: Sequence[str], header: Mapping[str, Any]
    ) -> LiveAboutGroups:
        """The readings about their own master's mean."""
        return live_about_masters(config, channels, header)

    def study(self, inputs: MethodInputs) -> LinearityStudy:
        """The study of ``inputs`` (StationError naming what is missing)."""
        references, values = _readings(inputs)
        rule = dict((inputs.header or {}).get(NAME) or {})
        share = rule.get("bias_share", BIAS_SHARE)
        return linearity_study(
            references,
            values,
            process_variation=_typed(inputs, "process_variation"),
            tolerance=_typed(inputs, "tolerance"),
            share=float(share) if is_number(share) else BIAS_SHARE,
            resolution=inputs.config.resolution,
            unit=inputs.config.unit,
        )

    def batch(self, inputs: MethodInputs) -> Judgement:
        """The study and its verdict (no capability analysis)."""
        study = self.study(inputs)
        verdict = MethodVerdict(study.verdict, study.sentence, study.acceptable)
        return Judgement(None, study, (fitted(study.lines(), inputs.width),), verdict)

    def json(self, result: Any) -> dict[str, Any]:
        """The study's figures (the regression, the biases, the verdict)."""
        return result.as_json()

    def count(self, result: Any) -> str:
        """``5 masters``."""
        return f"{len(result.masters)} masters"

    def header_fields(self, fields: Mapping[str, Any]) -> dict[str, Any]:
        """The decision rule the session's verdict takes (kept with it: a later station with
        another rule judges the file as it was judged)."""
        return {NAME: {"alpha": ALPHA, "bias_share": BIAS_SHARE}}

    def charts(self, inputs: MethodInputs, judgement: Judgement, kit: ChartKit) -> Iterator[Chart]:
        """The bias against the reference size, with the fitted line and its band."""
        references, values = _readings(inputs)
        yield (
            "bias-reference",
            "Bias against the reference size",
            bias_chart(judgement.result, references, values, kit),
        )

    def write_wide(self, session: Session, out: SupportsWrite[str]) -> int:
        """``cycle,reference,value``: each accepted reading with its master's size."""
        references, values = _readings(session_inputs(session_source(session)))
        numbers = [n for n in session.accepted_cycles if session.cycles[n].placement is not None]
        export_comments(session, out)
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(("cycle", *TABLE_COLUMNS))
        for cycle, size, value in zip(numbers, references, values, strict=True):
            writer.writerow((cycle, number(size), number(value)))
        return len(numbers)

    def file_in_register(self, path: Path, register: Path | None = None) -> list[str]:
        """File the study under the gauge id typed in the session, beside its checks."""
        source = load_session_source(path)
        session = source.session
        study = self.study(session_inputs(source))
        typed = typed_values(session.input_events, "gauge")
        gauge = str(typed.get("gauge") or "").strip()
        if not gauge:
            raise StationError(f"{session.path}: the study names no gauge id to register.")
        target = register or register_path()
        date = dt.date.fromisoformat(str(session.created)[:10]).isoformat()
        entry = record_study(
            target,
            gauge,
            NAME,
            {
                "date": date,
                "result": study.verdict.lower(),
                "summary": f"slope {two_digits(study.slope)}, average bias "
                + format_figure(study.average_bias, study.resolution, unit=study.unit),
                "slope": study.slope,
                "intercept": study.intercept,
                "r2": study.r2,
                "average_bias": study.average_bias,
                "pct_linearity": study.pct_linearity,
                "linearity": study.linearity,
                "references": [m.reference for m in study.masters],
                "n": study.n,
                "tolerance": study.tolerance,
                "session": session.session_id,
            },
            calibration_due=typed.get("calibration_due") or None,
            port=port_of(session.header, next(iter(source.channels), "x")),
        )
        return [
            f"Gauge linearity study of {gauge}: {study.verdict} on {entry['date']} (slope "
            f"{two_digits(study.slope)}, %linearity {study.pct_linearity:.3g} %); filed in the "
            f"gauge register {target}."
        ]

    def demo_rig(self, gauge: GaugeSpec, seed: int, *, stroke_points: int) -> DemoRig:
        """An indicator of 1 in travel over a surface plate and five gauge blocks of 0.1 to
        0.9 in, twelve seatings each; the indicator reads a little long (a slope)."""
        from station.instruments.gauge_bench import GaugeBenchModel

        bench = replace(gauge, low=-0.5, high=1.0)
        model = GaugeBenchModel(DEMO_REFERENCES, slope=DEMO_SLOPE, readings=12, gauge=bench)
        return DemoRig(
            model,
            "a simulated indicator over a surface plate and five gauge blocks (seeded)",
            channel_map={"1": "x"},
            display=_master_display,
        )


METHOD = GaugeLinearity()
