"""Issue 12, findings 3, 4 and 5: writes never follow a planted link or replace their input;
verify catches a cut or extended file with the anchor, a finished session holds nothing after
its signed finish, and a rechained forgery fails without the station's key; a session file
deleted or replaced during capture stops the writer."""

from __future__ import annotations

import json
import os
import stat
import subprocess
from pathlib import Path

import pytest
from helpers import run_station

from station.cli import main
from station.errors import StationError
from station.session.journal import SessionWriter
from station.session.lines import encode_line, line_hash
from station.session.model import load_session, replay_bytes
from station.session.verify import verify_session

from .conftest import reading_fields, session_header_fields, write_session

REPO = Path(__file__).resolve().parents[2]


def station(*args: str | Path) -> subprocess.CompletedProcess[str]:
    """``station ARGS`` in this process."""
    return run_station(*args, cwd=REPO)


# -- finding 3: writes follow planted symlinks -------------------------------------------------


def test_torn_tail_recovery_does_not_append_through_a_planted_torn_link(tmp_path: Path) -> None:
    path = write_session(tmp_path / "sessions", finish=False)
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    os.symlink(victim, path.with_name(path.name + ".torn"))
    path.write_bytes(path.read_bytes() + b'{"seq":99,"t":')
    session = load_session(path, recover=True)
    assert victim.read_text() == "precious\n", "bytes were appended through the link"
    assert session.torn is not None and session.torn.moved_to is None
    assert "could not move them aside" in session.torn.message


def test_export_does_not_write_through_a_planted_partial_or_output_link(tmp_path: Path) -> None:
    path = write_session(tmp_path / "sessions")
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    out = tmp_path / "out.csv"
    os.symlink(victim, tmp_path / ".out.csv.partial")  # the old fixed temporary name
    assert main(["export", str(path), "--csv", "-o", str(out)]) == 0
    assert victim.read_text() == "precious\n"
    assert out.is_file() and not out.is_symlink()
    assert out.read_text().startswith("cycle,channel,value")

    linked = tmp_path / "linked.csv"
    os.symlink(victim, linked)
    result = station("export", path, "--csv", "-o", linked, "--force")
    assert result.returncode == 2 and "symbolic link" in result.stderr, result.stderr
    assert victim.read_text() == "precious\n" and linked.is_symlink()


async def test_tui_exports_do_not_overwrite_a_planted_link_target(tmp_path: Path) -> None:
    from station.tui.app import StationApp, StationConfig
    from station.tui.screens.summary import SummaryScreen, SummaryView

    path = write_session(tmp_path / "sessions", cycles=30)
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    os.symlink(victim, path.with_name(path.stem + ".csv"))
    os.symlink(victim, path.with_name(path.stem + ".report.txt"))
    app = StationApp(StationConfig(sessions_dir=path.parent, sessions_reason="test"))
    async with app.run_test(size=(80, 24)) as pilot:
        app.push_screen(SummaryScreen(SummaryView.from_file(path), reviewing=True))
        await pilot.pause()
        await pilot.press("c")
        await pilot.press("e")
        await pilot.pause()
        assert app.screen.exported == []
    assert victim.read_text() == "precious\n"


# -- finding 5: export over its own input -----------------------------------------------------


def test_export_refuses_to_replace_the_session_file_itself(tmp_path: Path) -> None:
    path = write_session(tmp_path / "sessions")
    before = path.read_bytes()
    result = station("export", path, "--csv", "-o", path, "--force")
    assert result.returncode == 2, result.stdout + result.stderr
    assert "is the input file itself" in result.stderr
    assert path.read_bytes() == before
    hard = tmp_path / "hard.csv"
    os.link(path, hard)
    result = station("export", path, "--csv", "-o", hard, "--force")
    assert result.returncode == 2 and "input file itself" in result.stderr
    assert path.read_bytes() == before


# -- finding 4: verify misses truncation and appends ----------------------------------------


def test_a_finished_session_cut_short_fails_with_its_anchor(tmp_path: Path) -> None:
    path = write_session(tmp_path / "sessions")
    anchor = load_session(path, recover=False).last_hash
    cut = tmp_path / "cut.jsonl"
    cut.write_bytes(b"".join(line + b"\n" for line in path.read_bytes().split(b"\n")[:-2]))
    plain = station("verify", cut)
    # Without the anchor the chain cannot see the cut: verify says so instead of vouching.
    assert "running" in plain.stdout and "--anchor" in plain.stdout, plain.stdout
    anchored = station("verify", cut, "--anchor", anchor)
    assert anchored.returncode == 1, anchored.stdout
    assert "NOT intact" in anchored.stdout and "anchor is not in the file" in anchored.stdout
    assert station("verify", path, "--anchor", anchor).returncode == 0


def _append_rechained(path: Path, record: dict) -> None:
    """What an attacker with plain sha256 does: append a well-chained line."""
    data = path.read_bytes()
    replay, _, _ = replay_bytes(data, path, allow_torn=False)
    record = {"seq": replay.last_seq + 1, "t": "2026-11-23T13:00:00.000000Z", **record}
    path.write_bytes(data + encode_line(record, replay.chain_hash) + b"\n")


def test_a_line_appended_after_finish_fails_and_the_old_anchor_says_where(tmp_path: Path) -> None:
    path = write_session(tmp_path / "sessions", cycles=5)
    anchor = load_session(path, recover=False).last_hash
    _append_rechained(path, {"type": "reading", **reading_fields(99)})
    result = verify_session(path)
    assert not result.ok and "after the session's finish" in result.message
    assert result.first_bad_line == len(path.read_bytes().split(b"\n")) - 1
    assert not verify_session(path, anchor=anchor).ok
    with pytest.raises(StationError, match="after the session's finish"):
        load_session(path, recover=False)


def test_an_extension_of_an_unfinished_session_fails_against_the_anchor(tmp_path: Path) -> None:
    path = write_session(tmp_path / "sessions", finish=False)
    anchor = load_session(path, recover=False).last_hash
    _append_rechained(path, {"type": "note", "text": "added later"})
    assert verify_session(path).ok  # the chain alone holds
    result = verify_session(path, anchor=anchor)
    assert not result.ok and "1 line(s) were added after the report" in result.message


def test_a_rechained_forgery_of_a_finished_session_fails_without_the_key(tmp_path: Path) -> None:
    path = write_session(tmp_path / "sessions", cycles=5)
    lines = path.read_bytes().split(b"\n")[:-1]
    records = [json.loads(line) for line in lines]
    # Change a reading and rebuild every hash after it, the finish's signature copied over.
    for record in records:
        if record.get("type") == "reading" and record["cycle"] == 3:
            record["channels"]["x"]["value"] = 0.0009
    rebuilt, prev = [], None
    for record in records:
        record = {k: v for k, v in record.items() if k not in ("prev", "hash")}
        line = encode_line(record, prev)
        rebuilt.append(line)
        prev = line_hash(line)
    forged = tmp_path / "forged.jsonl"
    forged.write_bytes(b"".join(line + b"\n" for line in rebuilt))
    assert forged.read_bytes() != path.read_bytes()
    result = station("verify", forged)
    assert result.returncode == 1, result.stdout
    assert "signature does not match" in result.stdout


def test_finish_is_signed_by_a_key_made_once_with_mode_0600(tmp_path: Path) -> None:
    from station.session.signing import config_folder, key_id, station_key

    path = write_session(tmp_path / "sessions")
    key_file = config_folder() / "signing-key.pem"
    assert stat.S_IMODE(key_file.stat().st_mode) == 0o600
    assert str(key_file).startswith(os.environ["XDG_CONFIG_HOME"])
    key = station_key(create=False)
    session = load_session(path, recover=False)
    assert session.header["signer"]["key"] == key.id == key_id(key.public_key)
    assert "signature" in session.events[-1]
    result = station("verify", path)
    assert f"signed by station key: {key.id}" in result.stdout


# -- finding 9: a session file deleted during capture keeps being acknowledged ----------------


@pytest.mark.parametrize("how", ["deleted", "replaced"])
def test_a_session_file_deleted_or_replaced_stops_the_writer(tmp_path: Path, how: str) -> None:
    writer = SessionWriter.create(tmp_path, session_header_fields())
    writer.append("reading", **reading_fields(1))
    if how == "deleted":
        writer.path.unlink()
    else:
        other = tmp_path / "other"
        other.write_bytes(writer.path.read_bytes())
        os.replace(other, writer.path)
    with pytest.raises(StationError, match=f"was {how} while the session was running"):
        writer.append("reading", **reading_fields(2))
    assert writer.closed


# -- issue 23, item 2: verify streams the chain -------------------------------------------------


def test_the_cycle_index_holds_numbers_and_seqs_in_runs_or_out_of_order():
    from station.session.replay import CycleSeqs

    index = CycleSeqs()
    # 1-3 one run (seqs step by 2), 4 breaks the stride, 9 breaks the numbering.
    for cycle, seq in ((1, 3), (2, 5), (3, 7), (4, 10), (5, 11), (9, 12)):
        index.add(cycle, seq)
    assert [index[c] for c in (1, 2, 3, 4, 5, 9)] == [3, 5, 7, 10, 11, 12]
    assert 6 not in index and 10 not in index and 0 not in index and "2" not in index
    assert list(index) == [1, 2, 3, 4, 5, 9] and len(index) == 6 and index.highest == 9
    with pytest.raises(KeyError):
        index[7]
    index.add(7, 20)  # out of order: still found, by number
    assert index[7] == 20 and index[3] == 7 and index.highest == 9 and len(index) == 7
    assert sorted(index) == [1, 2, 3, 4, 5, 7, 9]


def _extend_chain(path: Path, records: list[dict]) -> None:
    """Append well-chained events after the file's last line, as the writer would (without an
    fsync each: a long file in a moment)."""
    data = path.read_bytes()
    replay, _, _ = replay_bytes(data, path, allow_torn=False)
    seq, prev = replay.last_seq, replay.chain_hash
    with path.open("ab") as out:
        for record in records:
            seq += 1
            line = encode_line({"seq": seq, "t": "2026-11-23T13:00:00.000000Z", **record}, prev)
            out.write(line + b"\n")
            prev = line_hash(line)


def _long_session(folder: Path, cycles: int) -> Path:
    path = write_session(folder, cycles=5, finish=False)
    records: list[dict] = []
    for cycle in range(6, cycles + 1):
        records.append({"type": "reading", **reading_fields(cycle)})
        if cycle % 100 == 0:
            records.append({"type": "reject", "cycle": cycle, "reason": "bumped"})
            records.append({"type": "alarm", "rule": "report-1", "channel": "x", "points": []})
    _extend_chain(path, records)
    return path


def _verify_peak(path: Path) -> int:
    import tracemalloc

    tracemalloc.start()
    try:
        result = verify_session(path)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert result.ok, result.message
    return peak


def test_verify_holds_a_line_at_a_time_not_the_file(tmp_path: Path) -> None:
    """A session of hours is hundreds of megabytes of JSON: verify's memory must not grow with
    the file (it held the bytes, every line and every event: ~9x the file)."""
    short = _long_session(tmp_path / "short", 300)
    long = _long_session(tmp_path / "long", 3000)
    grown = _verify_peak(long) - _verify_peak(short)
    more_bytes = long.stat().st_size - short.stat().st_size
    assert more_bytes > 1_000_000
    assert grown < more_bytes / 20, f"{grown} bytes more for {more_bytes} bytes more of file"
    result = verify_session(long)
    assert result.cycles == 3000 and result.events == load_session(long).last_seq
    assert ", 31 rejected, running" in result.message  # 30 and the base session's one
