"""Loading a procedure file: read its bytes (bounded), parse the TOML, validate every key into a
:class:`~station.procedures.model.Procedure`; every fault names the file, the step and what is
wrong."""

from __future__ import annotations

import hashlib
import math
import os
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from station.errors import StationError
from station.inputfiles import read_input_bytes
from station.instruments.arrival import ArrivalConfig
from station.instruments.triggers import TRIGGERS
from station.instruments.zeroing import DEFAULT_ZERO_SETTLE, DEFAULT_ZERO_STILL
from station.procedures.checker import TOML_DEPTH_LIMIT, Checker, toml_nesting_depth
from station.procedures.kinds import (
    analysis_kinds,
    analysis_needs,
    step_kinds,
    step_schema,
)
from station.procedures.model import (
    DEFAULT_CAUSES,
    DEFAULT_CYCLES_MIN,
    DEFAULT_CYCLES_TARGET,
    ID_PATTERN,
    OTHER_CAUSE,
    UNITS,
    AnalysisKind,
    InputField,
    Limit,
    Procedure,
    Step,
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
    path = Path(path)
    if not os.path.lexists(path):
        raise StationError(f"procedure file {path} does not exist")
    # A FIFO or a device named *.toml is refused before it is read (it would hang or grow).
    data = read_input_bytes(path, "procedure file", PROCEDURE_FILE_LIMIT)
    return parse_procedure(data, path)


PROCEDURE_FILE_LIMIT = 1 << 20
"""The largest procedure file read (1 MiB; the built-in ones are a few KiB)."""


def parse_procedure(data: bytes, path: Path) -> Procedure:
    """Validate the bytes of a procedure file (``path`` is used in messages and kept)."""
    check = Checker(path)
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
    if not ID_PATTERN.match(procedure_id):
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
    arrival = _parse_arrival(
        check, check.get(table, "arrival", dict, "", required=False), tuple(channels)
    )
    trigger = check.get(table, "trigger", str, "", required=False)
    if trigger is not None and trigger not in TRIGGERS:
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


def _parse_causes(check: Checker, value: Any) -> tuple[str, ...]:
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


def _parse_arrival(
    check: Checker, table: Mapping[str, Any] | None, channels: tuple[str, ...]
) -> ArrivalConfig:
    """The ``[arrival]`` table: band, still, settle, timeout, the indicators' stop and its
    reading (each optional)."""
    if not table:
        return ArrivalConfig()
    where = "[arrival]"
    check.only_keys(
        table, ("band", "still", "settle", "timeout", "stop", "free_travel", "trace"), where
    )
    numbers = ("band", "still", "settle", "timeout")
    given: dict[str, Any] = {
        key: check.number(table, key, where) for key in table if key in numbers
    }
    for key, value in given.items():
        if not value > 0:
            raise check.fail(where, f"{key!r} must be greater than 0, not {value}")
    if "stop" in table:
        if table["stop"] not in ("low", "high"):
            raise check.fail(where, f'\'stop\' must be "low" or "high", not {table["stop"]!r}')
        given["stop"] = table["stop"]
    if "free_travel" in table:
        given["free_travel"] = _free_travel(check, table["free_travel"], channels, where)
    if "trace" in table:
        trace = table["trace"]
        if isinstance(trace, bool) or not isinstance(trace, int):
            raise check.fail(where, "'trace' must be a whole number of points per return")
        given["trace"] = trace
    try:
        return ArrivalConfig(**given)
    except StationError as error:
        raise check.fail(where, error.message.rstrip(".")) from None


def _free_travel(
    check: Checker, value: Any, channels: tuple[str, ...], where: str
) -> dict[str, float]:
    """``free_travel``: one finite number for every channel, or a table of them by channel."""
    table = value if isinstance(value, Mapping) else dict.fromkeys(channels, value)
    unknown = [str(c) for c in table if c not in channels]
    if unknown:
        raise check.fail(
            where, f"'free_travel' names {', '.join(unknown)}, not a channel of this procedure"
        )
    stops = {}
    for channel, number in table.items():
        if isinstance(number, bool) or not isinstance(number, int | float):
            raise check.fail(where, f"'free_travel' of {channel} must be a number")
        if not math.isfinite(number):
            raise check.fail(where, f"'free_travel' of {channel} must be finite, not {number}")
        stops[str(channel)] = float(number)
    return stops


def _analysis_kind(
    check: Checker, declared: Any, steps: tuple[Step, ...], channels: tuple[str, ...]
) -> AnalysisKind:
    """The declared method, checked against what the steps record; else the default
    the steps imply (a stroke step: linearity; a repeat block: relative accuracy)."""
    every_step = [inner for step in steps for inner in (step, *step.steps)]
    schemas = [step_schema(step.kind) for step in every_step]
    if declared is None:
        # The first method whose needs its steps and channels meet (a repeat block over x alone
        # is judged as the default method is); else the default, first in the catalog.
        known = analysis_kinds()
        for name in known:
            needs = analysis_needs(name)
            if (
                needs.implied
                and needs.facet
                and any(getattr(schema, needs.facet) for schema in schemas)
                and set(needs.channels) <= set(channels)
            ):
                return name
        return known[0]
    if declared not in analysis_kinds():
        listed = ", ".join(analysis_kinds())
        raise check.fail("", f"'analysis' must be one of {listed}, not {declared!r}")
    needs = analysis_needs(declared)
    if needs.facet:
        # A facet inside a block: the steps of the blocks (a cycles step per joint).
        pool = (
            [
                step_schema(inner.kind)
                for step in steps
                if step_schema(step.kind).block
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
    check: Checker, table: Mapping[str, Any] | None, channels: tuple[str, ...]
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
    check: Checker
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
    if not ID_PATTERN.match(step_id):
        raise check.fail(where, f"'id' {step_id!r} may hold only letters, digits, '.', '_', '-'")
    where = f"step {number} ({step_id})"
    if step_id in context.seen:
        raise check.fail(
            where, f"duplicate step id {step_id!r} (also step {context.seen[step_id]})"
        )
    context.seen[step_id] = number
    kind = check.text(raw, "kind", where)
    if kind not in step_kinds():
        raise check.fail(
            where, f"unknown step kind {kind!r}; known kinds: {', '.join(step_kinds())}"
        )
    schema = step_schema(kind)
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
            seconds = check.number(raw, key, where, required=False)
            if seconds is not None and not seconds > 0:
                raise check.fail(where, f"{key!r} must be greater than 0, not {seconds}")
            values[key] = default if seconds is None else seconds
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


def _parse_fields(check: Checker, raw: Mapping[str, Any], where: str) -> tuple[InputField, ...]:
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
        if not ID_PATTERN.match(name):
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
