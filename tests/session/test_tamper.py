"""Any single flipped byte is found and named; the loader only ever raises StationError."""

from __future__ import annotations

import contextlib
import hashlib
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from station.errors import StationError
from station.session.model import load_session
from station.session.verify import verify_session
from tests.properties import examples

from .conftest import write_session

with tempfile.TemporaryDirectory(prefix="station-tamper-") as _folder:
    DATA = write_session(Path(_folder), cycles=4).read_bytes()


@settings(max_examples=examples(300), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(position=st.integers(0, len(DATA) - 1), flip=st.integers(1, 255))
def test_any_single_flipped_byte_fails_verify_and_names_its_line(position: int, flip: int) -> None:
    damaged = bytearray(DATA)
    damaged[position] ^= flip
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "s.jsonl"
        path.write_bytes(bytes(damaged))
        result = verify_session(path)
    assert not result.ok
    assert result.first_bad_line == DATA[:position].count(b"\n") + 1
    assert f"line {result.first_bad_line}:" in result.message


def test_a_newline_written_into_the_last_line_names_the_last_line() -> None:
    """Found by the property above (about one run in 80): a byte of the last line's hash flipped
    to a newline split it in two, and verify named the torn piece after it (line 15), not the
    damaged line 14 before it. Every byte of the last line, turned into a newline."""
    last = DATA.count(b"\n")
    start = DATA.rstrip(b"\n").rfind(b"\n") + 1
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "s.jsonl"
        for position in range(start, len(DATA) - 1):
            damaged = bytearray(DATA)
            damaged[position] = ord("\n")
            path.write_bytes(bytes(damaged))
            result = verify_session(path)
            assert (result.ok, result.first_bad_line) == (False, last), (position, result.message)


def _load_or_station_error(data: bytes) -> None:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "s.jsonl"
        path.write_bytes(data)
        with contextlib.suppress(StationError):
            load_session(path)
        with contextlib.suppress(StationError):
            verify_session(path)


@settings(max_examples=examples(150), deadline=None)
@given(st.binary(max_size=600))
def test_the_loader_only_raises_station_error_on_arbitrary_bytes(data: bytes) -> None:
    _load_or_station_error(data)


@settings(max_examples=examples(150), deadline=None)
@given(
    edits=st.lists(
        st.tuples(
            st.sampled_from(["flip", "insert", "delete", "cut"]),
            st.integers(0, len(DATA) - 1),
            st.binary(min_size=1, max_size=8),
        ),
        min_size=1,
        max_size=4,
    )
)
def test_the_loader_only_raises_station_error_on_mutated_sessions(edits) -> None:
    data = bytearray(DATA)
    for kind, position, chunk in edits:
        position = min(position, max(len(data) - 1, 0))
        if kind == "flip" and data:
            data[position] ^= chunk[0] or 1
        elif kind == "insert":
            data[position:position] = chunk
        elif kind == "delete":
            del data[position : position + len(chunk)]
        else:
            del data[position:]
    _load_or_station_error(bytes(data))


def test_hashed_hostile_lines_are_station_errors(tmp_path: Path) -> None:
    # Lines whose hash is right but whose content is hostile: deep nesting, a 5000-digit
    # number, NaN. They get past the hash check and must still end as StationError.
    header = DATA.split(b"\n")[0]
    bodies = [
        b'{"a":' + b"[" * 100_000 + b"]" * 100_000,
        b'{"seq":1,"t":"x","type":"note","text":"a","n":' + b"9" * 5000,
        b'{"seq":1,"t":"x","type":"reading","cycle":1,"channels":{"x":{"value":NaN}}',
        b'{"seq":1,"t":"x","type":"reading","cycle":1,"channels":{"x":{"value":'
        + b"9" * 400
        + b"}}",
        b'{"seq":1,"t":"x","type":"reading","cycle":1,"channels":{"x":{"value":1e400}}',
    ]
    for body in bodies:
        line = body + b',"hash":"' + hashlib.sha256(body).hexdigest().encode() + b'"}'
        path = tmp_path / "g.jsonl"
        path.write_bytes(header + b"\n" + line + b"\n" + line + b"\n")
        with pytest.raises(StationError, match="line 2:"):
            load_session(path, recover=False)


_KEYS = ["seq", "t", "type", "cycle", "channels", "value", "reason", "text", "step", "action"]
_KEYS += ["values", "t_mono", "stroke", "placement", "format", "x", "y"]
_SCALARS = (
    st.none()
    | st.booleans()
    | st.integers(-(10**30), 10**30)
    | st.floats(allow_nan=False, allow_infinity=False)
    | st.sampled_from(["reading", "reject", "samples", "zero", "input", "step", "note", "x"])
    | st.text(max_size=5)
)
_JSON = st.recursive(
    _SCALARS,
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.sampled_from(_KEYS), inner),
    max_leaves=12,
)


@settings(max_examples=100, deadline=None)
@given(st.lists(st.dictionaries(st.sampled_from(_KEYS), _JSON, max_size=6), max_size=4))
def test_well_chained_lines_with_arbitrary_content_load_or_raise_station_error(events) -> None:
    # Every line has a valid hash and chain, so the content checks themselves are exercised.
    from station.session.lines import encode_line, line_hash

    lines = [DATA.split(b"\n")[0]]
    for number, event in enumerate(events, start=1):
        record = {"seq": number, "t": "2026-01-01T00:00:00.000000Z", "type": "note", **event}
        lines.append(encode_line(record, line_hash(lines[-1])))
    _load_or_station_error(b"\n".join(lines) + b"\n")
