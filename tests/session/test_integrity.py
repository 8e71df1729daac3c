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
