"""The one contract every calibration method keeps: :class:`Method`.

A method is one way of measuring and judging a robot or a gauge (repeatability, relative
accuracy, a gauge linearity study ...). It says what a procedure of it must hold, how its
sessions are analysed live and afterwards, what its report, JSON, charts and CSV export hold,
what its sessions record in their header, what happens once one is finished, how its set-up
counts, and how ``station demo`` simulates it. The engine, the record, the commands and the TUI
ask the method; none of them names one.

A method is given a :class:`MethodInputs` (a session file's or a CSV table's readings and the
settings) and gives back a :class:`Judgement`: the capability :class:`Analysis` its verdict
judges (None for a method that judges no readings by capability), its own result, its report
blocks and, where its verdict is its own (a gauge study's ACCEPTABLE), a
:class:`MethodVerdict`. Its live analysis keeps the :class:`LiveVerdict` protocol.

The methods are listed in :mod:`station.methods.catalog`; a site adds its own through the
``station.methods`` entry-point group (:mod:`station.extensions`).
"""

from __future__ import annotations

import csv
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, Literal, Protocol

from station.procedures import AnalysisNeeds, Procedure, step_schema

if TYPE_CHECKING:
    from _typeshed import SupportsWrite

    from station.analysis.summary import Analysis, AnalysisConfig
    from station.instruments.simulator import GaugeSpec
    from station.session.model import Session
    from station.session.tables import ReadingTable

Layout = Literal["tidy", "wide"]
"""A CSV export's layout: a row per reading (tidy) or the table the method's analysis reads."""

OPTIONS = (
    "reference",
    "tolerance",
    "process_variation",
    "order",
    "pool_above",
    "distance",
    "band",
)
"""The values a command line may give a method's batch analysis (``station analyze``): a
reference size, a tolerance, a process variation (6σ), a fit's order, the p above which a Gage
R&R pools its interaction, the two poses a distance is measured between (the text
``P2:P4=27.71``, which the method reads), the radius of a stabilisation band. A method
names the ones it takes in :attr:`Method.options`."""


# -- what a method is given and gives back -----------------------------------------------------


@dataclass(frozen=True)
class MethodInputs:
    """What a batch analysis may read, from a session file or a CSV table: the accepted readings
    of each channel with their cycle numbers and times, the analysis settings, the command
    line's values, and the session or the table itself for what a method reads of its own
    (strokes, placements, typed inputs, a column of joint numbers)."""

    config: AnalysisConfig
    channels: Mapping[str, Any]
    """The accepted readings per channel (numpy arrays)."""
    cycles: Mapping[str, Any] | None = None
    """The cycle number of each reading per channel (None: numbered 1, 2, ...)."""
    excluded_cycles: Sequence[int] = ()
    times: Mapping[str, Any] | None = None
    """The time (s) of each reading per channel, for the drift's trend test."""
    options: Mapping[str, Any] = field(default_factory=dict)
    """Values from the command line (:data:`OPTIONS`), over what a session typed."""
    width: int = 80
    """The report's width in columns (the TUI's summary is narrower than a printout)."""
    session: Session | None = None
    """The session file's content; None for a CSV table."""
    table: ReadingTable | None = None
    """The CSV table; None for a session file."""

    @property
    def header(self) -> Mapping[str, Any] | None:
        """The session's header (None for a CSV table)."""
        return None if self.session is None else self.session.header

    @property
    def input_events(self) -> Sequence[Mapping[str, Any]]:
        """The session's ``input`` events (values typed, with their placement); none for a
        CSV table."""
        return () if self.session is None else tuple(self.session.input_events)

    def option(self, name: str) -> Any:
        """The command line's value ``name`` (:data:`OPTIONS`), else None."""
        return self.options.get(name)


@dataclass(frozen=True)
class MethodVerdict:
    """A method's own verdict (a gauge study's), beside or instead of a capability verdict:
    its word, the sentence that says why (and, when the readings cannot settle it, what would),
    and whether it accepts (None: neither accepted nor refused, e.g. INCONCLUSIVE)."""

    word: str
    sentence: str
    accepted: bool | None


@dataclass(frozen=True)
class Judgement:
    """A method's batch result: the :class:`Analysis` the capability verdict judges (None when
    the method judges none), its own result (None for repeatability), its report blocks (plain
    lines, the same in every report format) and its own verdict, where it has one."""

    analysis: Analysis | None
    result: Any
    sections: tuple[tuple[str, ...], ...]
    verdict: MethodVerdict | None = None


class LiveVerdict(Protocol):
    """A method's live analysis, fed by the engine as events reach the disk."""

    def add_cycle(
        self,
        values: Mapping[str, float],
        cycle: int,
        times: Mapping[str, float] | None = None,
        placement: int | None = None,
    ) -> Mapping[str, Any]:
        """Take one accepted cycle (``times``: each reading's time; ``placement``: the
        repeated block's placement it was taken at, None outside one); per channel an update
        whose ``alarms`` are new. A cycle of a ``parts`` step comes with the keyword ``part``
        (the part it measured): the live analysis of a method whose procedures present parts
        takes it."""
        ...

    def add_stroke(self, outcome: Any) -> None:
        """Take one whole streamed stroke (its ``profile`` and ``direction``)."""
        ...

    def snapshot(self) -> Analysis:
        """The analysis so far (StationError while there is nothing to analyse)."""
        ...

    def result(self) -> Any:
        """The method's own result so far (per-stroke straightness...), or None."""
        ...

    def rebuilt(self, cycles: Sequence[tuple[Any, ...]], session: Session | None) -> LiveVerdict:
        """A fresh live analysis of ``cycles`` (values, number, times, placement, part)
        keeping what is not a cycle (strokes), or taking that from ``session`` when given
        (resume)."""
        ...

    def copy(self) -> LiveCopy:
        """What the analysis holds now, cheaply (no analysis: the engine takes it under its
        lock); its ``snapshot()`` and ``result()`` equal this object's now and are computed
        later, on another thread, while this one goes on taking cycles."""
        ...


class LiveCopy(Protocol):
    """A live analysis as it was at one moment (:meth:`LiveVerdict.copy`)."""

    def snapshot(self) -> Analysis:
        """The analysis (StationError while there is nothing to analyse)."""
        ...

    def result(self) -> Any:
        """The method's own result, or None."""
        ...


# -- the set-up's count ------------------------------------------------------------------------


@dataclass(frozen=True)
class CountField:
    """What the set-up's count field asks for: cycles, placements of a repeated block (fixture
    placements, joints, reference masters) or streamed strokes."""

    label: str
    noun: str
    setup_key: str
    """The ``SessionSetup`` argument it fills: ``cycles``, ``placements`` or ``strokes``."""
    header_key: str
    target: int
    minimum: int
    hint: str
    too_few: str


@dataclass(frozen=True)
class PlacementWords:
    """How a method names the placements of its repeated block in the set-up: the field's
    label, the noun, and the hint (``{low}`` and ``{target}`` are the block's counts)."""

    label: str = "Placements"
    noun: str = "placements"
    hint: str = (
        "fixture placements over the envelope; the report asks for a few ({low} to {target})"
    )
    too_few: str = "Give at least 1 fixture placement."
    fewest: int = 1
    """The fewest placements the method's analysis can judge (``too_few`` says so)."""


# -- charts -----------------------------------------------------------------------------------

Chart = tuple[str, str, Any]
"""One chart of a report: its key, its caption and its matplotlib ``Figure``."""


class ChartKit(Protocol):
    """What a method draws its charts with (the record's figure, colours and labels, so that
    every chart of a report looks alike); given by :mod:`station.record.charts`."""

    @property
    def point(self) -> str: ...
    @property
    def centre(self) -> str: ...
    @property
    def limit(self) -> str: ...
    @property
    def alarm(self) -> str: ...

    def figure(self, width: float = 7.0, height: float = 3.2) -> Any:
        """A new matplotlib ``Figure`` of that size (inches)."""
        ...

    def label(self, text: object) -> str:
        """Text from outside (a channel name, a unit) as a chart may show it."""
        ...

    def number(self, value: float, *, signed: bool = True) -> str:
        """A figure in the session's unit in the one number format (one decimal beyond the
        gauge step: :func:`station.text.format_figure`)."""
        ...

    def legend(self, axes: Any) -> None:
        """The axes' legend, outside the plot (never over the data)."""
        ...


# -- the demo ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class DemoDisplay:
    """What a simulated set-up shows the operator at one placement, for an input step: the
    teach pendant's X, Y, Z, a reference master's size. ``values`` are what the operator types
    (by field name), ``text`` how the display reads, ``hint`` what the demo tells them to do."""

    label: str
    text: str
    values: Mapping[str, Any]
    hint: str


@dataclass(frozen=True)
class DemoRig:
    """A method's simulated set-up for ``station demo``: the simulator's model, the channel
    map, the trigger and push rate, and in words what it is.

    ``loops``: the robot can run a playback loop (leave the fixture and come back every
    ``--cycle-period`` seconds, each return a cycle under the ``arrival`` trigger).
    ``display(model, placement, unit)``: what the set-up shows at an input step (None: nothing).
    """

    model: Any
    description: str
    channel_map: Mapping[str, str] = field(default_factory=lambda: {"1": "x", "2": "y", "3": "z"})
    trigger: str = "poll"
    push_rate: float = 0.0
    loops: bool = False
    display: Callable[[Any, int | None, str], DemoDisplay | None] | None = None


# -- the method ---------------------------------------------------------------------------------


class Method(ABC):
    """One calibration method (see the module). A method is an instance of a subclass that
    sets :attr:`name` and :attr:`title` and gives :meth:`batch`; everything else has a default
    that fits a method judging the readings of each channel by capability, cycle by cycle."""

    name: ClassVar[str]
    """What a procedure file's ``analysis =`` names (a plain id)."""
    title: ClassVar[str]
    """The report's title, before ``ON <file>``."""
    needs: ClassVar[AnalysisNeeds] = AnalysisNeeds()
    """What a procedure of this method must hold (checked when the file loads)."""
    json_key: ClassVar[str | None] = None
    """Where :meth:`json` goes in the JSON document (``linearity``...); None: at the top."""
    options: ClassVar[tuple[str, ...]] = ()
    """The command line's values (:data:`OPTIONS`) its batch analysis takes."""
    export_layout: ClassVar[Layout] = "tidy"
    """The CSV layout ``station export`` writes by default."""
    reads_columns_by_name: ClassVar[bool] = False
    """Whether its batch reads a CSV table by column name (linearity's stroke, s, h, v; a gains
    table's q) rather than each column as a channel: then no column is left out for counting
    the rows (``station analyze``), since 1, 2, 3 ... may be its own positions or joints."""
    label_columns: ClassVar[tuple[str, ...]] = ()
    """The columns of its CSV table that hold words, not numbers (a Gage R&R's part and
    appraiser, an approach's direction): ``station analyze`` keeps their cells as text
    (``ReadingTable.labels``), never as a channel."""
    drift_chart: ClassVar[bool] = True
    """Whether its report draws the readings over time (cycles in time order; not strokes)."""
    files_in_register: ClassVar[bool] = False
    """Whether its finished sessions are filed in the gauge register (:meth:`file_in_register`)."""
    limits_help: ClassVar[str] = ""
    """A sentence the set-up shows under the limits: how this method judges them ("" none)."""
    placement_words: ClassVar[PlacementWords] = PlacementWords()
    """How the set-up names the placements of its repeated block."""
    demo_words: ClassVar[str | None] = None
    """The set-up ``station demo`` simulates for it, in words; None: no simulated set-up."""

    # -- the analysis ----------------------------------------------------------------------

    def live(
        self, config: AnalysisConfig, channels: Sequence[str], header: Mapping[str, Any]
    ) -> LiveVerdict:
        """The live analysis the engine feeds while a session of this method runs (by
        default cycles, O(1) per cycle, equal to the batch analysis of the readings)."""
        from station.methods.live import LiveCycles

        return LiveCycles(config, channels, header)

    @abstractmethod
    def batch(self, inputs: MethodInputs) -> Judgement:
        """The analysis of a session file or a CSV table (StationError naming what is missing
        when there is nothing to analyse yet)."""

    def json(self, result: Any) -> dict[str, Any]:
        """Its own result in the JSON document (``station analyze --json``)."""
        return {}

    def count(self, result: Any) -> str | None:
        """What a session measured in words (``7 strokes``); None: its cycles."""
        return None

    def recognises(self, session: Session) -> bool:
        """True when ``session`` holds what this method judges although its header does not
        say (a file written before headers recorded the method: streamed strokes are
        linearity's)."""
        return False

    # -- the session -----------------------------------------------------------------------

    def header_fields(self, fields: Mapping[str, Any]) -> dict[str, Any]:
        """Fields a new session's header records for this method, given its other fields (the
        gauge checks covering a repeatability session's gauges, a study's conditions)."""
        return {}

    def finished(self, path: Path) -> list[str]:
        """What happens once a session of this method is finished and closed (a gauge study
        files itself in the gauge register); the operator messages to show. StationError: a
        warning, never a lost session."""
        return self.file_in_register(path) if self.files_in_register else []

    def file_in_register(self, path: Path, register: Path | None = None) -> list[str]:
        """File the finished session at ``path`` in the gauge register (``register``: another
        register file); the sentences to show. StationError when it cannot."""
        from station.errors import StationError

        raise StationError(f"a {self.name} session files nothing in the gauge register.")

    # -- the record ------------------------------------------------------------------------

    def charts(self, inputs: MethodInputs, judgement: Judgement, kit: ChartKit) -> Iterable[Chart]:
        """Its own charts of a report, before the histograms and control charts every
        report draws of the judged channels."""
        return ()

    def write_wide(self, session: Session, out: SupportsWrite[str]) -> int:
        """Write ``session`` as the CSV table this method's analysis reads (``station export
        --layout wide``); the data rows. By default ``cycle``, ``t`` and one column per
        channel of the accepted cycles."""
        from station.methods.tables import export_comments, number
        from station.session.model import event_seconds

        export_comments(session, out)
        writer = csv.writer(out, lineterminator="\n")
        # ``t``: the cycle's time in seconds (the drift's trend reads it back).
        writer.writerow(("cycle", "t", *session.channels))
        rows = 0
        for cycle_number in session.accepted_cycles:
            cycle = session.cycles[cycle_number]
            readings = cycle.readings
            if all(channel in readings for channel in session.channels):
                values = (number(readings[c].value) for c in session.channels)
                writer.writerow((cycle_number, repr(event_seconds(cycle.t)), *values))
                rows += 1
        return rows

    # -- the set-up ------------------------------------------------------------------------

    def count_field(self, procedure: Procedure) -> CountField:
        """The set-up's count field for ``procedure``: strokes for a streamed step, the
        placements of a repeated block (named by :attr:`placement_words`), else cycles."""
        steps = list(procedure.steps)
        stroke = next((s for s in steps if step_schema(s.kind).direction), None)
        block = next((s for s in steps if step_schema(s.kind).block), None)
        if stroke is not None:
            target = int(stroke.count_target or procedure.cycles_target)
            low = int(stroke.count_min or target)
            # Fewer strokes are allowed (a short trial run); the report's range is said.
            return CountField(
                "Strokes",
                "strokes",
                "strokes",
                "strokes_target",
                target,
                2,
                f"A↔B strokes; the report asks for {low} to {target}",
                f"Give at least 2 strokes (one each way); the report asks for {low} to {target}.",
            )
        if block is not None:
            target = int(block.count_target or 1)
            low = int(block.count_min or target)
            words = self.placement_words
            return CountField(
                words.label,
                words.noun,
                "placements",
                "placements_target",
                target,
                words.fewest,
                words.hint.format(low=low, target=target),
                words.too_few,
            )
        # Fewer cycles are allowed (a short trial run, e.g. the demo's --count 5): the verdict
        # says it is provisional below the report's minimum.
        return CountField(
            "Cycles",
            "cycles",
            "cycles",
            "cycles_target",
            procedure.cycles_target,
            2,
            f"the report asks for {procedure.cycles_min} to {procedure.cycles_target}",
            f"Give at least 2 cycles; the report asks for {procedure.cycles_min} to "
            f"{procedure.cycles_target}.",
        )

    def judged_channels(self, procedure: Procedure) -> list[str]:
        """The channels that take spec limits: all but a streamed step's position channel (a
        linear scale measures where along the bar, not an error); none when the method judges
        no spec limits (:attr:`AnalysisNeeds.limits`)."""
        if not self.needs.limits:
            return []
        positions = {s.direction_channel for s in procedure.all_steps() if s.direction_channel}
        return [c for c in procedure.channels if c not in positions]

    # -- the demo --------------------------------------------------------------------------

    def demo_rig(self, gauge: GaugeSpec, seed: int, *, stroke_points: int) -> DemoRig | None:
        """The simulated set-up ``station demo`` runs this method against (``gauge``: the
        demo's indicator, ``stroke_points``: points per streamed stroke); None: none."""
        return None
