"""Reading plain CSV tables of readings for ``station analyze``.

The format is the simplest a spreadsheet or a logger writes: a header row, then one row per
cycle, one numeric column per channel. Lines whose first non-blank character is ``#`` are
comments (where the data came from, the unit) and blank lines are skipped. Columns named
``cycle``, ``subgroup`` or ``t`` (any case) number or time the rows; they are not channels.

Every problem is a :class:`~station.errors.StationError` that names the file, and where it
helps the line (1-based, counted in the file as an editor shows it) and the column.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from station.errors import StationError

#: Column names (compared case-insensitively) that index the rows instead of holding readings.
INDEX_COLUMNS: frozenset[str] = frozenset({"cycle", "subgroup", "t"})


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
        index_columns=tuple(name for name in names if name.lower() in INDEX_COLUMNS),
        comments=tuple(comments),
        cycles=None if cycle_position is None else np.asarray(cycles, dtype=int),
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
