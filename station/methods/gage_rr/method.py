"""The crossed Gage R&R as a method: the readings of one gauge, each of a part by an appraiser at
a trial (a session's: the part a ``parts`` step recorded, the step's id as the appraiser, the
repeated block's placement as the trial; a CSV's ``part,appraiser,trial,value`` rows, with
``operator`` accepted for ``appraiser``), judged by
:func:`~station.methods.gage_rr.study.gage_rr_study` against the tolerance typed at the
session's input step (or ``--tolerance``). It judges no readings by capability: its verdict is
its own (ACCEPTABLE, CONDITIONALLY ACCEPTABLE, NOT ACCEPTABLE or INCONCLUSIVE). Its report draws
the readings by part and by appraiser, the interaction and the range chart; a finished study
files itself in the gauge register under the gauge id typed in it, beside the gauge's checks."""

from __future__ import annotations

import csv
import datetime as dt
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from station.errors import StationError
from station.methods.contract import (
    Chart,
    ChartKit,
    CountField,
    DemoDisplay,
    DemoRig,
    Judgement,
    Method,
    MethodInputs,
    MethodVerdict,
    PlacementWords,
)
from station.methods.gage_rr.charts import (
    by_appraiser_chart,
    by_part_chart,
    interaction_chart,
    range_chart,
)
from station.methods.gage_rr.study import (
    APPRAISERS_AIAG,
    POOL_ABOVE,
    TRIALS_AIAG,
    GageRRStudy,
    gage_rr_study,
)
from station.methods.live import LiveAboutGroups
from station.methods.sessions import (
    is_number,
    load_session_source,
    session_inputs,
    typed_values,
)
from station.methods.tables import export_comments, number
from station.methods.text import fitted
from station.procedures import AnalysisNeeds, Procedure
from station.session.gauge_register import port_of, record_study, register_path

if TYPE_CHECKING:
    from _typeshed import SupportsWrite

    from station.analysis.summary import AnalysisConfig
    from station.instruments.simulator import GaugeSpec
    from station.session.model import Session

NAME = "gage_rr"
TABLE_COLUMNS = ("part", "appraiser", "trial", "value")
"""The columns of its CSV table: one row per reading."""
APPRAISER_ALIASES = ("appraiser", "operator")
"""The names the appraiser's column may have (Minitab and others say operator)."""

Readings = tuple[list[str], list[str], list[int], np.ndarray]
"""The part, appraiser and trial of each reading, and the readings."""
DEMO_PARTS = (0.2480, 0.2512, 0.2497, 0.2525, 0.2469, 0.2503, 0.2538, 0.2490, 0.2516, 0.2476)
"""The demo bench's ten parts (in): a process of about ±0.003 in about 0.25 in."""
DEMO_APPRAISERS = {"A": 0.0, "B": 0.0001, "C": -0.00008}
"""How the demo's appraisers read (in): B a tenth high, C a little low."""
DEMO_NOISE = 0.00008
"""The demo gauge's repeatability (σ, in): with the appraisers, about 10 % GRR."""
DEMO_GAUGE = "DEMO-IND-1"
DEMO_TOLERANCE = 0.006
DEMO_NAMES = {"A": "Ann", "B": "Bo", "C": "Cy"}


def _typed(inputs: MethodInputs, name: str) -> float | None:
    """The command line's ``name``, else the session's typed one (None: neither)."""
    given = inputs.option(name)
    if given is None:
        given = typed_values(inputs.input_events, name).get(name)
    return float(given) if is_number(given) else None


def _table_readings(inputs: MethodInputs) -> Readings:
    """The rows of a ``part,appraiser,trial,value`` table (StationError naming a missing
    column or a trial that is no whole number)."""
    table = inputs.table
    assert table is not None
    labels = {name.lower(): cells for name, cells in table.labels.items()}
    numbers = {name.lower(): values for name, values in table.channels.items()}
    appraiser = next((labels[a] for a in APPRAISER_ALIASES if a in labels), None)
    missing = [
        name
        for name, found in (
            ("part", labels.get("part")),
            ("appraiser", appraiser),
            ("trial", numbers.get("trial")),
            ("value", numbers.get("value")),
        )
        if found is None
    ]
    if missing:
        have = ", ".join([*table.labels, *table.channels]) or "none"
        raise StationError(
            f"{table.path}: a Gage R&R table needs the columns {', '.join(TABLE_COLUMNS)} "
            f"(operator for appraiser); {', '.join(missing)} missing (the file has {have})."
        )
    assert appraiser is not None
    trials = numbers["trial"]
    wrong = np.flatnonzero((trials != np.floor(trials)) | (trials < 1))
    if wrong.size:
        raise StationError(
            f"{table.path}: trial {trials[wrong[0]]:g} of part {labels['part'][wrong[0]]} is "
            "not a trial number (1, 2, 3 ...); fix the cell."
        )
    return (
        list(labels["part"]),
        list(appraiser),
        [int(t) for t in trials],
        numbers["value"],
    )


def _session_readings(session: Session) -> Readings:
    """The accepted readings of the session's parts steps: the part each recorded, the step
    (an appraiser's) and the placement (the trial) it was taken at."""
    numbers = [
        n
        for n in session.accepted_cycles
        if session.cycles[n].part is not None and session.cycles[n].placement is not None
    ]
    if not numbers:
        raise StationError(
            f"{session.path}: the session has no accepted reading of a part by an appraiser yet."
        )
    channel = session.channels[0]
    cycles = [session.cycles[n] for n in numbers]
    if any(channel not in cycle.readings for cycle in cycles):
        raise StationError(f"{session.path}: a reading of a part has no value of {channel}.")
    return (
        [str(cycle.part) for cycle in cycles],
        [cycle.step for cycle in cycles],
        [int(cycle.placement or 0) for cycle in cycles],
        np.asarray([cycle.readings[channel].value for cycle in cycles], dtype=float),
    )


def _names(inputs: MethodInputs, appraisers: Sequence[str]) -> dict[str, str]:
    """The appraisers' names typed in the session (a field named by an appraiser's step id)."""
    names: dict[str, str] = {}
    for event in inputs.input_events:
        for key, value in dict(event.get("values") or {}).items():
            if key in appraisers and isinstance(value, str) and value.strip():
                names[key] = value.strip()
    return names


def _bench_display(model: Any, placement: int | None, unit: str) -> DemoDisplay | None:
    """What the simulated bench's label says at the study's input step: the gauge's id, the
    tolerance and the appraisers' names."""
    if placement is not None:
        return None
    names = ", ".join(f"{a} {n}" for a, n in DEMO_NAMES.items())
    return DemoDisplay(
        label="Gauge and appraisers (simulated)",
        text=f"indicator {DEMO_GAUGE}, tolerance {DEMO_TOLERANCE:g} {unit}; appraisers {names}",
        values={"gauge": DEMO_GAUGE, "tolerance": DEMO_TOLERANCE, **DEMO_NAMES},
        hint="type the indicator's id, the tolerance and the appraisers' names shown above",
    )


class GageRR(Method):
    """A crossed Gage R&R study of one gauge (see the module)."""

    name = NAME
    title = "GAGE R&R (CROSSED) REPORT"
    reads_columns_by_name = True
    label_columns = ("part", *APPRAISER_ALIASES)
    needs = AnalysisNeeds(
        facet="parts",
        facet_in_block=True,
        facet_words="a repeat block (one per trial) holding a parts step per appraiser",
        limits=False,
    )
    json_key = NAME
    options = ("tolerance", "pool_above")
    export_layout = "wide"
    drift_chart = False
    files_in_register = True
    placement_words = PlacementWords(
        label="Trials",
        noun="trials",
        hint=f"trials: every appraiser measures every part once per trial; AIAG asks for "
        f"{TRIALS_AIAG} with {APPRAISERS_AIAG} appraisers ({{low}} to {{target}})",
        too_few="Give at least 2 trials: repeatability needs a part measured twice.",
    )
    demo_words = "an indicator over a surface plate, ten parts and three appraisers"

    def count_field(self, procedure: Procedure) -> CountField:
        """The trials (the placements of its block): 2 at least, since one trial shows no
        repeatability."""
        return replace(super().count_field(procedure), minimum=2)

    def live(
        self, config: AnalysisConfig, channels: Sequence[str], header: Mapping[str, Any]
    ) -> LiveAboutGroups:
        """The readings about their part's mean (the gauge's and the appraisers' variation)."""
        return LiveAboutGroups(config, channels, header, by="part", what="part")

    def study(self, inputs: MethodInputs) -> GageRRStudy:
        """The study of ``inputs`` (StationError naming what is missing)."""
        if inputs.table is not None:
            parts, appraisers, trials, values = _table_readings(inputs)
        else:
            assert inputs.session is not None
            parts, appraisers, trials, values = _session_readings(inputs.session)
        rule = dict((inputs.header or {}).get(NAME) or {})
        pool_above = inputs.option("pool_above")
        if pool_above is None:
            pool_above = rule.get("pool_above", POOL_ABOVE)
        return gage_rr_study(
            parts,
            appraisers,
            trials,
            values,
            tolerance=_typed(inputs, "tolerance"),
            pool_above=float(pool_above) if is_number(pool_above) else POOL_ABOVE,
            resolution=inputs.config.resolution,
            unit=inputs.config.unit,
            names=_names(inputs, tuple(dict.fromkeys(appraisers))),
        )

    def batch(self, inputs: MethodInputs) -> Judgement:
        """The study and its verdict (no capability analysis)."""
        study = self.study(inputs)
        verdict = MethodVerdict(study.verdict, study.sentence, study.acceptable)
        return Judgement(None, study, (fitted(study.lines(), inputs.width),), verdict)

    def json(self, result: Any) -> dict[str, Any]:
        """The study's figures: ``anova``, ``xbar_r``, the verdict and the design."""
        return result.as_json()

    def count(self, result: Any) -> str:
        """``3 appraisers x 10 parts x 3 trials``."""
        return (
            f"{len(result.appraisers)} appraisers x {len(result.parts)} parts x "
            f"{result.trials} trials"
        )

    def header_fields(self, fields: Mapping[str, Any]) -> dict[str, Any]:
        """The pooling rule the session's verdict takes (kept with it: a later station with
        another default judges the file as it was judged)."""
        return {NAME: {"pool_above": POOL_ABOVE}}

    def charts(self, inputs: MethodInputs, judgement: Judgement, kit: ChartKit) -> Iterator[Chart]:
        """The readings by part and by appraiser, the interaction, the range chart."""
        study = judgement.result
        yield "by-part", "Readings by part", by_part_chart(study, kit)
        yield "by-appraiser", "Readings by appraiser", by_appraiser_chart(study, kit)
        yield "interaction", "Part x appraiser interaction", interaction_chart(study, kit)
        yield "range-chart", "Range chart by appraiser", range_chart(study, kit)

    def file_in_register(self, path: Path, register: Path | None = None) -> list[str]:
        """File the study under the gauge id typed in the session, beside its checks."""
        source = load_session_source(path)
        session = source.session
        study = self.study(session_inputs(source))
        gauge = str(typed_values(session.input_events, "gauge").get("gauge") or "").strip()
        if not gauge:
            raise StationError(f"{session.path}: the study names no gauge id to register.")
        target = register or register_path()
        anova = study.anova
        pct = anova.pct_grr
        summary = f"%GRR {pct:.1f} %, ndc {anova.ndc}" if pct is not None else "no variation"
        entry = record_study(
            target,
            gauge,
            NAME,
            {
                "date": dt.date.fromisoformat(str(session.created)[:10]).isoformat(),
                "result": study.verdict.lower(),
                "summary": summary,
                "pct_grr": pct,
                "pct_tolerance": anova.pct_tolerance,
                "ndc": anova.ndc,
                "ev": anova.ev,
                "av": anova.av,
                "grr": anova.grr,
                "pv": anova.pv,
                "tolerance": study.tolerance,
                "appraisers": list(study.appraisers),
                "parts": len(study.parts),
                "trials": study.trials,
                "session": session.session_id,
            },
            port=port_of(session.header, next(iter(source.channels), "x")),
        )
        return [
            f"Gage R&R of {gauge}: {study.verdict} on {entry['date']} ({summary}); filed in "
            f"the gauge register {target}."
        ]

    def write_wide(self, session: Session, out: SupportsWrite[str]) -> int:
        """``cycle,part,appraiser,trial,value``: each accepted reading of a part."""
        parts, appraisers, trials, values = _session_readings(session)
        numbers = [
            n
            for n in session.accepted_cycles
            if session.cycles[n].part is not None and session.cycles[n].placement is not None
        ]
        export_comments(session, out)
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(("cycle", *TABLE_COLUMNS))
        for row in zip(numbers, parts, appraisers, trials, values.tolist(), strict=True):
            writer.writerow((*row[:4], number(row[4])))
        return len(numbers)

    def demo_rig(self, gauge: GaugeSpec, seed: int, *, stroke_points: int) -> DemoRig:
        """An indicator over a surface plate, ten parts about 0.25 in and three appraisers,
        B reading a little high and C a little low: about 10 % GRR."""
        from station.instruments.gauge_bench import GageRRBenchModel

        bench = replace(gauge, low=-0.5, high=1.0)
        model = GageRRBenchModel(DEMO_PARTS, DEMO_APPRAISERS, noise=DEMO_NOISE, gauge=bench)
        return DemoRig(
            model,
            "a simulated indicator over a surface plate, ten parts and three appraisers (seeded)",
            channel_map={"1": "x"},
            display=_bench_display,
        )


METHOD = GageRR()
