"""The per-joint troubleshooting method: the x, y, z readings labelled by the joint (the repeat
block's placement in a session, the ``joint`` column of a CSV) and the lever arm typed per joint
(a ``lever`` input or column); its capability analysis is the returns of every joint pooled."""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from station.analysis.joints import analyze_joints
from station.errors import StationError
from station.methods.capability import capability_of
from station.methods.contract import (
    DemoDisplay,
    DemoRig,
    Judgement,
    Method,
    MethodInputs,
    PlacementWords,
)
from station.methods.sessions import AXES, is_number, placement_readings
from station.methods.text import fitted
from station.procedures import AnalysisNeeds
from station.session.tables import require_columns

if TYPE_CHECKING:
    from station.instruments.simulator import GaugeSpec
    from station.session.tables import ReadingTable

DEMO_FAULTY_JOINT = 2
"""The joint the demo's arm has a fault in (a noisy servo), for the study to find."""
DEMO_RETURNS = 25
"""Returns per joint the demo's arm makes (the procedure's own count)."""

TABLE_COLUMNS = ("joint", "x", "y", "z")
"""The columns of a per-joint CSV (``lever`` optional: the joint's axis to the cube)."""

JointInputs = tuple[np.ndarray, dict[str, np.ndarray], dict[int, float] | None]
"""Joint of each return, readings x, y, z and the lever arms (None unless every joint has one)."""


def table_joint_inputs(table: ReadingTable) -> JointInputs:
    """Joint labels, readings x, y, z and lever arms (an optional ``lever`` column, one value
    per joint) of a CSV with columns ``joint,x,y,z[,lever]``."""
    columns = require_columns(table, TABLE_COLUMNS, "a per-joint table")
    readings = {axis: columns[axis] for axis in AXES}
    if "lever" not in {name.lower() for name in table.channels}:
        return columns["joint"], readings, None
    lever = require_columns(table, ("lever",), "the lever arms")["lever"]
    levers: dict[int, float] = {}
    for joint, value in zip(columns["joint"], lever, strict=True):
        if joint != np.round(joint):
            break  # analyze_joints says what is wrong with the joint column
        known = levers.setdefault(int(joint), float(value))
        if known != value:
            raise StationError(
                f"{table.path}: joint {int(joint)} has two lever arms ({known:g} and "
                f"{value:g}); give one per joint."
            )
    return columns["joint"], readings, levers


def session_joint_inputs(inputs: MethodInputs) -> JointInputs:
    """Joint of each return (the repeat block's placement), readings and lever arms."""
    assert inputs.session is not None
    placements, readings, typed = placement_readings(inputs.session)
    levers = {
        placement: float(values["lever"])
        for placement, values in typed.items()
        if is_number(values.get("lever")) and values["lever"] > 0
    }
    complete = set(np.asarray(placements).tolist()) <= set(levers)
    return np.asarray(placements), readings, levers if complete else None


class JointTroubleshooting(Method):
    """Each joint's returns, the suspect joint named."""

    name = "joint_troubleshooting"
    title = "PER-JOINT TROUBLESHOOTING REPORT"
    reads_columns_by_name = True
    needs = AnalysisNeeds(
        facet="counts",
        facet_in_block=True,
        facet_words="a repeat block (one per joint) holding a cycles step",
        channels=AXES,
    )
    placement_words = PlacementWords(
        label="Joints",
        noun="joints",
        hint="joints moved one at a time, joint 1 at the base first ({low} to {target})",
        too_few="Give at least 2 joints: the study compares the joints' spreads.",
        fewest=2,
    )
    demo_words = "a three-joint arm at one fixture, one joint noisy"

    def batch(self, inputs: MethodInputs) -> Judgement:
        """The joints ranked and the suspect named; the returns pooled for the verdict."""
        if inputs.table is not None:
            joints, readings, levers = table_joint_inputs(inputs.table)
            # The table's columns as the method reads them (not the joint column).
            inputs = replace(inputs, channels=readings, cycles=None, times=None)
            axes = list(readings)
        else:
            joints, readings, levers = session_joint_inputs(inputs)
            axes = [axis for axis in AXES if axis in inputs.channels]
        result = analyze_joints(joints, readings, lever_arms=levers)
        analysis = capability_of(inputs, axes, inputs.config) if axes else None
        return Judgement(
            analysis, result, (fitted(result.lines(inputs.config.unit), inputs.width),)
        )

    def json(self, result: Any) -> dict[str, Any]:
        """Per joint its share of the spread, and the suspect."""
        return result.as_json()

    def count(self, result: Any) -> str:
        """``3 joints``."""
        return f"{len(result.joints)} joints"

    def demo_rig(self, gauge: GaugeSpec, seed: int, *, stroke_points: int) -> DemoRig:
        """A three-joint arm returning to the 3-D fixture one joint at a time, joint 2's servo
        noisy (the suspect to be found); each joint's turn starts at the taught position,
        where the station zeroes."""
        from station.instruments.joint_model import faulty_arm

        model = faulty_arm(
            DEMO_FAULTY_JOINT, "noise", cycles=DEMO_RETURNS, gauge=gauge, home_readings=1
        )
        return DemoRig(
            model,
            "a simulated three-joint arm at a fixture with three indicators (seeded)",
            display=_lever_display,
        )


def _lever_display(model: Any, placement: int | None, unit: str) -> DemoDisplay | None:
    """What the tape shows for the joint of ``placement``: its axis to the cube."""
    if placement is None or not 1 <= placement <= len(model.lever_arms()):
        return None
    lever = round(model.lever_arms()[placement - 1], 1)
    return DemoDisplay(
        label=f"Tape from joint {placement}'s axis to the cube (simulated)",
        text=f"{lever:g} {unit}",
        values={"lever": lever},
        hint="type the lever arm shown above",
    )


METHOD = JointTroubleshooting()
