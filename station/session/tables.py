"""Reading plain CSV tables of readings for ``station analyze``.

The format is the simplest a spreadsheet or a logger writes: a header row, then one row per
cycle, one numeric column per channel. The tidy layout ``station export`` writes (one row per
cycle and channel: columns cycle, channel, value, status ...) is read too and turned into one
column per channel, rejected rows left out. Lines whose first non-blank character is ``#`` are
comments (where the data came from, the unit) and blank lines are skipped. Columns named
``cycle``, ``subgroup`` or ``t`` (any case) number or time the rows, and so do ``sample``,
``id``, ``index`` and ``obs`` (the row numbers Minitab, JASP and Excel export): they are not
channels. :func:`row_counters` finds a column of another name that only counts the rows. A
caller may name *label* columns (a Gage R&R's part and appraiser): their cells are kept as text,
not read as channels.

Every problem is a :class:`~station.errors.StationError` that names the file, and where it
helps the line (1-based, counted in the file as an editor shows it) and the column.
"""

from __future__ import annotations

import csv
import re
import warnings
from collections.abc import Collection
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from station.errors import StationError
from station.inputfiles import check_regular_file
from station.plain import plain
from station.session.model import event_seconds
from station.session.replay import CYCLE_LIMIT, READING_LIMIT

#: Column names (compared case-insensitively) that index the rows instead of holding readings.
INDEX_COLUMNS: frozenset[str] = frozenset(
    {"cycle", "subgroup", "t", "sample", "id", "index", "obs"}
)
ROW_COUNT_MINIMUM = 5
"""The fewest rows at which a column holding exactly 1, 2, 3 ... n (or 0 ... n-1) is taken
for a row number: a gauge's readings run so in order by chance only in a very short table."""


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
    times: np.ndarray | None = None
    """The time (seconds) of each row, from a ``t`` column (or a tidy table's ``time``), for
    the drift's trend; None without one."""
    placements: np.ndarray | None = None
    """A tidy table's fixture placement of each accepted cycle (aligned with the channels),
    None when it records none."""
    labels: dict[str, tuple[str, ...]] = field(default_factory=dict)
    """The label columns the caller named that the table has (by their name in the file):
    each row's cell as text, stripped (a Gage R&R's part, an approach's ``direction``)."""
    row_lines: tuple[int, ...] | None = None
    """The file's line of each data row (as an editor counts), for a table with label columns
    (read line by line), so a method's sentence about a row can name its line; else None."""

    @property
    def rows(self) -> int:
        """The number of data rows."""
        return len(next(iter(self.channels.values())))


#: A header with these columns (any case) is a tidy table: one row per cycle and channel.
TIDY_COLUMNS: frozenset[str] = frozenset({"channel", "value"})
TIDY_VALUE_COLUMNS: frozenset[str] = frozenset({"channel", "value"})
EXPORT_COMMENT_SCAN_LIMIT = 64 << 20
"""Files up to this size are scanned for the ``# rejected cycle N`` lines a wide export writes
after its rows (a larger file is raw data, not an export)."""

CSV_FILE_LIMIT = 8 << 30
"""The largest CSV file read (8 GiB, some 500 million one-column rows)."""
HEADER_LINE_LIMIT = 1 << 20

_NUMBER = re.compile(r"^\s*[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?\s*$", re.ASCII)
_NAMED_NUMBER = re.compile(r"^\s*[+-]?(?:inf|infinity|nan)\s*$", re.IGNORECASE)


def _is_number_text(text: str) -> bool:
    """True for a plain decimal number in ASCII digits (no ``1_000``, no other scripts)."""
    return bool(_NUMBER.match(text))


def _parse_cell(text: str, path: Path, line: int, column: str) -> float:
    shown = plain(text.strip(), limit=40)
    if not text.strip():
        what = "the cell is empty"
    elif _NAMED_NUMBER.match(text):
        what = f"{shown!r} is not a finite number"
    elif not _is_number_text(text):
        what = f"{shown!r} is not a number"
    else:
        value = float(text)
        if abs(value) <= READING_LIMIT:
            return value
        what = f"{shown!r} is beyond ±{READING_LIMIT:g}, not a reading"
    raise StationError(
        f"{plain(path)}: line {line}, column {plain(column, limit=40)!r}: {what}; "
        "fix the cell or delete the row."
    )


def read_table(path: str | Path, labels: Collection[str] = ()) -> ReadingTable:
    """Read a CSV table of readings: a header row, ``#`` comments, one column per channel.
    The columns named in ``labels`` (compared case-insensitively; a Gage R&R's part and
    appraiser, an approach's direction ``up``/``down``) hold words: their cells are kept as
    text in :attr:`ReadingTable.labels` and are no channels.

    The rows are parsed by numpy in one streaming pass (``numpy.loadtxt``, no per-cell Python);
    a file it cannot take is read again line by line to name the first fault. Raises
    StationError for a missing or unreadable file, a FIFO, a device or a folder, an empty file,
    a first row of numbers (no header), a header without channel columns, duplicate column
    names, a row with a different number of cells than the header (naming the line), a cell
    that is not a finite number in ASCII digits within ±1e150 (naming line and column), an
    empty label cell, and a ``cycle`` that is not a whole number from 1 to 2**53.
    """
    path = Path(path)
    info = check_regular_file(path, "CSV file of readings")
    if info.st_size > CSV_FILE_LIMIT:
        raise StationError(
            f"{plain(path)} is larger than {CSV_FILE_LIMIT >> 30} GiB; split it into smaller files."
        )
    try:
        with open(path, encoding="utf-8-sig", newline="") as handle:
            comments, header_line, names = _read_header(handle, path)
            if {name.lower() for name in names} >= TIDY_COLUMNS:
                data_rows = [
                    (number, _cells(line, path, number))
                    for number, line in enumerate(handle, start=header_line + 1)
                    if line.strip() and not line.lstrip().startswith("#")
                ]
                if not data_rows:
                    raise StationError(
                        f"{plain(path)} has a header but no readings; add one row per cycle."
                    )
                return _read_tidy(path, names, data_rows, tuple(comments))
            wanted = {name.lower() for name in labels}
            label_positions = [i for i, name in enumerate(names) if name.lower() in wanted]
            channel_positions = _check_header(names, header_line, path, label_positions)
            label_cells: dict[str, tuple[str, ...]] = {}
            row_lines = None
            if label_positions:
                # Text beside the numbers: read row by row (a study's table is small).
                data, label_cells, row_lines = _read_labelled(
                    handle, path, header_line, names, label_positions
                )
            else:
                data = _read_numbers(handle, path, header_line, names)
    except UnicodeDecodeError:
        raise StationError(
            f"{plain(path)} is not a text file (not UTF-8); give a CSV file of readings."
        ) from None
    except OSError as error:
        raise StationError(f"{plain(path)}: cannot read the file ({error.strerror}).") from None

    if data.shape[0] == 0:
        raise StationError(f"{plain(path)} has a header but no readings; add one row per cycle.")
    bad = ~np.isfinite(data) | (np.abs(data) > READING_LIMIT)
    if bad.any():
        # Rare: numpy took an 'inf', 'nan' or a huge value. Name the line and the cell.
        with open(path, encoding="utf-8-sig", newline="") as handle:
            _diagnose(handle, path, 0, names, skip_header=True, labels=label_positions)
        raise StationError(f"{plain(path)}: a cell is not a finite number.")
    # The numeric columns, in the order of ``data``'s (the label columns are kept apart).
    numeric = [name for i, name in enumerate(names) if i not in label_positions]
    channel_positions = [numeric.index(names[i]) for i in channel_positions]
    cycle_position = next((i for i, name in enumerate(numeric) if name.lower() == "cycle"), None)
    cycles = None
    if cycle_position is not None:
        numbers = data[:, cycle_position]
        wrong = (numbers != np.floor(numbers)) | (numbers < 1) | (numbers > CYCLE_LIMIT)
        if wrong.any():
            with open(path, encoding="utf-8-sig", newline="") as handle:
                _diagnose(handle, path, 0, names, skip_header=True, labels=label_positions)
            raise StationError(f"{plain(path)}: a cycle number is not 1, 2, 3 ...")
        cycles = numbers.astype(np.int64)
    if info.st_size <= EXPORT_COMMENT_SCAN_LIMIT and _holds_a_hash(path):
        with open(path, encoding="utf-8-sig", newline="") as handle:
            comments = [
                line.strip()[1:].strip() for line in handle if line.lstrip().startswith("#")
            ]
    return ReadingTable(
        path=path,
        channels={numeric[i]: np.ascontiguousarray(data[:, i]) for i in channel_positions},
        index_columns=tuple(name for name in names if name.lower() in INDEX_COLUMNS),
        comments=tuple(comments),
        cycles=cycles,
        excluded_cycles=excluded_in_comments(comments),
        times=next(
            (np.ascontiguousarray(data[:, i]) for i, n in enumerate(numeric) if n.lower() == "t"),
            None,
        ),
        labels=label_cells,
        row_lines=row_lines,
    )


def _read_numbers(handle: Any, path: Path, header_line: int, names: list[str]) -> np.ndarray:
    """The data rows of a table of numbers, in one streaming pass where numpy can take them;
    else the first fault, named."""
    start = handle.tell()
    try:
        return _load_rows(handle, len(names))
    except ValueError:
        pass
    handle.seek(start)
    try:
        return _load_rows((ln for ln in handle if ln.strip()), len(names))
    except ValueError:
        pass
    handle.seek(start)
    _diagnose(handle, path, header_line, names)
    raise StationError(f"{plain(path)}: the rows cannot be read as numbers.")


def _read_labelled(
    handle: Any, path: Path, header_line: int, names: list[str], label_positions: list[int]
) -> tuple[np.ndarray, dict[str, tuple[str, ...]], tuple[int, ...]]:
    """The data rows of a table with label columns: the numbers of the other columns (one row
    each), each label column's cells as text and each row's line in the file; a fault names
    its line and column."""
    rows: list[list[float]] = []
    lines: list[int] = []
    labels: dict[int, list[str]] = {i: [] for i in label_positions}
    for line_number, line in enumerate(handle, start=header_line + 1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        cells = _cells(line, path, line_number)
        if len(cells) != len(names):
            raise StationError(
                f"{plain(path)}: line {line_number} has {len(cells)} cells but the header has "
                f"{len(names)} columns; every row needs one cell per column."
            )
        row = []
        for index, (name, cell) in enumerate(zip(names, cells, strict=True)):
            if index in labels:
                if not cell.strip():
                    raise StationError(
                        f"{plain(path)}: line {line_number}, column {plain(name, limit=40)!r}: "
                        "the cell is empty; name it or delete the row."
                    )
                labels[index].append(cell.strip())
            else:
                row.append(_parse_cell(cell, path, line_number, name))
        rows.append(row)
        lines.append(line_number)
    width = len(names) - len(label_positions)
    data = np.asarray(rows, dtype=np.float64).reshape(len(rows), width)
    return data, {names[i]: tuple(cells) for i, cells in labels.items()}, tuple(lines)


def _holds_a_hash(path: Path, block: int = 1 << 20) -> bool:
    """True when the file holds a ``#`` anywhere: only then can it have a comment line to
    collect. Searching the bytes a block at a time costs a fraction of reading it line by
    line, and most tables have no comment at all."""
    with open(path, "rb") as raw:
        while chunk := raw.read(block):
            if b"#" in chunk:
                return True
    return False


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
    time_of: dict[int, float] = {}
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
        if cell.get("time", "").strip():
            time_of[int(number)] = event_seconds(cell["time"].strip())
    if not values:
        raise StationError(f"{path}: every reading in the table is rejected; nothing to analyse.")
    first = next(iter(cycles.values()))
    placements = None
    if placement_of and all(c in placement_of for c in first):
        placements = np.asarray([placement_of[c] for c in first], dtype=float)
    times = None
    if time_of and all(c in time_of for c in first):
        times = np.asarray([time_of[c] for c in first], dtype=float)
    return ReadingTable(
        path=path,
        channels={name: np.asarray(column, dtype=float) for name, column in values.items()},
        index_columns=tuple(n for n in names if n.lower() not in TIDY_VALUE_COLUMNS),
        comments=comments,
        cycles=None,
        channel_cycles={name: np.asarray(column, dtype=int) for name, column in cycles.items()},
        excluded_cycles=tuple(sorted(excluded - {c for cs in cycles.values() for c in cs})),
        placements=placements,
        times=times,
    )


CELL_LIMIT = csv.field_size_limit()
"""The longest cell the csv module splits (128 KiB): no column name or reading is near it."""


def _cells(line: str, path: Path, line_number: int) -> list[str]:
    """The cells of one CSV line; a cell over :data:`CELL_LIMIT` (or a line the csv module
    cannot split) is a StationError naming the file and the line."""
    try:
        return next(csv.reader([line]))
    except csv.Error as error:
        if "field limit" not in str(error):
            raise StationError(
                f"{plain(path)}: line {line_number} is not a CSV row ({plain(error)}); "
                "fix the line."
            ) from None
        raise StationError(
            f"{plain(path)}: line {line_number} has a cell longer than {CELL_LIMIT >> 10} KiB, "
            "which is no column name or reading; check that it is the right file, or shorten "
            "the cell."
        ) from None


def _load_rows(lines: Any, columns: int) -> np.ndarray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "input contained no data" for a header-only file
        data = np.loadtxt(
            lines, delimiter=",", comments="#", dtype=np.float64, ndmin=2, quotechar='"'
        )
    if data.size and data.shape[1] != columns:
        raise ValueError("column count")
    return data.reshape(-1, columns) if data.size else np.empty((0, columns))


def _read_header(handle: Any, path: Path) -> tuple[list[str], int, list[str]]:
    comments: list[str] = []
    line_number = 0
    while True:
        line = handle.readline(HEADER_LINE_LIMIT)
        if not line:
            raise StationError(
                f"{plain(path)} is empty: expected a header row (e.g. 'cycle,x,y,z') and one "
                "row per cycle."
            )
        if len(line) >= HEADER_LINE_LIMIT:
            raise StationError(f"{plain(path)}: line {line_number + 1} is longer than 1 MiB.")
        line_number += 1
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            comments.append(stripped[1:].strip())
            continue
        cells = _cells(line, path, line_number)
        return comments, line_number, [cell.strip() for cell in cells]


def _check_header(
    names: list[str], header_line: int, path: Path, label_positions: Collection[int] = ()
) -> list[int]:
    where = f"{plain(path)}: line {header_line}"
    if all(_is_number_text(name) or _NAMED_NUMBER.match(name) for name in names):
        raise StationError(
            f"{where}: the first row holds numbers, not column names; add a header row "
            "(e.g. 'x' or 'cycle,x,y,z') so no reading is taken for a name."
        )
    if any(not name for name in names):
        raise StationError(
            f"{where}: the header has an empty column name; name every column (e.g. 'cycle,x,y,z')."
        )
    duplicates = sorted({name for name in names if names.count(name) > 1})
    if duplicates:
        raise StationError(
            f"{where}: column {plain(duplicates[0], limit=40)!r} appears twice in the header; "
            "give every column its own name."
        )
    channel_positions = [
        i
        for i, name in enumerate(names)
        if name.lower() not in INDEX_COLUMNS and i not in label_positions
    ]
    if not channel_positions:
        raise StationError(
            f"{where}: no channel columns in the header {plain(','.join(names), limit=80)!r}; "
            "add one numeric column per channel (e.g. 'x')."
        )
    return channel_positions


def _diagnose(
    handle: Any,
    path: Path,
    first_line: int,
    names: list[str],
    *,
    skip_header: bool = False,
    labels: Collection[int] = (),
) -> None:
    """Read the rows line by line (streaming, nothing kept) and raise at the first fault
    (``labels``: the positions of label columns, which hold text)."""
    line_number = first_line
    header_seen = not skip_header
    for line in handle:
        line_number += 1
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        if not header_seen:
            header_seen = True
            continue
        cells = _cells(line, path, line_number)
        if len(cells) != len(names):
            raise StationError(
                f"{plain(path)}: line {line_number} has {len(cells)} cells but the header has "
                f"{len(names)} columns; every row needs one cell per column."
            )
        for index, name in enumerate(names):
            if index in labels:
                continue
            value = _parse_cell(cells[index], path, line_number, name)
            if name.lower() == "cycle" and (
                value != int(value) or value < 1 or value > CYCLE_LIMIT
            ):
                raise StationError(
                    f"{plain(path)}: line {line_number}, column {name!r}: "
                    f"{plain(cells[index].strip(), limit=40)!r} is not a cycle number "
                    "(1, 2, 3 ...); fix the cell or delete the row."
                )


def row_counters(channels: dict[str, np.ndarray]) -> tuple[str, ...]:
    """The channel columns that only count the rows (1, 2, 3 ... n or 0, 1 ... n-1, at least
    :data:`ROW_COUNT_MINIMUM` rows): a row number a spreadsheet wrote under a name of its own
    (``n``, ``no``, ``row``), which analysed as a channel would fail a capable run."""
    counters = []
    for name, values in channels.items():
        n = len(values)
        if n < ROW_COUNT_MINIMUM:
            continue
        steps = np.arange(n, dtype=np.float64)
        if np.array_equal(values, steps + 1) or np.array_equal(values, steps):
            counters.append(name)
    return tuple(counters)


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
