"""The relative-accuracy method: the indicators' error after the inverse move at each fixture
placement, per axis and overall, with the same statistics as repeatability; its wide table is
``cycle,placement,x,y,z`` (and the pendant's ``px,py,pz`` when every placement has them)."""

from __future__ import annotations

import csv
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from station.analysis.accuracy import accuracy_json, analyze_accuracy
from station.analysis.report import format_accuracy
from station.methods.contract import (
    DemoDisplay,
    DemoRig,
    Judgement,
    Method,
    MethodInputs,
)
from station.methods.sessions import AXES, placement_readings, typed_points
from station.methods.tables import export_comments, number
from station.procedures import AnalysisNeeds
from station.session.tables import require_columns

if TYPE_CHECKING:
    from _typeshed import SupportsWrite

    from station.instruments.simulator import GaugeSpec
    from station.session.model import Session
    from station.session.tables import ReadingTable

TABLE_COLUMNS: tuple[str, ...] = ("placement", "x", "y", "z")
"""The columns its CSV table must have (``station analyze --procedure relative_accuracy``)."""
PENDANT_COLUMNS: tuple[str, ...] = ("px", "py", "pz")
"""The teach pendant's coordinates, optional columns of its table."""

AccuracyInputs = tuple[np.ndarray, dict[str, np.ndarray], dict[int, tuple[float, ...]]]
"""Placement of each reading, the errors x, y, z, and the pendant coordinates per placement."""


def session_accuracy_inputs(session: Session) -> AccuracyInputs:
    """Placements, errors x, y, z and the pendant's coordinates typed per placement."""
    placements, errors, typed = placement_readings(session)
    return placements, errors, typed_points(typed)


def table_accuracy_inputs(table: ReadingTable) -> AccuracyInputs:
    """Placements, errors x, y, z and pendant coordinates of a relative-accuracy CSV."""
    if table.placements is not None and "placement" not in {n.lower() for n in table.channels}:
        # A tidy table keeps the placement beside each cycle, not as a channel.
        table = replace(table, channels={**table.channels, "placement": table.placements})
    columns = require_columns(table, TABLE_COLUMNS, "a relative-accuracy table")
    pendant: dict[int, tuple[float, ...]] = {}
    lowered = {name.lower() for name in table.channels}
    if set(PENDANT_COLUMNS) <= lowered:
        coordinates = require_columns(table, PENDANT_COLUMNS, "the pendant")
        for row, placement in enumerate(columns["placement"]):
            pendant.setdefault(int(placement), tuple(coordinates[c][row] for c in PENDANT_COLUMNS))
    errors = {axis: columns[axis] for axis in AXES}
    return columns["placement"], errors, pendant


def _pendant_display(model: Any, placement: int | None, unit: str) -> DemoDisplay | None:
    """What the simulated teach pendant shows at ``placement``."""
    if placement is None:
        return None
    shown = model.placement_of(placement)
    return DemoDisplay(
        label="Teach pendant (simulated)",
        text=shown.pendant_text(unit),
        values=dict(zip(AXES, shown.pendant, strict=True)),
        hint="copy the simulated pendant's X, Y, Z shown above",
    )


class RelativeAccuracy(Method):
    """Relative accuracy over several fixture placements."""

    name = "relative_accuracy"
    title = "RELATIVE ACCURACY REPORT"
    reads_columns_by_name = True
    needs = AnalysisNeeds(
        facet="block",
        facet_words="a repeat block (one per placement)",
        channels=AXES,
        implied=True,
    )
    json_key = "accuracy"
    export_layout = "wide"
    demo_words = "two fixtures and a teach pendant"

    def batch(self, inputs: MethodInputs) -> Judgement:
        """The error at each placement and across placements."""
        if inputs.table is not None:
            placements, errors, pendant = table_accuracy_inputs(inputs.table)
        else:
            assert inputs.session is not None
            placements, errors, pendant = session_accuracy_inputs(inputs.session)
        result = analyze_accuracy(
            placements,
            errors,
            inputs.config,
            pendant=pendant,
            excluded_cycles=inputs.excluded_cycles,
        )
        block = tuple(format_accuracy(result, inputs.config, inputs.width))
        return Judgement(result.overall, result, (block,))

    def json(self, result: Any) -> dict[str, Any]:
        """The accuracy per placement and across placements."""
        return accuracy_json(result)

    def count(self, result: Any) -> str:
        """``3 placements``."""
        return f"{len(result.placements)} placements"

    def recognises(self, session: Session) -> bool:
        """Captures at fixture placements (a file from before headers named the method)."""
        return any(cycle.placement is not None for cycle in session.cycles.values())

    def write_wide(self, session: Session, out: SupportsWrite[str]) -> int:
        """``cycle,placement,x,y,z`` of the accepted readings at fixture placements and, when
        every placement has them, the teach pendant's ``px,py,pz``."""
        _, _, pendant = session_accuracy_inputs(session)
        numbers = [
            n
            for n in session.accepted_cycles
            if session.cycles[n].placement is not None
            and all(axis in session.cycles[n].readings for axis in AXES)
        ]
        with_pendant = bool(numbers) and all(
            session.cycles[n].placement in pendant for n in numbers
        )
        export_comments(session, out)
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(("cycle", *TABLE_COLUMNS) + (PENDANT_COLUMNS if with_pendant else ()))
        for cycle_number in numbers:
            cycle = session.cycles[cycle_number]
            row = [cycle_number, cycle.placement, *(number(cycle.readings[a].value) for a in AXES)]
            if with_pendant:
                row += [number(v) for v in pendant[cycle.placement]]  # type: ignore[index]
            writer.writerow(row)
        return len(numbers)

    def demo_rig(self, gauge: GaugeSpec, seed: int, *, stroke_points: int) -> DemoRig:
        """Two fixtures with a pendant display, an error that grows with the distance moved,
        and a preload at home that only zeroing takes out."""
        from station.instruments.simulator import TwoFixtureModel

        # Mitutoyo has no zero command: the station zeroes in software from readings at home,
        # so the preload really has to be zeroed out.
        model = TwoFixtureModel(preload=0.05, gauge=gauge, seed=seed)
        return DemoRig(
            model,
            "two simulated fixtures and a teach pendant (seeded)",
            display=_pendant_display,
        )


METHOD = RelativeAccuracy()
