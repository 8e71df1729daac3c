"""Procedures as data: load and validate ``procedures/*.toml`` into frozen dataclasses.

A procedure file is TOML read with :mod:`tomllib`; nothing in it is ever executed. Every fault
found on load is a :class:`~station.errors.StationError` naming the file, the step (number and
id) and what is wrong, so a site editing its own procedure sees exactly where to look.

The file format (see ``procedures/repeatability.toml`` for a full example)::

    id = "repeatability"            # letters, digits, '.', '_' and '-'
    title = "..."
    version = "1.0"                 # a string
    report_section = "2.6"
    description = "..."             # optional
    channels = ["x", "y", "z"]
    unit = "in"                     # "in" or "mm"
    resolution = 0.0001             # the gauge's resolution in `unit`
    analysis = "repeatability"      # optional: repeatability, relative_accuracy, linearity,
                                    # gauge_check, joint_troubleshooting or gain_schedule;
                                    # default by the steps: a stroke step -> linearity, a repeat
                                    # block -> relative_accuracy, else repeatability

    [cycles]                        # optional; default min 25, target 30 (the report's 25 to 30)
    min = 25
    target = 30

    trigger = "arrival"             # optional: the trigger a session takes by default where
                                    # the gauges can be read continuously (a polled protocol):
                                    # poll, push, stable or arrival; else poll

    [arrival]                       # optional: the arrival trigger (cycles paced by the robot)
    band = 0.01                     # a channel farther than this from its zero has left the
                                    # fixture (in `unit`; default 100 x the gauge resolution)
    still = 2                       # resolutions the readings may spread and still be still (2)
    settle = 0.5                    # seconds of stillness before the set is taken (0.5)
    timeout = 10.0                  # seconds after its return by which the robot must be
                                    # still, else the return is reported, not recorded (10)

    [limits]                        # optional; either a tolerance about a nominal for every channel
    tolerance = 0.001
    nominal = 0.0                   # optional, default 0
    # ... or per channel:  x = { lsl = -0.001, usl = 0.001, nominal = 0.0 }  or  x = [-0.001, 0.001]

    causes = ["fixture moved", "gauge", "temperature", "robot", "other"]
                                    # optional: the assignable causes an operator acknowledges
                                    # an alarm with (this list is the default; "other" asks for
                                    # a text and is always offered)

    [[steps]]
    id = "fixture"
    kind = "check"                  # check input zero capture cycles stroke repeat
    title = "Fix the fixture"
    text = "Bolt or clamp the 3D fixture to a surface plate within the robot's work envelope."

Keys per step kind, beyond ``id``, ``kind``, ``title`` and ``text``:

- ``input``: ``fields = [{ name, label, type = "number"|"text", unit, required }]``
- ``zero``: ``channels`` (default: all), ``readings`` (per channel, 2 or more: the zero is
  their mean; default 5, or 3 DATA presses with the push trigger), ``settle`` (seconds
  the readings are spread over; default 1.0) and ``still`` (resolutions the readings may spread
  before a gauge counts as moving and the zero is refused; default 3)
- ``capture``: ``channels`` (default: all the procedure's channels)
- ``cycles``: ``channels``, ``min``, ``target`` (default: the procedure's cycle counts), ``prompt``
  (shown before each cycle; ``{cycle}`` and ``{count}`` are replaced by plain text substitution)
- ``stroke``: ``channels``, ``direction_channel`` (the channel that tracks the position along the
  stroke, e.g. the linear scale ``s``), ``min``, ``target`` (strokes), ``prompt``
- ``repeat``: ``label`` (e.g. ``"placement"``), ``min``, ``target``, ``prompt``, and its own
  ``[[steps.steps]]`` block (no nested ``repeat``)
"""

from __future__ import annotations

import hashlib
import importlib.resources
import math
import os
import re
import tomllib
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from station.errors import StationError
from station.instruments.arrival import ArrivalConfig
from station.instruments.zeroing import (
    DEFAULT_ZERO_SETTLE,
    DEFAULT_ZERO_STILL,
)

StepKind = str
"""A step kind: one of :func:`step_kinds` (the built-ins, and any a handler registered)."""
UNITS: tuple[str, ...] = ("in", "mm")
AnalysisKind = str
"""An analysis kind: one of :func:`analysis_kinds`."""


@dataclass(frozen=True)
class StepSchema:
    """What a step kind may hold in a procedure file, beyond ``id``, ``kind``, ``title`` and
    ``text``: its own ``keys``, and which shared parts apply (so the loader validates a kind it
    has never seen the code of)."""

    keys: tuple[str, ...] = ()
    channels: bool = False
    """``channels`` (default: all the procedure's)."""
    counts: bool = False
    """``min``/``target`` and a ``prompt`` (cycle or stroke counts)."""
    fields: bool = False
    """``fields`` typed by the operator."""
    direction: bool = False
    """``direction_channel``: the channel tracking the position along a stream."""
    block: bool = False
    """A block of inner ``steps`` repeated ``target`` times (no nesting)."""
    zero_window: bool = False
    """``readings``, ``settle`` and ``still``: a zero taken as the mean of several readings."""
    implies_analysis: str | None = None
    """The analysis kind a procedure holding this step defaults to."""

    @property
    def allowed(self) -> tuple[str, ...]:
        """Every key a step of this kind may have beyond the common ones."""
        shared = (
            (("channels",) if self.channels else ())
            + (("min", "target", "prompt") if self.counts else ())
            + (("fields",) if self.fields else ())
            + (("direction_channel",) if self.direction else ())
            + (("label", "min", "target", "prompt", "steps") if self.block else ())
            + (("readings", "settle", "still") if self.zero_window else ())
        )
        return tuple(dict.fromkeys(shared + self.keys))


_STEP_SCHEMAS: dict[str, StepSchema] = {
    "check": StepSchema(),
    "input": StepSchema(fields=True),
    "zero": StepSchema(channels=True, zero_window=True),
    "capture": StepSchema(channels=True),
    "cycles": StepSchema(channels=True, counts=True),
    "stroke": StepSchema(channels=True, counts=True, direction=True, implies_analysis="linearity"),
    "repeat": StepSchema(block=True, implies_analysis="relative_accuracy"),
}


@dataclass(frozen=True)
class AnalysisNeeds:
    """What a procedure must hold for an analysis kind: a step of a kind with ``facet`` (e.g.
    ``direction`` for streamed strokes, ``block`` for placements), inside a repeat block when
    ``facet_in_block``; these ``channels``; and input steps with the number fields ``numbers``
    plus ``more_numbers`` others (a gain schedule's position ``q`` and one field per gain).
    ``facet_words`` and ``numbers_words`` say what is missing when a file lacks it."""

    facet: str | None = None
    facet_words: str = ""
    channels: tuple[str, ...] = ()
    facet_in_block: bool = False
    numbers: tuple[str, ...] = ()
    more_numbers: int = 0
    numbers_words: str = ""
    limits: bool = True
    """Whether the kind's verdict judges the session's spec limits (a gauge check judges
    against its reference and tolerance, a gain schedule judges nothing): a set-up screen
    asks for limits only when it does."""


_ANALYSES: dict[str, AnalysisNeeds] = {
    "repeatability": AnalysisNeeds(),
    "relative_accuracy": AnalysisNeeds(
        facet="block", facet_words="a repeat block (one per placement)", channels=("x", "y", "z")
    ),
    "linearity": AnalysisNeeds(facet="direction", facet_words="a stroke step (streamed strokes)"),
    # The rest of the report's method (station.method_kinds registers them with these needs;
    # they are known here too so that a file declaring them loads without the registry).
    "gauge_check": AnalysisNeeds(
        facet="counts",
        facet_words="a cycles step (the repeated readings)",
        numbers=("reference", "tolerance"),
        numbers_words="an input step with number fields 'reference' and 'tolerance'",
        limits=False,
    ),
    "joint_troubleshooting": AnalysisNeeds(
        facet="counts",
        facet_in_block=True,
        facet_words="a repeat block (one per joint) holding a cycles step",
        channels=("x", "y", "z"),
    ),
    "gain_schedule": AnalysisNeeds(
        numbers=("q",),
        more_numbers=1,
        numbers_words="an input step with a number field 'q' (the position) and one number "
        "field per gain",
        limits=False,
    ),
}


def register_step_schema(kind: str, schema: StepSchema) -> None:
    """Let procedure files use step kind ``kind`` with ``schema`` (called by the step-handler
    registry when a handler is registered)."""
    if not _ID_PATTERN.match(kind):
        raise ValueError(f"a step kind is a plain name, not {kind!r}")
    _STEP_SCHEMAS[kind] = schema


def register_analysis_needs(kind: str, needs: AnalysisNeeds) -> None:
    """Let procedure files declare ``analysis = kind`` (called by the analysis-kind registry)."""
    _ANALYSES[kind] = needs


def step_kinds() -> tuple[str, ...]:
    """The step kinds a procedure file may use."""
    return tuple(_STEP_SCHEMAS)


def analysis_needs(kind: str) -> AnalysisNeeds:
    """What a procedure declaring ``analysis = kind`` must hold (KeyError for an unknown kind)."""
    return _ANALYSES[kind]


def analysis_kinds() -> tuple[str, ...]:
    """The analysis kinds a procedure file may declare."""
    return tuple(_ANALYSES)


DEFAULT_CYCLES_MIN = 25
#: The assignable causes an alarm is acknowledged with when the procedure names none.
DEFAULT_CAUSES: tuple[str, ...] = ("fixture moved", "gauge", "temperature", "robot", "other")
#: The cause that asks the operator to say what it was.
OTHER_CAUSE = "other"
DEFAULT_CYCLES_TARGET = 30
PROCEDURES_ENV = "STATION_PROCEDURES"

_ID_PATTERN = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]*$")


@dataclass(frozen=True)
class InputField:
    """One value an ``input`` step asks the operator for, e.g. the teach pendant's X."""

    name: str
    label: str
    type: Literal["number", "text"] = "number"
    unit: str | None = None
    required: bool = True


@dataclass(frozen=True)
class Step:
    """One step of a procedure. Fields that do not apply to the step's kind keep their defaults.

    ``channels`` is always filled for ``zero``, ``capture``, ``cycles`` and ``stroke`` steps (the
    procedure's channels when the file does not name them). ``count_min``/``count_target`` are
    the cycle counts of a ``cycles`` step, the stroke counts of a ``stroke`` step and the
    repetition counts of a ``repeat`` block; ``None`` for the other kinds.
    """

    id: str
    kind: StepKind
    title: str
    text: str = ""
    fields: tuple[InputField, ...] = ()
    channels: tuple[str, ...] = ()
    count_min: int | None = None
    count_target: int | None = None
    prompt: str = ""
    direction_channel: str | None = None
    label: str = ""
    steps: tuple[Step, ...] = ()
    number: str = ""
    """Where the step is in the file, 1-based: ``"3"``, or ``"5.2"`` inside a repeat block."""
    options: Mapping[str, Any] = field(default_factory=dict)
    """The values of the keys a registered step kind declares as its own (``schema.keys``)."""
    readings: int | None = None
    """A ``zero`` step: readings per channel the zero is the mean of (None: the engine's default
    for the session's trigger, always several; always None for other kinds)."""
    settle: float | None = None
    """A ``zero`` step: seconds its readings are spread over."""
    still: float | None = None
    """A ``zero`` step: resolutions its readings may spread before the zero is refused."""

    def prompt_for(self, cycle: int, count: int) -> str:
        """The per-cycle prompt with ``{cycle}`` and ``{count}`` filled in (plain substitution)."""
        return self.prompt.replace("{cycle}", str(cycle)).replace("{count}", str(count))


@dataclass(frozen=True)
class Limit:
    """Specification limits of one channel, in the procedure's unit."""

    lsl: float
    usl: float
    nominal: float = 0.0


@dataclass(frozen=True)
class Procedure:
    """A validated procedure file. ``sha256`` is the hash of the file's bytes (kept in sessions)."""

    id: str
    title: str
    version: str
    report_section: str
    description: str
    channels: tuple[str, ...]
    unit: str
    resolution: float
    cycles_min: int
    cycles_target: int
    limits: Mapping[str, Limit]
    """Default limits per channel; empty when the file gives none (the set-up asks)."""
    steps: tuple[Step, ...]
    path: Path
    sha256: str
    analysis: AnalysisKind = "repeatability"
    """How its sessions are analysed: the file's ``analysis``, else by its steps."""
    arrival: ArrivalConfig = field(default_factory=ArrivalConfig)
    """The ``arrival`` trigger's parameters: the file's ``[arrival]``, else the defaults."""
    trigger: str | None = None
    """The trigger its sessions take by default where the gauges can be read continuously (the
    file's ``trigger``); None: poll."""
    causes: tuple[str, ...] = DEFAULT_CAUSES
    """The assignable causes an alarm is acknowledged with; "other" (with a text) is last."""

    def all_steps(self) -> Iterator[Step]:
        """Every step in file order, including those inside repeat blocks (after their block)."""
        for step in self.steps:
            yield step
            yield from step.steps

    def step(self, step_id: str) -> Step:
        """The step with this id, anywhere in the procedure; StationError when there is none."""
        for step in self.all_steps():
            if step.id == step_id:
                return step
        raise StationError(f"procedure {self.id!r} has no step {step_id!r}")


@dataclass(frozen=True)
class ProcedureCatalog:
    """The procedures found by :func:`discover_procedures`, one per id (a user's wins)."""

    procedures: tuple[Procedure, ...]
    builtin_ids: frozenset[str] = frozenset()
    """Ids whose winning procedure is the built-in one."""
    overridden: Mapping[str, Path] = field(default_factory=dict)
    """Id -> the file that was overridden (built-in or an earlier folder's)."""
    notes: tuple[str, ...] = ()
    """Sentences for the listing: overrides, and files that failed to load (with their error)."""
    errors: tuple[str, ...] = ()
    """The load errors alone (also in ``notes``)."""
    overrides_builtin: frozenset[str] = frozenset()
    """Ids where a site's procedure replaced the built-in one."""

    def get(self, procedure_id: str) -> Procedure:
        """The procedure with this id; StationError naming the known ids when there is none."""
        for procedure in self.procedures:
            if procedure.id == procedure_id:
                return procedure
        known = ", ".join(p.id for p in self.procedures) or "none"
        hint = f" ({len(self.errors)} file(s) failed to load: run `station procedures`)"
        raise StationError(
            f"no procedure {procedure_id!r}; known procedures: {known}"
            + (hint if self.errors else "")
        )

    def ids(self) -> tuple[str, ...]:
        """The ids, sorted."""
        return tuple(p.id for p in self.procedures)

    def is_builtin(self, procedure_id: str) -> bool:
        """True when the procedure with this id is the built-in one (not overridden)."""
        return procedure_id in self.builtin_ids

    def origin(self, procedure_id: str) -> str:
        """``built-in``, ``site`` or ``site, overrides built-in``: for listings."""
        if procedure_id in self.builtin_ids:
            return "built-in"
        if procedure_id in self.overrides_builtin:
            return "site, overrides built-in"
        return "site"


# --------------------------------------------------------------------------------------------
# Loading and validation


class _Checker:
    """Reads typed values out of TOML tables, raising errors that name the file and the place."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def fail(self, where: str, fault: str) -> StationError:
        place = f"{where}: " if where else ""
        return StationError(f"procedure file {self.path}: {place}{fault}")

    def only_keys(self, table: Mapping[str, Any], allowed: Iterable[str], where: str) -> None:
        unknown = sorted(set(table) - set(allowed))
        if unknown:
            raise self.fail(
                where,
                f"unknown key(s) {', '.join(map(repr, unknown))}; "
                f"allowed: {', '.join(sorted(allowed))}",
            )

    def get(
        self,
        table: Mapping[str, Any],
        key: str,
        kind: type | tuple[type, ...],
        where: str,
        *,
        required: bool = True,
        default: Any = None,
    ) -> Any:
        if key not in table:
            if required:
                raise self.fail(where, f"missing required key {key!r}")
            return default
        value = table[key]
        kinds = kind if isinstance(kind, tuple) else (kind,)
        # TOML booleans are ints in Python; a boolean is never a number here.
        if isinstance(value, bool) and bool not in kinds:
            raise self.fail(where, f"{key!r} must be {_type_name(kinds)}, not a boolean")
        if not isinstance(value, kinds):
            raise self.fail(
                where, f"{key!r} must be {_type_name(kinds)}, not {_toml_type(value)} {value!r}"
            )
        return value

    def text(self, table: Mapping[str, Any], key: str, where: str, **kw: Any) -> str:
        value = self.get(table, key, str, where, **kw)
        if kw.get("required", True) and not str(value).strip():
            raise self.fail(where, f"{key!r} must not be empty")
        return value

    def number(self, table: Mapping[str, Any], key: str, where: str, **kw: Any) -> float:
        value = self.get(table, key, (int, float), where, **kw)
        if value is None:
            return value
        try:
            number = float(value)
        except OverflowError:
            number = math.inf
        if not math.isfinite(number):
            raise self.fail(where, f"{key!r} must be a finite number, not {value}")
        return number

    def count(self, table: Mapping[str, Any], key: str, where: str, **kw: Any) -> int | None:
        value = self.get(table, key, int, where, **kw)
        if value is not None and value < 1:
            raise self.fail(where, f"{key!r} must be at least 1, not {value}")
        return value

    def names(
        self, table: Mapping[str, Any], key: str, where: str, **kw: Any
    ) -> tuple[str, ...] | None:
        value = self.get(table, key, list, where, **kw)
        if value is None:
            return None
        if not value:
            raise self.fail(where, f"{key!r} must name at least one channel")
        for item in value:
            if not isinstance(item, str) or not _ID_PATTERN.match(item):
                raise self.fail(where, f"{key!r} holds {item!r}, which is not a channel name")
        if len(set(value)) != len(value):
            raise self.fail(where, f"{key!r} names a channel twice: {value!r}")
        return tuple(value)


def _type_name(kinds: tuple[type, ...]) -> str:
    names = {str: "a string", int: "an integer", float: "a number", list: "a list"}
    names |= {dict: "a table", bool: "true or false"}
    if set(kinds) == {int, float}:
        return "a number"
    return " or ".join(names.get(k, k.__name__) for k in kinds)


def _toml_type(value: Any) -> str:
    return {str: "a string", int: "an integer", float: "a number", list: "a list"}.get(
        type(value), "a table" if isinstance(value, dict) else type(value).__name__
    )


_TOP_KEYS = (
    "id",
    "title",
    "version",
    "report_section",
    "description",
    "channels",
    "unit",
    "resolution",
    "analysis",
    "cycles",
    "limits",
    "causes",
    "steps",
    "arrival",
    "trigger",
)
_COMMON_STEP_KEYS = ("id", "kind", "title", "text")
_FIELD_KEYS = ("name", "label", "type", "unit", "required")


def load_procedure(path: str | os.PathLike[str]) -> Procedure:
    """Read and validate one procedure file; StationError naming the file, step and fault."""
    from station.inputfiles import read_input_bytes

    path = Path(path)
    if not os.path.lexists(path):
        raise StationError(f"procedure file {path} does not exist")
    # A FIFO or a device named *.toml is refused before it is read (it would hang or grow).
    data = read_input_bytes(path, "procedure file", PROCEDURE_FILE_LIMIT)
    return parse_procedure(data, path)


PROCEDURE_FILE_LIMIT = 1 << 20
"""The largest procedure file read (1 MiB; the built-in ones are a few KiB)."""
TOML_DEPTH_LIMIT = 16
"""The deepest nesting of arrays and inline tables a procedure file may have (tomllib recurses
once per level: a file of ``[[[[...`` would otherwise end in a RecursionError)."""


def toml_nesting_depth(text: str) -> int:
    """The deepest nesting of ``[`` and ``{`` in TOML ``text`` outside strings and comments
    (a table header ``[a]`` or ``[[a]]`` counts its brackets too). Linear, no recursion."""
    depth = deepest = 0
    index, length = 0, len(text)
    while index < length:
        char = text[index]
        if char == "#":
            newline = text.find("\n", index)
            index = length if newline < 0 else newline
            continue
        if char in "\"'":
            triple = text.startswith(char * 3, index)
            quote = char * 3 if triple else char
            index += len(quote)
            while index < length:
                if char == '"' and text[index] == "\\":
                    index += 2
                    continue
                if text.startswith(quote, index):
                    index += len(quote)
                    break
                if not triple and text[index] == "\n":
                    break
                index += 1
            continue
        if char in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif char in "]}":
            depth = max(depth - 1, 0)
        index += 1
    return deepest


def parse_procedure(data: bytes, path: Path) -> Procedure:
    """Validate the bytes of a procedure file (``path`` is used in messages and kept)."""
    check = _Checker(path)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise check.fail("", "is not UTF-8 text") from None
    if toml_nesting_depth(text) > TOML_DEPTH_LIMIT:
        raise check.fail(
            "", f"nests arrays or tables more than {TOML_DEPTH_LIMIT} deep; no procedure does"
        )
    try:
        table = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise check.fail("", f"is not valid TOML ({error})") from None
    except RecursionError:
        raise check.fail("", "nests too deeply to read") from None

    check.only_keys(table, _TOP_KEYS, "")
    procedure_id = check.text(table, "id", "")
    if not _ID_PATTERN.match(procedure_id):
        raise check.fail("", f"'id' {procedure_id!r} may hold only letters, digits, '.', '_', '-'")
    title = check.text(table, "title", "")
    version = check.text(table, "version", "")
    report_section = check.text(table, "report_section", "")
    description = check.get(table, "description", str, "", required=False, default="")
    channels = check.names(table, "channels", "")
    assert channels is not None
    unit = check.text(table, "unit", "")
    if unit not in UNITS:
        raise check.fail("", f"'unit' must be one of {', '.join(UNITS)}, not {unit!r}")
    resolution = check.number(table, "resolution", "")
    if not resolution > 0:
        raise check.fail("", f"'resolution' must be greater than 0, not {resolution}")

    cycles = check.get(table, "cycles", dict, "", required=False, default={})
    check.only_keys(cycles, ("min", "target"), "[cycles]")
    cycles_min = check.count(cycles, "min", "[cycles]", required=False)
    cycles_target = check.count(cycles, "target", "[cycles]", required=False)
    cycles_min = cycles_min or min(DEFAULT_CYCLES_MIN, cycles_target or DEFAULT_CYCLES_MIN)
    cycles_target = cycles_target or max(DEFAULT_CYCLES_TARGET, cycles_min)
    if cycles_min > cycles_target:
        raise check.fail("[cycles]", f"min {cycles_min} is more than target {cycles_target}")

    limits = _parse_limits(check, check.get(table, "limits", dict, "", required=False), channels)
    arrival = _parse_arrival(check, check.get(table, "arrival", dict, "", required=False))
    trigger = check.get(table, "trigger", str, "", required=False)
    if trigger is not None:
        from station.instruments.gauge import TRIGGERS

        if trigger not in TRIGGERS:
            raise check.fail("", f"'trigger' must be one of {', '.join(TRIGGERS)}, not {trigger!r}")

    raw_steps = check.get(table, "steps", list, "")
    if not raw_steps:
        raise check.fail("", "has no [[steps]]")
    context = _StepContext(check, channels, cycles_min, cycles_target, seen={})
    steps = tuple(
        _parse_step(context, raw, str(index)) for index, raw in enumerate(raw_steps, start=1)
    )
    analysis = _analysis_kind(check, table.get("analysis"), steps, channels)
    causes = _parse_causes(check, table.get("causes"))
    return Procedure(
        id=procedure_id,
        title=title,
        version=version,
        report_section=report_section,
        description=description.strip(),
        channels=channels,
        unit=unit,
        resolution=resolution,
        cycles_min=cycles_min,
        cycles_target=cycles_target,
        limits=limits,
        steps=steps,
        path=path,
        sha256=hashlib.sha256(data).hexdigest(),
        analysis=analysis,
        arrival=arrival,
        trigger=trigger,
        causes=causes,
    )


def _parse_causes(check: _Checker, value: Any) -> tuple[str, ...]:
    """The file's ``causes``: distinct, non-empty, one line each; "other" is added at the end
    when missing, so an operator can always name a cause the list did not foresee."""
    if value is None:
        return DEFAULT_CAUSES
    if not isinstance(value, list) or not value:
        raise check.fail("", '\'causes\' must be a list of short texts, e.g. ["gauge", "other"]')
    causes: list[str] = []
    for item in value:
        if not isinstance(item, str) or not item.strip() or "\n" in item or len(item) > 60:
            raise check.fail("", f"'causes' holds {item!r}: give one line of text (60 at most)")
        if item.strip() in causes:
            raise check.fail("", f"'causes' names {item.strip()!r} twice")
        causes.append(item.strip())
    if OTHER_CAUSE not in causes:
        causes.append(OTHER_CAUSE)
    return tuple(causes)


def _parse_arrival(check: _Checker, table: Mapping[str, Any] | None) -> ArrivalConfig:
    """The ``[arrival]`` table: band, still, settle, timeout (each optional)."""
    if not table:
        return ArrivalConfig()
    where = "[arrival]"
    check.only_keys(table, ("band", "still", "settle", "timeout"), where)
    given = {key: check.number(table, key, where) for key in table}
    for key, value in given.items():
        if not value > 0:
            raise check.fail(where, f"{key!r} must be greater than 0, not {value}")
    try:
        return ArrivalConfig(**given)
    except StationError as error:
        raise check.fail(where, error.message.rstrip(".")) from None


def _analysis_kind(
    check: _Checker, declared: Any, steps: tuple[Step, ...], channels: tuple[str, ...]
) -> AnalysisKind:
    """The declared analysis kind, checked against what the steps record; else the default
    the steps imply (a stroke step: linearity; a repeat block: relative accuracy)."""
    every_step = [inner for step in steps for inner in (step, *step.steps)]
    schemas = [_STEP_SCHEMAS[step.kind] for step in every_step]
    if declared is None:
        # The first kind the steps imply whose channels the procedure has (a repeat block over
        # x alone is judged as repeatability).
        implied = [
            schema.implies_analysis
            for schema in schemas
            if schema.implies_analysis
            and set(_ANALYSES[schema.implies_analysis].channels) <= set(channels)
        ]
        return implied[0] if implied else "repeatability"
    if declared not in _ANALYSES:
        raise check.fail("", f"'analysis' must be one of {', '.join(_ANALYSES)}, not {declared!r}")
    needs = _ANALYSES[declared]
    if needs.facet:
        # A facet inside a block: the steps of the blocks (a cycles step per joint).
        pool = (
            [
                _STEP_SCHEMAS[inner.kind]
                for step in steps
                if _STEP_SCHEMAS[step.kind].block
                for inner in step.steps
            ]
            if needs.facet_in_block
            else schemas
        )
        if not any(getattr(schema, needs.facet) for schema in pool):
            raise check.fail("", f"'analysis' {declared} needs {needs.facet_words}")
    if not set(needs.channels) <= set(channels):
        raise check.fail(
            "", f"'analysis' {declared} needs the channels {', '.join(needs.channels)}"
        )
    numbers = _number_fields(steps)
    if not set(needs.numbers) <= numbers or len(numbers) < len(needs.numbers) + needs.more_numbers:
        raise check.fail("", f"'analysis' {declared} needs {needs.numbers_words}")
    return str(declared)


def _number_fields(steps: tuple[Step, ...]) -> set[str]:
    """The names of the number fields of every input step (a block's too)."""
    every = [*steps, *(inner for step in steps for inner in step.steps)]
    return {
        f.name for step in every if step.kind == "input" for f in step.fields if f.type == "number"
    }


def _parse_limits(
    check: _Checker, table: Mapping[str, Any] | None, channels: tuple[str, ...]
) -> dict[str, Limit]:
    if not table:
        return {}
    where = "[limits]"
    if "tolerance" in table:
        check.only_keys(table, ("tolerance", "nominal"), where)
        tolerance = check.number(table, "tolerance", where)
        nominal = check.number(table, "nominal", where, required=False, default=0.0)
        if not tolerance > 0:
            raise check.fail(where, f"'tolerance' must be greater than 0, not {tolerance}")
        return {ch: Limit(nominal - tolerance, nominal + tolerance, nominal) for ch in channels}
    check.only_keys(table, channels, where + " (a tolerance, or one entry per channel)")
    limits: dict[str, Limit] = {}
    for channel, spec in table.items():
        place = f"{where} {channel}"
        if isinstance(spec, list):
            if len(spec) != 2 or not all(
                isinstance(v, int | float)
                and not isinstance(v, bool)
                and abs(v) < 1e300
                and math.isfinite(v)
                for v in spec
            ):
                raise check.fail(place, f"must be [lsl, usl] (two numbers), not {spec!r}")
            lsl, usl = float(spec[0]), float(spec[1])
            nominal = (lsl + usl) / 2
        elif isinstance(spec, dict):
            check.only_keys(spec, ("lsl", "usl", "nominal"), place)
            lsl = check.number(spec, "lsl", place)
            usl = check.number(spec, "usl", place)
            nominal = check.number(spec, "nominal", place, required=False, default=(lsl + usl) / 2)
        else:
            raise check.fail(place, f"must be [lsl, usl] or {{ lsl, usl }}, not {spec!r}")
        if not usl > lsl:
            raise check.fail(place, f"impossible limits: usl {usl} is not above lsl {lsl}")
        limits[channel] = Limit(lsl, usl, nominal)
    return limits


@dataclass
class _StepContext:
    check: _Checker
    channels: tuple[str, ...]
    cycles_min: int
    cycles_target: int
    seen: dict[str, str]
    """Step id -> its number, to name both places of a duplicate."""


def _parse_step(context: _StepContext, raw: Any, number: str, *, nested: bool = False) -> Step:
    check = context.check
    where = f"step {number}"
    if not isinstance(raw, dict):
        raise check.fail(where, f"must be a table, not {raw!r}")
    step_id = check.text(raw, "id", where)
    if not _ID_PATTERN.match(step_id):
        raise check.fail(where, f"'id' {step_id!r} may hold only letters, digits, '.', '_', '-'")
    where = f"step {number} ({step_id})"
    if step_id in context.seen:
        raise check.fail(
            where, f"duplicate step id {step_id!r} (also step {context.seen[step_id]})"
        )
    context.seen[step_id] = number
    kind = check.text(raw, "kind", where)
    schema = _STEP_SCHEMAS.get(kind)
    if schema is None:
        raise check.fail(
            where, f"unknown step kind {kind!r}; known kinds: {', '.join(_STEP_SCHEMAS)}"
        )
    if schema.block and nested:
        raise check.fail(where, "a repeat block cannot hold another repeat block")
    check.only_keys(raw, _COMMON_STEP_KEYS + schema.allowed, f"{where}, kind {kind}")
    values: dict[str, Any] = {
        "id": step_id,
        "kind": kind,
        "title": check.text(raw, "title", where),
        "text": check.get(raw, "text", str, where, required=False, default="").strip(),
        "number": number,
    }
    if schema.channels:
        channels = check.names(raw, "channels", where, required=False) or context.channels
        missing = [c for c in channels if c not in context.channels]
        if missing:
            raise check.fail(
                where,
                f"names channel(s) {', '.join(missing)} that the procedure lacks "
                f"(its channels: {', '.join(context.channels)})",
            )
        values["channels"] = channels
    if schema.counts or schema.block:
        values["prompt"] = check.get(raw, "prompt", str, where, required=False, default="")
        count_min = check.count(raw, "min", where, required=False)
        count_target = check.count(raw, "target", where, required=False)
        if schema.block:
            if count_target is None:
                raise check.fail(where, "missing required key 'target' (repetitions)")
            count_min = count_min or count_target
        else:
            count_min = count_min or min(context.cycles_min, count_target or context.cycles_min)
            count_target = count_target or max(context.cycles_target, count_min)
        if count_min > count_target:
            raise check.fail(where, f"min {count_min} is more than target {count_target}")
        values["count_min"], values["count_target"] = count_min, count_target
    if schema.fields:
        values["fields"] = _parse_fields(check, raw, where)
    if schema.zero_window:
        readings = check.get(raw, "readings", int, where, required=False)
        if readings is not None and readings < 2:
            raise check.fail(
                where, f"'readings' must be 2 or more (a zero is a mean), not {readings}"
            )
        # Without ``readings`` the engine chooses by the session's trigger (several readings
        # always: one reading is no zero); ``settle`` and ``still`` keep their defaults.
        values["readings"] = readings
        for key, default in (("settle", DEFAULT_ZERO_SETTLE), ("still", DEFAULT_ZERO_STILL)):
            number = check.number(raw, key, where, required=False)
            if number is not None and not number > 0:
                raise check.fail(where, f"{key!r} must be greater than 0, not {number}")
            values[key] = default if number is None else number
    if schema.direction:
        direction = check.text(raw, "direction_channel", where)
        if direction not in values["channels"]:
            raise check.fail(
                where,
                f"direction_channel {direction!r} is not one of the step's channels "
                f"({', '.join(values['channels'])})",
            )
        values["direction_channel"] = direction
    if schema.block:
        values["label"] = check.get(raw, "label", str, where, required=False, default="placement")
        inner = check.get(raw, "steps", list, where)
        if not inner:
            raise check.fail(where, "a repeat block needs at least one step in 'steps'")
        values["steps"] = tuple(
            _parse_step(context, item, f"{number}.{index}", nested=True)
            for index, item in enumerate(inner, start=1)
        )
    own = {key: raw[key] for key in schema.keys if key in raw}
    if own:
        values["options"] = own
    return Step(**values)


def _parse_fields(check: _Checker, raw: Mapping[str, Any], where: str) -> tuple[InputField, ...]:
    items = check.get(raw, "fields", list, where)
    if not items:
        raise check.fail(where, "an input step needs at least one entry in 'fields'")
    fields: list[InputField] = []
    for index, item in enumerate(items, start=1):
        place = f"{where}, field {index}"
        if not isinstance(item, dict):
            raise check.fail(place, f"must be a table {{ name, label, type }}, not {item!r}")
        check.only_keys(item, _FIELD_KEYS, place)
        name = check.text(item, "name", place)
        if not _ID_PATTERN.match(name):
            raise check.fail(place, f"'name' {name!r} may hold only letters, digits, '.', '_', '-'")
        if any(f.name == name for f in fields):
            raise check.fail(place, f"duplicate field name {name!r}")
        field_type = check.get(item, "type", str, place, required=False, default="number")
        if field_type not in ("number", "text"):
            raise check.fail(place, f"'type' must be 'number' or 'text', not {field_type!r}")
        fields.append(
            InputField(
                name=name,
                label=check.get(item, "label", str, place, required=False, default=name),
                type=field_type,
                unit=check.get(item, "unit", str, place, required=False),
                required=check.get(item, "required", bool, place, required=False, default=True),
            )
        )
    return tuple(fields)


# --------------------------------------------------------------------------------------------
# Discovery


def builtin_procedures_dir() -> Path:
    """The folder of the procedures that ship with station.

    In an installed wheel they are the package ``station.builtin_procedures`` (pyproject maps the
    top-level ``procedures/`` folder there); in a source or editable checkout that package does
    not import, so the checkout's ``procedures/`` folder is used.
    """
    try:
        # The folder has no __init__.py: on Python 3.11 files() of such a namespace package is
        # a MultiplexedPath, so find the folder through the files it holds.
        for entry in importlib.resources.files("station.builtin_procedures").iterdir():
            if entry.name.endswith(".toml") and isinstance(entry, Path):
                return entry.parent
    except (ModuleNotFoundError, TypeError, ValueError, OSError):
        pass
    import station

    return Path(station.__file__).resolve().parent.parent / "procedures"


def procedure_dirs_from_env(environ: Mapping[str, str] | None = None) -> tuple[Path, ...]:
    """The folders named in ``STATION_PROCEDURES`` (``os.pathsep``-separated), in order."""
    value = (os.environ if environ is None else environ).get(PROCEDURES_ENV, "")
    return tuple(Path(part) for part in value.split(os.pathsep) if part.strip())


def discover_procedures(
    extra_dirs: Sequence[str | os.PathLike[str]] = (),
    *,
    use_env: bool = True,
) -> ProcedureCatalog:
    """The built-in procedures plus a site's folders, one per id.

    Folders are read in order: built-in, then ``STATION_PROCEDURES`` (when ``use_env``), then
    ``extra_dirs`` (from ``--procedures``); a later folder's procedure with the same id wins and
    the catalog's notes say so. A named folder that does not exist is a StationError; a file
    that fails to load is listed in ``notes``/``errors`` and skipped, so one bad file does not
    hide the others.
    """
    builtin = builtin_procedures_dir()
    folders: list[tuple[Path, bool]] = [(builtin, True)]
    user_dirs = [*(procedure_dirs_from_env() if use_env else ()), *map(Path, extra_dirs)]
    for folder in user_dirs:
        if not folder.is_dir():
            raise StationError(
                f"procedures folder {folder} does not exist (from the command line or "
                f"{PROCEDURES_ENV}); create it or fix the path"
            )
        if folder.resolve() != builtin.resolve():
            folders.append((folder, False))

    chosen: dict[str, tuple[Procedure, bool]] = {}
    overridden: dict[str, Path] = {}
    overrides_builtin: set[str] = set()
    notes: list[str] = []
    errors: list[str] = []
    for folder, is_builtin in folders:
        for path in sorted(folder.glob("*.toml")):
            try:
                procedure = load_procedure(path)
            except StationError as error:
                errors.append(error.message)
                continue
            previous = chosen.get(procedure.id)
            if previous is not None:
                old, old_builtin = previous
                if old.path.resolve() == path.resolve():
                    continue
                overridden[procedure.id] = old.path
                if old_builtin:
                    overrides_builtin.add(procedure.id)
                what = "built-in" if old_builtin else str(old.path)
                notes.append(f"{procedure.id}: {path} overrides {what} ({old.path})")
            chosen[procedure.id] = (procedure, is_builtin)
    procedures = tuple(p for p, _ in sorted(chosen.values(), key=lambda item: item[0].id))
    builtin_ids = frozenset(p.id for p, is_builtin in chosen.values() if is_builtin)
    notes.extend(f"skipped: {message}" for message in errors)
    return ProcedureCatalog(
        procedures=procedures,
        builtin_ids=builtin_ids,
        overridden=overridden,
        notes=tuple(notes),
        errors=tuple(errors),
        overrides_builtin=frozenset(overrides_builtin),
    )
