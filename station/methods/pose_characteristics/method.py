"""The ISO 9283 pose characteristics test as a method: AP and RP per pose of the test cube, vAP,
and AD and RD between two poses (:mod:`.iso9283`).

A session takes one 3-D fixture to each pose in turn (a placement of the procedure's repeated
block is a pose: placement 1 is P1 ...), teaches the pose with the cube in the fixture, zeroes
the indicators there and, while the robot runs the standard's cycle, captures each return to
the pose. The teach pendant's X, Y, Z of the taught pose may be typed (as relative accuracy
types its pendant): the indicators read 0 at it, so an attained point is that command pose
plus the readings, in the robot's frame (the fixture square to it), and the distance between
two poses can be measured; without it, AP is relative to the zero. The block's first capturing
step is the standard's approach direction; a block with more (a site's procedure) approaches
the pose from more directions, for vAP.

A CSV (``station analyze FILE --procedure pose_characteristics``) has the columns
``cycle,x,y,z`` and optionally ``pose`` (1 = P1 ...), ``direction`` (1, 2, 3) and the command
pose ``cx,cy,cz``, every point in the frame of the command poses. The conditions of the run
(load, speed, warm-up, temperature) are typed at the procedure's input steps.
"""

from __future__ import annotations

import csv
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from station.errors import StationError
from station.methods.contract import (
    DemoDisplay,
    DemoRig,
    Judgement,
    Method,
    MethodInputs,
    PlacementWords,
)
from station.methods.pose_characteristics.iso9283 import (
    CYCLES,
    POSES,
    Conditions,
    PoseCharacteristics,
    as_json,
    parse_distance,
    pose_characteristics,
    report_lines,
)
from station.methods.pose_characteristics.live import LivePerPose
from station.methods.sessions import (
    AXES,
    is_number,
    typed_per_placement,
    typed_points,
    typed_values,
)
from station.methods.tables import export_comments, number
from station.methods.text import fitted
from station.procedures import AnalysisNeeds
from station.session.tables import require_columns

if TYPE_CHECKING:
    from _typeshed import SupportsWrite

    from station.analysis.summary import AnalysisConfig
    from station.instruments.simulator import GaugeSpec
    from station.session.model import Session
    from station.session.tables import ReadingTable

NAME = "pose_characteristics"
COMMAND_COLUMNS = ("cx", "cy", "cz")
"""The command pose, optional columns of its CSV (one command pose per pose)."""
CONDITION_FIELDS = ("load", "speed", "warm_up", "temperature_start", "temperature_end")
"""The input fields the conditions are typed in (:class:`~.iso9283.Conditions`)."""


@dataclass(frozen=True)
class PoseReadings:
    """What the analysis reads: the attained points (n × 3), the pose, approach direction and
    cycle of each (cycle None: counted in order), the command pose per pose, the conditions."""

    points: np.ndarray
    poses: np.ndarray
    directions: np.ndarray
    cycles: np.ndarray | None
    commands: dict[int, tuple[float, ...]]
    conditions: Conditions | None


def table_readings(table: ReadingTable) -> PoseReadings:
    """The readings of a pose CSV: ``x,y,z`` (and the ``cycle`` index), optionally ``pose``,
    ``direction`` and ``cx,cy,cz``."""
    columns = require_columns(table, AXES, "a pose characteristics table")
    rows = len(columns["x"])
    lowered = {name.lower(): values for name, values in table.channels.items()}
    poses = lowered.get("pose")
    if poses is None:
        # A tidy export keeps the placement beside each cycle: in a pose test, the pose.
        poses = table.placements if table.placements is not None else np.ones(rows)
    directions = lowered.get("direction", np.ones(rows))
    commands: dict[int, tuple[float, ...]] = {}
    given = [name for name in COMMAND_COLUMNS if name in lowered]
    if given and len(given) < len(COMMAND_COLUMNS):
        raise StationError(
            f"{table.path}: the command pose needs all of cx, cy, cz, not only {', '.join(given)}."
        )
    if given:
        coordinates = np.column_stack([lowered[name] for name in COMMAND_COLUMNS])
        for row, pose in enumerate(poses):
            key = int(pose) if pose == round(pose) else 0  # the analysis names a bad pose
            point = tuple(float(v) for v in coordinates[row])
            known = commands.setdefault(key, point)
            if known != point:
                raise StationError(
                    f"{table.path}: pose P{key} has two command poses ({_point(known)} and "
                    f"{_point(point)}); give one per pose."
                )
    return PoseReadings(
        points=np.column_stack([columns[axis] for axis in AXES]),
        poses=np.asarray(poses, dtype=float),
        directions=np.asarray(directions, dtype=float),
        cycles=table.cycles,
        commands=commands,
        conditions=None,
    )


def _point(point: Sequence[float]) -> str:
    return ", ".join(f"{v:g}" for v in point)


def session_readings(session: Session) -> PoseReadings:
    """The readings a pose test session took at its poses: the command pose typed at a pose
    plus the readings (the indicators read 0 at it), else the readings alone; the direction
    of a reading is its step's place among the pose's capturing steps (1: the first)."""
    numbers = [
        n
        for n in session.accepted_cycles
        if session.cycles[n].placement is not None
        and all(axis in session.cycles[n].readings for axis in AXES)
    ]
    if not numbers:
        raise StationError(
            f"{session.path}: the session has no accepted x, y, z reading at a pose yet."
        )
    commands = typed_points(typed_per_placement(session.input_events))
    steps: dict[int, list[str]] = {}
    points, poses, directions = [], [], []
    for cycle_number in numbers:
        cycle = session.cycles[cycle_number]
        pose = int(cycle.placement)  # type: ignore[arg-type]
        seen = steps.setdefault(pose, [])
        if cycle.step not in seen:
            seen.append(cycle.step)
        origin = commands.get(pose, (0.0, 0.0, 0.0))
        points.append([o + cycle.readings[a].value for o, a in zip(origin, AXES, strict=True)])
        poses.append(pose)
        directions.append(seen.index(cycle.step) + 1)
    conditions = {
        name: typed_values(session.input_events, name).get(name) for name in CONDITION_FIELDS
    }
    values = {name: float(value) for name, value in conditions.items() if is_number(value)}
    return PoseReadings(
        points=np.asarray(points, dtype=float),
        poses=np.asarray(poses, dtype=float),
        directions=np.asarray(directions, dtype=float),
        cycles=None,
        commands=commands,
        conditions=Conditions(**values),
    )


def _readings(inputs: MethodInputs) -> PoseReadings:
    if inputs.table is not None:
        return table_readings(inputs.table)
    assert inputs.session is not None
    return session_readings(inputs.session)


def _pose_display(model: Any, placement: int | None, unit: str) -> DemoDisplay | None:
    """What the simulated teach pendant shows at pose ``placement``, or the conditions of the
    simulated run before the first pose."""
    if placement is None:
        return DemoDisplay(
            label="Test conditions (simulated)",
            text="load 100 % of rated, speed 100 % of rated, warm-up 30 min, 20.5 °C at the "
            "start, 21.0 °C at the end",
            values={
                "load": 100,
                "speed": 100,
                "warm_up": 30,
                "temperature_start": 20.5,
                "temperature_end": 21.0,
            },
            hint="type the conditions shown above",
        )
    shown = model.placement_of(placement)
    return DemoDisplay(
        label=f"Teach pendant at P{placement} (simulated)",
        text=shown.pendant_text(unit),
        values=dict(zip(AXES, shown.pendant, strict=True)),
        hint="copy the simulated pendant's X, Y, Z shown above",
    )


class PoseCharacteristicsMethod(Method):
    """ISO 9283 pose accuracy, repeatability, vAP and distance at the test cube's poses."""

    name = NAME
    title = "ISO 9283 POSE CHARACTERISTICS REPORT"
    reads_columns_by_name = True
    needs = AnalysisNeeds(
        facet="counts",
        facet_in_block=True,
        facet_words="a repeat block (one per pose) holding a cycles step",
        channels=AXES,
        limits=False,
    )
    json_key = "iso9283"
    options = ("distance",)
    export_layout = "wide"
    # Each pose has its own bias: the readings in time order step from pose to pose.
    drift_chart = False
    placement_words = PlacementWords(
        label="Poses",
        noun="poses",
        hint=f"the test cube's poses P1 to P{POSES}, one after the other ({{low}} to {{target}})",
        too_few=f"Give at least 1 pose; the standard measures P1 to P{POSES}.",
    )
    demo_words = "one fixture taken to the five poses of the ISO 9283 test cube"

    def live(
        self, config: AnalysisConfig, channels: Sequence[str], header: Mapping[str, Any]
    ) -> LivePerPose:
        """Each pose's readings on their own (see :mod:`.live`)."""
        return LivePerPose(config, channels, header)

    def batch(self, inputs: MethodInputs) -> Judgement:
        """AP and RP per pose, vAP, and the distance the command line names (no capability
        verdict: the standard reports figures)."""
        readings = _readings(inputs)
        asked = inputs.option("distance")
        result = pose_characteristics(
            readings.points,
            readings.poses,
            directions=readings.directions,
            cycles=readings.cycles,
            commands=readings.commands,
            distance=None if asked is None else parse_distance(str(asked)),
        )
        report = PoseReport(result, readings.conditions)
        lines = report_lines(
            result,
            readings.conditions,
            unit=inputs.config.unit,
            resolution=inputs.config.resolution,
        )
        return Judgement(None, report, (fitted(lines, inputs.width),))

    def json(self, result: Any) -> dict[str, Any]:
        """Per pose the barycentre, AP and RP; vAP; the distance; the conditions."""
        return as_json(result.figures, result.conditions)

    def count(self, result: Any) -> str:
        """``5 poses``."""
        poses = len(result.figures.poses)
        return f"{poses} pose" + ("" if poses == 1 else "s")

    def write_wide(self, session: Session, out: SupportsWrite[str]) -> int:
        """``cycle,pose,direction,x,y,z`` (the cycle: the n-th at that pose and direction) and,
        when every pose has its command pose typed, ``cx,cy,cz`` (x, y, z then in the robot's
        frame: the command pose plus the readings)."""
        readings = session_readings(session)
        poses = readings.poses.astype(int).tolist()
        with_command = all(pose in readings.commands for pose in poses)
        export_comments(session, out)
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(
            ("cycle", "pose", "direction", *AXES) + (COMMAND_COLUMNS if with_command else ())
        )
        counted: dict[tuple[int, int], int] = {}
        for row, pose in enumerate(poses):
            direction = int(readings.directions[row])
            counted[(pose, direction)] = counted.get((pose, direction), 0) + 1
            point = readings.points[row]
            if not with_command:
                # The readings alone: the indicators' zero at each pose.
                point = point - np.asarray(readings.commands.get(pose, (0.0, 0.0, 0.0)))
            cells = [counted[(pose, direction)], pose, direction, *(number(v) for v in point)]
            if with_command:
                cells += [number(v) for v in readings.commands[pose]]
            writer.writerow(cells)
        return len(poses)

    def demo_rig(self, gauge: GaugeSpec, seed: int, *, stroke_points: int) -> DemoRig:
        """One fixture at the five poses of a 20 in test cube, each pose with a bias and a
        spread of its own, and the teach pendant's X, Y, Z of each."""
        from station.instruments.simulator.cube import CubePosesModel

        # Mitutoyo has no zero command: the station zeroes in software at the taught pose.
        model = CubePosesModel(captures=CYCLES, preload=0.05, gauge=gauge, seed=seed)
        return DemoRig(
            model,
            "one simulated fixture at the test cube's five poses and a teach pendant (seeded)",
            display=_pose_display,
        )


@dataclass(frozen=True)
class PoseReport:
    """The method's result: the figures and the run's conditions (None for a CSV)."""

    figures: PoseCharacteristics
    conditions: Conditions | None


METHOD = PoseCharacteristicsMethod()
