"""A crash mid-write leaves a torn last line: it is moved aside, everything before it is kept."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from station.errors import StationError
from station.session.journal import SessionWriter
from station.session.model import load_session
from station.session.verify import verify_session

from .conftest import reading_fields


def test_truncating_the_last_line_at_every_byte_offset_recovers(session_factory, tmp_path) -> None:
    original = session_factory(cycles=3)
    data = original.read_bytes()
    start = data.rstrip(b"\n").rindex(b"\n") + 1  # where the last line begins
    complete = load_session(original, recover=False)
    work = tmp_path / "work"
    work.mkdir()
    for cut in range(start + 1, len(data)):
        path = work / f"s{cut}.jsonl"
        path.write_bytes(data[:cut])
        session = load_session(path)
        assert session.torn is not None, cut
        assert session.recovered_torn_bytes == cut - start
        assert session.torn.moved_to == path.with_name(path.name + ".torn")
        assert session.torn.moved_to.read_bytes() == data[start:cut]
        assert path.read_bytes() == data[:start]
        assert session.last_seq == complete.last_seq - 1
        assert session.cycles.keys() == complete.cycles.keys()
        assert session.status == "running"  # the finish event was the torn line
        assert verify_session(path).ok
    # A cut exactly at the line boundary is a clean (shorter) file, not a torn one.
    path = work / "boundary.jsonl"
    path.write_bytes(data[:start])
    assert load_session(path).torn is None


def test_read_only_load_reports_but_does_not_touch_the_file(session_factory) -> None:
    path = session_factory()
    data = path.read_bytes()
    path.write_bytes(data[:-10])
    session = load_session(path, recover=False)
    assert session.torn is not None and session.torn.moved_to is None
    assert "left in place" in session.torn.message
    assert path.read_bytes() == data[:-10]
    assert not path.with_name(path.name + ".torn").exists()
    report = verify_session(path)
    assert not report.ok and report.first_bad_line == session.lines + 1
    assert "torn" in report.message


def test_a_second_tear_is_appended_to_the_torn_file(session_factory) -> None:
    path = session_factory(finish=False)
    path.write_bytes(path.read_bytes() + b'{"seq":99,"t":')
    load_session(path)
    writer, before = SessionWriter.resume(path)
    with writer:
        writer.append("reading", **reading_fields(before.next_cycle))
    path.write_bytes(path.read_bytes() + b'{"seq":')
    session = load_session(path)
    torn = path.with_name(path.name + ".torn")
    assert torn.read_bytes() == b'{"seq":99,"t":{"seq":'
    assert session.next_cycle == before.next_cycle + 1


def test_a_zero_filled_last_line_is_torn(session_factory) -> None:
    # What a power cut can leave: the file's new length on disk, its data not.
    path = session_factory(finish=False)
    clean = path.read_bytes()
    path.write_bytes(clean + b"\0" * 120 + b"\n")
    session = load_session(path)
    assert session.recovered_torn_bytes == 121
    assert path.read_bytes() == clean


def test_resume_recovers_a_torn_tail_first(session_factory) -> None:
    path = session_factory(cycles=3, finish=False)
    path.write_bytes(path.read_bytes() + b'{"seq":21,"t":"2026')
    writer, session = SessionWriter.resume(path, by="test")
    with writer:
        assert session.torn is not None and session.torn.length == 19
        writer.append("reading", **reading_fields(session.next_cycle))
    assert verify_session(path).ok
    assert sorted(load_session(path).cycles) == [1, 2, 3, 4]


def test_a_file_cut_inside_its_header_is_an_error(tmp_path: Path, session_factory) -> None:
    path = session_factory()
    data = path.read_bytes()
    for content, message in ((b"", "empty"), (data[:40], "no complete header")):
        target = tmp_path / "cut.jsonl"
        target.write_bytes(content)
        with pytest.raises(StationError, match=message):
            load_session(target)
        assert target.read_bytes() == content


def test_an_edited_last_line_is_an_error_not_a_tear(session_factory) -> None:
    path = session_factory()
    data = path.read_bytes()
    path.write_bytes(data.replace(b'"verdict":"capable"', b'"verdict":"CAPABLE"'))
    with pytest.raises(StationError, match=r"line \d+: .*edited"):
        load_session(path)


def test_loading_a_sessions_copy_does_not_change_the_original(session_factory, tmp_path) -> None:
    path = session_factory()
    copy = tmp_path / "copy.jsonl"
    shutil.copy(path, copy)
    load_session(copy)
    assert copy.read_bytes() == path.read_bytes()


def test_a_file_being_written_is_never_cut(session_factory) -> None:
    path = session_factory(finish=False)
    writer, _ = SessionWriter.resume(path)
    with writer:
        with path.open("ab") as other:  # as if a write were under way
            other.write(b'{"seq":')
        session = load_session(path)
        assert session.torn is not None and session.torn.moved_to is None
        assert "another process is writing" in session.torn.message
        assert path.read_bytes().endswith(b'{"seq":')
