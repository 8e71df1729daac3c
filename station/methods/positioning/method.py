"""Axis positioning, ISO 230-2, as a method: the bidirectional accuracy and repeatability of one
axis (a robot axis along the parallel bar), the report's "inverse move" made systematic.

In a session the scale (channel ``s``) reads the axis's actual position at each stop of the
standard test cycle: each run (a placement of the procedure's repeated block) visits the targets
typed at the targets step (``target_1``, ``target_2`` ... along the axis) moving up, then moving
down (:func:`~station.methods.positioning.iso230.standard_cycle`); the k-th stop of a run is its
k-th accepted cycle. A CSV table gives one approach per row: ``target``, ``direction`` (``up`` or
``down``, or ``+``/``-``), an optional ``cycle`` (the run) and ``actual`` (the position read) or
``deviation`` (actual − target). The figures are :mod:`~station.methods.positioning.iso230`'s;
the method judges no readings by capability and gives no verdict of its own (ISO 230-2 states
figures; a tolerance on them is the buyer's).
"""

from __future__ import annotations

import csv
import re
from collections.abc import Iterator, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from station.errors import StationError
from station.methods.contract import (
    Chart,
    ChartKit,
    DemoDisplay,
    DemoRig,
    Judgement,
    Method,
    MethodInputs,
    PlacementWords,
)
from station.methods.positioning.iso230 import (
    APPROACHES,
    DOWN,
    UP,
    AxisPositioning,
    axis_positioning,
    cycle_approach,
    direction_of,
)
from station.methods.positioning.live import LiveAboutApproaches, stops
from station.methods.sessions import is_number
from station.methods.tables import export_comments, number
from station.methods.text import fitted
from station.plain import plain
from station.procedures import AnalysisNeeds

if TYPE_CHECKING:
    from _typeshed import SupportsWrite

    from station.analysis.summary import AnalysisConfig
    from station.instruments.simulator import GaugeSpec
    from station.session.model import Session
    from station.session.tables import ReadingTable

NAME = "positioning"
TARGET_FIELD = re.compile(r"target_(\d+)")
"""The typed fields that hold the targets, numbered along the axis: ``target_1``, ..."""
TABLE_COLUMNS = "target, direction and actual (or deviation)"
DEMO_TARGETS = (10.3, 97.6, 203.1, 301.9, 398.4)
"""The demo axis's targets (mm): five over a 400 mm travel, spaced unevenly as ISO 230-2 asks."""
DEMO_SLOPE = 5e-5
"""The demo axis stops long by 50 µm per metre of travel."""
DEMO_BACKLASH = 0.020
"""The demo axis's lost motion at a reversal (mm): a reversal B_i of -0.020 at every target."""
DEMO_NOISE = 0.002


Approaches = tuple[np.ndarray, np.ndarray, np.ndarray]
"""Each approach's target, whether it was moving up, and its deviation (actual − target)."""


# -- a session ----------------------------------------------------------------------------------


def typed_targets(events: Sequence[Mapping[str, Any]]) -> list[float]:
    """The targets of the last input event that typed any (``target_1``, ``target_2`` ... in
    their order); StationError when none are typed, one is not a number, or they do not rise
    along the axis (the standard cycle visits them in that order going up)."""
    for event in reversed(events):
        values = event.get("values") or {}
        found = {
            int(match.group(1)): value
            for name, value in values.items()
            if (match := TARGET_FIELD.fullmatch(str(name)))
        }
        if not found:
            continue
        order = sorted(found)
        for index in order:
            if not is_number(found[index]):
                raise StationError(
                    f"target_{index} is {plain(str(found[index]), limit=40)!r}, not a number: "
                    "type each target's position."
                )
        targets = [float(found[i]) for i in order]
        for (i, low), (j, high) in zip(
            zip(order, targets, strict=True),
            zip(order[1:], targets[1:], strict=True),
            strict=False,
        ):
            if not high > low:
                raise StationError(
                    f"target_{j} ({high:g}) is not beyond target_{i} ({low:g}): type the "
                    "targets in order along the axis, each beyond the one before."
                )
        return targets
    raise StationError("no targets are typed in yet: type them at the targets step.")


Stop = tuple[int, int, float, bool, float]
"""One accepted stop of a session: its cycle number, run, target, whether it was approached
moving up, and the scale's reading."""


def session_stops(session: Session) -> list[Stop]:
    """Each accepted stop of a run mapped onto the standard cycle over the typed targets (see
    the module), in the order taken. StationError naming what is missing."""
    numbers = [n for n in session.accepted_cycles if session.cycles[n].placement is not None]
    if not numbers:
        raise StationError(
            f"{plain(session.path)}: no stop of the test cycle is captured yet; capture one."
        )
    targets = typed_targets(session.input_events)
    channel = next(
        (c for c in session.channels if all(c in session.cycles[n].readings for n in numbers)),
        None,
    )
    if channel is None:
        raise StationError(f"{plain(session.path)}: no channel was read at every stop.")
    count = len(targets)
    found = []
    runs = stops([session.cycles[n].placement for n in numbers])
    for (run, k), n in zip(runs, numbers, strict=True):
        if k >= 2 * count:
            raise StationError(
                f"run {run} has more than {2 * count} stops, but {count} targets make "
                f"{2 * count} (each approached up, then down): the procedure's stops per run "
                "must be twice its targets."
            )
        index, direction = cycle_approach(k, count)
        reading = session.cycles[n].readings[channel].value
        found.append((n, int(run or 0), targets[index], direction == UP, reading))
    return found


def session_approaches(session: Session) -> Approaches:
    """The approaches of a session (:func:`session_stops`), each deviation the scale's reading
    less its target."""
    found = session_stops(session)
    targets = np.asarray([stop[2] for stop in found])
    readings = np.asarray([stop[4] for stop in found])
    return targets, np.asarray([stop[3] for stop in found], dtype=bool), readings - targets


# -- a CSV table --------------------------------------------------------------------------------


def table_approaches(table: ReadingTable) -> Approaches:
    """The approaches of a CSV table (columns ``target``, ``direction``, ``actual`` or
    ``deviation``, optional ``cycle``); StationError naming what is missing or wrong."""
    numbers = {name.lower(): values for name, values in table.channels.items()}
    words = {name.lower(): values for name, values in table.labels.items()}
    reading = [name for name in ("actual", "deviation") if name in numbers]
    missing = [name for name in ("target",) if name not in numbers]
    missing += [name for name in ("direction",) if name not in words]
    if not reading:
        missing.append("actual (or deviation)")
    if missing:
        have = ", ".join([*table.channels, *table.labels]) or "none"
        raise StationError(
            f"{plain(table.path)}: a positioning table needs the columns {TABLE_COLUMNS}; "
            f"missing {', '.join(missing)} (it has {plain(have, limit=80)})."
        )
    if len(reading) > 1:
        raise StationError(
            f"{plain(table.path)}: the table has both an actual and a deviation column; keep "
            "one (deviation = actual - target)."
        )
    targets = numbers["target"]
    lines = table.row_lines or tuple(range(1, len(targets) + 1))
    rising = []
    for line, text in zip(lines, words["direction"], strict=True):
        direction = direction_of(text)
        if direction is None:
            raise StationError(
                f"{plain(table.path)}: line {line}, column 'direction': "
                f"{plain(text, limit=40)!r} is not up, down, + or -; fix the cell."
            )
        rising.append(direction == UP)
    values = numbers[reading[0]]
    deviations = values - targets if reading[0] == "actual" else values
    if table.cycles is not None:
        seen: dict[tuple[float, bool, int], int] = {}
        keys = zip(targets.tolist(), rising, table.cycles.tolist(), strict=True)
        for line, key in zip(lines, keys, strict=True):
            if key in seen:
                target, up, cycle = key
                raise StationError(
                    f"{plain(table.path)}: target {target:g} is approached "
                    f"{UP if up else DOWN} twice in cycle {cycle} (lines {seen[key]} and "
                    f"{line}); keep one approach per target, direction and cycle."
                )
            seen[key] = line
    return targets, np.asarray(rising, dtype=bool), deviations


# -- the chart ----------------------------------------------------------------------------------


def deviation_chart(result: AxisPositioning, approaches: Approaches, kit: ChartKit) -> Any:
    """Every approach's deviation against its target, the mean up and the mean down with
    their ±2s bands (the bands A is taken over)."""
    targets, rising, deviations = approaches
    unit = kit.label(result.unit)
    suffix = f" ({unit})" if unit else ""
    figure = kit.figure()
    axes = figure.add_subplot()
    where = [t.target for t in result.targets]
    for up, colour, marker, word in (
        (True, kit.point, "^", "up"),
        (False, kit.alarm, "v", "down"),
    ):
        mask = rising == up
        axes.scatter(targets[mask], deviations[mask], s=10, color=colour, alpha=0.4, marker=marker)
        means = np.asarray([t.mean_up if up else t.mean_down for t in result.targets])
        spread = np.asarray([t.s_up if up else t.s_down for t in result.targets])
        axes.plot(where, means, color=colour, marker=marker, label=f"mean {word}")
        axes.fill_between(
            where, means - 2 * spread, means + 2 * spread, color=colour, alpha=0.15,
            label=f"mean {word} ± 2s",
        )  # fmt: skip
    axes.axhline(0.0, color="grey", linestyle=":")
    figures = f"E {result.e:.3g}, R {result.r:.3g}, B {result.b:.3g}" + (f" {unit}" if unit else "")
    axes.set_title(f"Deviation against the target: {figures}")
    axes.set_xlabel("target" + suffix)
    axes.set_ylabel("deviation (actual - target)" + suffix)
    axes.legend(loc="best", fontsize=7)
    return figure


def _targets_display(model: Any, placement: int | None, unit: str) -> DemoDisplay | None:
    """What the simulated axis's program lists: the targets it stops at, to be typed."""
    if placement is not None:
        return None
    targets = model.targets
    return DemoDisplay(
        label="The axis's test program (simulated)",
        text="targets " + ", ".join(f"{t:g}" for t in targets) + " mm",
        values={f"target_{i}": t for i, t in enumerate(targets, start=1)},
        hint="type the targets shown above",
    )


# -- the method ---------------------------------------------------------------------------------


class Positioning(Method):
    """Bidirectional accuracy and repeatability of one axis, ISO 230-2."""

    name = NAME
    title = "AXIS POSITIONING REPORT (ISO 230-2)"
    reads_columns_by_name = True
    label_columns = ("direction",)
    needs = AnalysisNeeds(
        facet="counts",
        facet_in_block=True,
        facet_words="a repeat block (one per run of the test cycle) holding a cycles step",
        numbers=("target_1", "target_2"),
        numbers_words="an input step with number fields target_1, target_2, ... (the targets "
        "along the axis)",
        limits=False,
    )
    json_key = "iso230_2"
    export_layout = "wide"
    drift_chart = False
    demo_words = "a linear scale along an axis with a positioning error and backlash"
    placement_words = PlacementWords(
        label="Runs",
        noun="runs of the test cycle",
        hint=f"runs of the test cycle (every target up, then down); ISO 230-2 asks for "
        f"{APPROACHES} ({{low}} to {{target}})",
        too_few=f"Give at least 1 run of the test cycle (ISO 230-2 asks for {APPROACHES}).",
    )

    def live(
        self, config: AnalysisConfig, channels: Sequence[str], header: Mapping[str, Any]
    ) -> LiveAboutApproaches:
        """The readings about their own approach's mean."""
        return LiveAboutApproaches(config, channels, header)

    def approaches(self, inputs: MethodInputs) -> Approaches:
        """The approaches of a CSV table or a session."""
        if inputs.table is not None:
            return table_approaches(inputs.table)
        assert inputs.session is not None
        return session_approaches(inputs.session)

    def batch(self, inputs: MethodInputs) -> Judgement:
        """The ISO 230-2 figures (no capability analysis, no verdict)."""
        targets, rising, deviations = self.approaches(inputs)
        result = axis_positioning(
            targets,
            rising,
            deviations,
            resolution=inputs.config.resolution,
            unit=inputs.config.unit,
        )
        return Judgement(None, result, (fitted(result.lines(), inputs.width),))

    def json(self, result: Any) -> dict[str, Any]:
        """The figures: ``B``, ``R``, ``E``, ``M``, ``A`` ... and ``targets``."""
        return result.as_json()

    def count(self, result: Any) -> str:
        """``5 targets, 50 approaches``."""
        approaches = sum(t.n_up + t.n_down for t in result.targets)
        return f"{len(result.targets)} targets, {approaches} approaches"

    def charts(self, inputs: MethodInputs, judgement: Judgement, kit: ChartKit) -> Iterator[Chart]:
        """The deviations against the target, up and down, with their ±2s bands."""
        yield (
            "deviation-target",
            "Deviation against the target, approached up and down",
            deviation_chart(judgement.result, self.approaches(inputs), kit),
        )

    def write_wide(self, session: Session, out: SupportsWrite[str]) -> int:
        """``target,direction,cycle,actual``: each accepted stop, its run as the cycle."""
        found = session_stops(session)
        export_comments(session, out)
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(("target", "direction", "cycle", "actual"))
        for _, run, target, up, reading in found:
            writer.writerow((number(target), UP if up else DOWN, run, number(reading)))
        return len(found)

    def demo_rig(self, gauge: GaugeSpec, seed: int, *, stroke_points: int) -> DemoRig:
        """A 1 µm scale along a 400 mm axis that stops long by 50 µm/m and loses 0.020 mm
        at each reversal, with 0.002 mm of scatter (σ), running the standard test cycle."""
        from station.instruments.axis_model import AxisPositioningModel

        model = AxisPositioningModel(
            DEMO_TARGETS, slope=DEMO_SLOPE, backlash=DEMO_BACKLASH, noise=DEMO_NOISE
        )
        return DemoRig(
            model,
            "a simulated linear scale along an axis with backlash (seeded)",
            channel_map={"1": "s"},
            display=_targets_display,
        )


METHOD = Positioning()
