"""``station capture``'s input values: ``--input [P:]NAME=VALUE`` and the ``--inputs`` CSV, by
placement, and the check, before anything is written, that every input step can be answered."""

from __future__ import annotations

import csv
from typing import Any

from station.errors import StationError
from station.inputfiles import read_input_bytes

Inputs = dict[int | None, dict[str, str]]
"""Typed values by placement (``None``: for every placement and for steps outside a block)."""


def parse_inputs(items: list[str], table: str | None = None) -> Inputs:
    """``--input [P:]NAME=VALUE`` values and the rows of an ``--inputs`` CSV, by placement."""
    values: Inputs = {None: {}}
    for item in items:
        name, equals, value = item.partition("=")
        placement, colon, field_name = name.partition(":")
        number: int | None = None
        if colon:
            try:
                number = int(placement)
            except ValueError:
                number = 0
            if number < 1:
                raise StationError(
                    f"--input {item!r}: the placement before ':' must be 1, 2, 3, ..."
                )
            name = field_name
        if not equals or not name.strip():
            raise StationError(
                f"--input {item!r} is not [P:]NAME=VALUE; write e.g. --input x=12.5 or "
                "--input 2:x=12.5"
            )
        values.setdefault(number, {})[name.strip()] = value.strip()
    if table:
        for number, row in _read_inputs(table).items():
            values.setdefault(number, {}).update(row)
    return values


def _read_inputs(path: str) -> dict[int, dict[str, str]]:
    # A regular file of at most 1 MiB (a FIFO or /dev/zero is refused), UTF-8 text.
    data = read_input_bytes(path, "--inputs file", 1 << 20)
    try:
        rows = list(csv.DictReader(data.decode("utf-8-sig").splitlines()))
    except UnicodeDecodeError:
        raise StationError(f"--inputs {path} is not UTF-8 text; give a CSV file") from None
    except csv.Error as error:
        raise StationError(f"--inputs {path}: not a CSV table ({error})") from None
    table: dict[int, dict[str, str]] = {}
    for line, row in enumerate(rows, start=2):
        row = {(k or "").strip().lower(): (v or "").strip() for k, v in row.items()}
        try:
            number = int(row.pop("placement"))
        except (KeyError, ValueError):
            raise StationError(
                f"--inputs {path} line {line}: needs a placement column of whole numbers "
                "(placement,x,y,z)"
            ) from None
        table[number] = row
    return table


def values_for(inputs: Inputs, placement: int | None) -> dict[str, str]:
    """The values that answer an input step at ``placement``."""
    return {**inputs.get(None, {}), **(inputs.get(placement, {}) if placement else {})}


def check_answerable(runner_plan: Any, procedure: Any, inputs: Inputs, done: set) -> None:
    """Refuse, before anything is written, a procedure this command cannot walk alone
    (``runner_plan``: the unrolled steps as (step, placement); ``done``: the (step id,
    placement) pairs a resumed session already confirmed)."""
    for step, placement in runner_plan:
        if (step.id, placement) in done or not step.fields:
            continue
        given = values_for(inputs, placement)
        needed = [f.name for f in step.fields if f.required and f.name not in given]
        if needed:
            prefix = f"{placement}:" if placement else ""
            where = f" at placement {placement}" if placement else ""
            raise StationError(
                f"step {step.title!r}{where} asks for {', '.join(needed)}: pass "
                + " ".join(f"--input {prefix}{name}=VALUE" for name in needed)
                + (" (or --inputs FILE with a row per placement)" if placement else "")
            )
    known = {f.name for step in procedure.all_steps() for f in step.fields}
    unknown = sorted({name for values in inputs.values() for name in values} - known)
    if unknown:
        raise StationError(
            f"--input {', '.join(unknown)}: procedure {procedure.id} asks for no such value"
            + (f" (it asks for {', '.join(sorted(known))})" if known else "")
        )
