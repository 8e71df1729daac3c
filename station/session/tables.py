"""Reading plain CSV tables of readings for ``station analyze``.

The format is the simplest a spreadsheet or a logger writes: a header row, then one row per
cycle, one numeric column per channel. The tidy layout ``station export`` writes (one row per
cycle and channel: columns cycle, channel, value, status ...) is read too and turned into one
column per channel, rejected rows left out. Lines whose first non-blank character is ``#`` are
comments (where the data came from, the unit) and blank lines are skipped. Columns named
``cycle``, ``subgroup`` or ``t`` (any case) number or time the rows; they are not channels.

Every problem is a :class:`~station.errors.StationError` that names the file, and where it
helps the line (1-based, counted in the file as an editor shows it) and the column.
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from station.errors import StationError

#: Column names (compared case-insensitively) that index the rows instead of holding readings.
INDEX_COLUMNS: frozenset[str] = frozenset({"cycle", "subgroup", "t"})
#: A header with these columns (any case) is a tidy table: one row per cycle and channel.
TIDY_COLUMNS: frozenset[str] = frozenset({"channel", "value"})
TIDY_VALUE_COLUMNS: frozenset[str] = frozenset({"channel", "value"})


@dataclass(frozen=True)
class ReadingTable:
    """The channels of a CSV table, in the order of its columns.

    ``channels`` maps each channel column to its readings (float64, one per data row);
    ``index_columns`` names the columns that were recognised as row indices and left out;
    ``comments`` holds the text of the ``#`` lines (without the ``#``), for a report header.
    """

    path: Path
    channels: dict[str, np.ndarray]
    index_columns: tuple[str, ...]
    comments: tuple[str, ...]
    cycles: np.ndarray | None = None
    """The ``cycle`` column's whole numbers, one per row (None without one): the analysis
    numbers the readings by them."""
    channel_cycles: dict[str, np.ndarray] | None = None
    """A tidy table's cycle numbers per channel (its channels may cover different cycles)."""
    excluded_cycles: tuple[int, ...] = ()
    """A tidy table's rejected cycles (status ``rejected: ...``), left out of the channels."""
    placements: np.ndarray | None = None
    """A tidy table's fixture placement of each accepted cycle (aligned with the channels),
    None when it records none."""

    @property
    def rows(self) -> int:
        """The number of data rows."""
        return len(next(iter(self.channels.values())))


def _parse_cell(text: str, path: Path, line: int, column: str) -> float:
    try:
        value = float(text)
    except ValueError:
        what = f"{text.strip()!r} is not a number" if text.strip() else "the cell is empty"
        raise StationError(
            f"{path}: line {line}, column {column!r}: {what}; fix the cell or delete the row."
        ) from None
    if not math.isfinite(value):
        raise StationError(
            f"{path}: line {line}, column {column!r}: {text.strip()!r} is not a finite number; "
            "fix the cell or delete the row."
        )
    return value


def read_table(path: str | Path) -> ReadingTable:
    """Read a CSV table of readings: a header row, ``#`` comments, one column per channel.

    Raises StationError for a missing or unreadable file, an empty file, a header without
    channel columns, duplicate column names, a row with a different number of cells than the
    header (naming the line), and a cell that is not a finite number (naming line and column).
    """
    path = Path(path)
    if not path.exists():
        raise StationError(f"{path}: no such file; check the path.")
    if path.is_dir():
        raise StationError(f"{path} is a folder; give the CSV file of readings.")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise StationError(
            f"{path} is not a text file (not UTF-8); give a CSV file of readings."
        ) from None
    except OSError as error:
        raise StationError(f"{path}: cannot read the file ({error.strerror}).") from None

    comments: list[str] = []
    numbered_rows: list[tuple[int, list[str]]] = []
    lines = text.splitlines()
    # csv.reader on each line separately keeps the file's own line numbers for messages;
    # readings never contain quoted newlines.
    for line_number, line in enumerate(lines, start=1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            comments.append(stripped[1:].strip())
            continue
        numbered_rows.append((line_number, next(csv.reader([line]))))

    if not numbered_rows:
        raise StationError(
            f"{path} is empty: expected a header row (e.g. 'cycle,x,y,z') and one row per cycle."
        )
    header_line, header = numbered_rows[0]
    names = [name.strip() for name in header]
    if any(not name for name in names):
        raise StationError(
            f"{path}: line {header_line}: the header has an empty column name; "
            "name every column (e.g. 'cycle,x,y,z')."
        )
    duplicates = sorted({name for name in names if names.count(name) > 1})
    if duplicates:
        raise StationError(
            f"{path}: line {header_line}: column {duplicates[0]!r} appears twice in the header; "
            "give every column its own name."
        )
    channel_positions = [i for i, name in enumerate(names) if name.lower() not in INDEX_COLUMNS]
    if not channel_positions:
        raise StationError(
            f"{path}: line {header_line}: no channel columns in the header {','.join(names)!r}; "
            "add one numeric column per channel (e.g. 'x')."
        )
    data_rows = numbered_rows[1:]
    if not data_rows:
        raise StationError(f"{path} has a header but no readings; add one row per cycle.")
    if {name.lower() for name in names} >= TIDY_COLUMNS:
        return _read_tidy(path, names, data_rows, tuple(comments))

    columns: dict[str, list[float]] = {names[i]: [] for i in channel_positions}
    cycle_position = next((i for i, name in enumerate(names) if name.lower() == "cycle"), None)
    cycles: list[int] = []
    for line_number, cells in data_rows:
        if len(cells) != len(names):
            raise StationError(
                f"{path}: line {line_number} has {len(cells)} cells but the header has "
                f"{len(names)} columns; every row needs one cell per column."
            )
        for i in channel_positions:
            columns[names[i]].append(_parse_cell(cells[i], path, line_number, names[i]))
        if cycle_position is not None:
            name = names[cycle_position]
            number = _parse_cell(cells[cycle_position], path, line_number, name)
            if number != int(number) or number < 1:
                raise StationError(
                    f"{path}: line {line_number}, column {name!r}: "
                    f"{cells[cycle_position].strip()!r} is not a cycle number (1, 2, 3 ...); "
                    "fix the cell or delete the row."
                )
            cycles.append(int(number))

    return ReadingTable(
        path=path,
        channels={name: np.asarray(values, dtype=float) for name, values in columns.items()},
        excluded_cycles=excluded_in_comments(comments),
        index_columns=tuple(name for name in names if name.lower() in INDEX_COLUMNS),
        comments=tuple(comments),
        cycles=None if cycle_position is None else np.asarray(cycles, dtype=int),
    )


_REJECTED_COMMENT = re.compile(r"^rejected cycle (\d+)\b")


def excluded_in_comments(comments: list[str] | tuple[str, ...]) -> tuple[int, ...]:
    """The cycles a wide export names as rejected (``# rejected cycle 3 (left out): ...``):
    they are not in the table, and the analysis lists them as excluded."""
    found = (_REJECTED_COMMENT.match(comment) for comment in comments)
    return tuple(sorted({int(match.group(1)) for match in found if match}))


def _read_tidy(
    path: Path, names: list[str], data_rows: list[tuple[int, list[str]]], comments: tuple[str, ...]
) -> ReadingTable:
    """A tidy table (``station export --layout tidy``: one row per cycle and channel, columns
    cycle, channel, value, optional status and placement) turned into one column per channel.
    Rows whose status is ``rejected: ...`` are left out and their cycles listed as excluded."""
    position = {name.lower(): i for i, name in enumerate(names)}
    if "cycle" not in position:
        raise StationError(
            f"{path}: a table with 'channel' and 'value' columns (one row per reading) needs a "
            "'cycle' column too."
        )
    values: dict[str, list[float]] = {}
    cycles: dict[str, list[int]] = {}
    placement_of: dict[int, int] = {}
    excluded: set[int] = set()
    for line_number, cells in data_rows:
        if len(cells) != len(names):
            raise StationError(
                f"{path}: line {line_number} has {len(cells)} cells but the header has "
                f"{len(names)} columns; every row needs one cell per column."
            )
        cell = {name: cells[i] for name, i in position.items()}
        number = _parse_cell(cell["cycle"], path, line_number, names[position["cycle"]])
        if number != int(number) or number < 1:
            raise StationError(
                f"{path}: line {line_number}, column 'cycle': {cell['cycle'].strip()!r} is not a "
                "cycle number (1, 2, 3 ...); fix the cell or delete the row."
            )
        if cell.get("status", "ok").strip().lower().startswith("rejected"):
            excluded.add(int(number))
            continue
        channel = cell["channel"].strip()
        if not channel:
            raise StationError(f"{path}: line {line_number}: the channel cell is empty.")
        value = _parse_cell(cell["value"], path, line_number, names[position["value"]])
        values.setdefault(channel, []).append(value)
        cycles.setdefault(channel, []).append(int(number))
        if cell.get("placement", "").strip():
            placement = _parse_cell(cell["placement"], path, line_number, "placement")
            placement_of[int(number)] = int(placement)
    if not values:
        raise StationError(f"{path}: every reading in the table is rejected; nothing to analyse.")
    first = next(iter(cycles.values()))
    placements = None
    if placement_of and all(c in placement_of for c in first):
        placements = np.asarray([placement_of[c] for c in first], dtype=float)
    return ReadingTable(
        path=path,
        channels={name: np.asarray(column, dtype=float) for name, column in values.items()},
        index_columns=tuple(n for n in names if n.lower() not in TIDY_VALUE_COLUMNS),
        comments=comments,
        cycles=None,
        channel_cycles={name: np.asarray(column, dtype=int) for name, column in cycles.items()},
        excluded_cycles=tuple(sorted(excluded - {c for cs in cycles.values() for c in cs})),
        placements=placements,
    )


def require_columns(
    table: ReadingTable, required: tuple[str, ...], what: str
) -> dict[str, np.ndarray]:
    """The columns ``required`` of ``table`` (names compared case-insensitively), or a
    StationError that names the missing ones and the header ``what`` needs (e.g. "a linearity
    table needs the columns stroke, s, h, v")."""
    by_name = {name.lower(): values for name, values in table.channels.items()}
    missing = [name for name in required if name not in by_name]
    if missing:
        have = ", ".join(table.channels) or "none"
        raise StationError(
            f"{table.path}: {what} needs the columns {', '.join(required)}; "
            f"{', '.join(missing)} missing (the file has {have})."
        )
    return {name: by_name[name] for name in required}
