"""`station verify`, `station export` and `station procedures` through the real command line."""

from __future__ import annotations

import csv
import io
import subprocess
import sys
from datetime import UTC, datetime
from pathlib import Path

import pytest

from station.cli import main
from station.procedures import discover_procedures
from station.run import PortSetup, SessionSetup
from station.session.journal import SessionWriter


def make_session(folder: Path, cycles: int = 3) -> Path:
    procedure = discover_procedures(use_env=False).get("repeatability")
    port = PortSetup("loop://", "mitutoyo", {"1": "x", "2": "y", "3": "z"})
    header = SessionSetup(procedure, "cell 4", "ana", (port,)).header_fields()
    moment = datetime(2026, 11, 23, 9, 30, tzinfo=UTC)
    with SessionWriter.create(folder, header, now=moment) as writer:
        for cycle in range(1, cycles + 1):
            channels = {c: {"value": 0.0001 * cycle, "unit": "in"} for c in ("x", "y", "z")}
            writer.append("reading", cycle=cycle, step="cycles", channels=channels)
        writer.append("reject", cycle=1, reason="robot bumped")
        writer.append("finish")
    return writer.path


def station(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "station", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=60,
    )


def test_verify_exit_codes_through_the_real_cli(tmp_path: Path) -> None:
    path = make_session(tmp_path)
    intact = station("verify", str(path))
    assert intact.returncode == 0, intact.stderr
    verdict, line, key, anchor = intact.stdout.splitlines()
    assert verdict == f"{path}: intact" and "3 cycles, 1 rejected" in line
    assert key.startswith("signed by station key: ")
    from station.session.model import load_session

    assert anchor == f"last hash: {load_session(path, recover=False).last_hash}"

    data = bytearray(path.read_bytes())
    for line_number in (1, 3, 6):  # header, a reading, the finish line
        start = sum(len(x) + 1 for x in bytes(data).split(b"\n")[: line_number - 1])
        damaged = bytearray(data)
        damaged[start + 12] ^= 0x04
        target = tmp_path / f"damaged{line_number}.jsonl"
        target.write_bytes(bytes(damaged))
        result = station("verify", str(target))
        assert result.returncode == 1
        verdict, detail = result.stdout.splitlines()[:2]
        assert verdict == f"{target}: NOT intact" and detail.startswith(f"line {line_number}: ")

    missing = station("verify", str(tmp_path / "nope.jsonl"))
    assert missing.returncode == 2
    assert (
        missing.stderr.strip() == f"station: session file {tmp_path / 'nope.jsonl'} does not exist"
    )


def test_export_to_stdout_and_to_a_file(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    path = make_session(tmp_path)
    assert main(["export", str(path), "--csv"]) == 0
    rows = list(csv.reader(io.StringIO(capsys.readouterr().out)))
    assert rows[0][:6] == ["cycle", "channel", "value", "unit", "status", "time"]
    assert len(rows) == 1 + 9
    assert rows[1][4] == "rejected: robot bumped" and rows[4][4] == "ok"

    out = tmp_path / "out.csv"
    assert main(["export", str(path), "--csv", "-o", str(out)]) == 0
    assert out.read_text().splitlines()[0].startswith("cycle,channel,value,unit,status,time")
    out.write_text("keep me")
    assert main(["export", str(path), "--csv", "-o", str(out)]) == 2
    assert "exists; pass --force" in capsys.readouterr().err
    assert out.read_text() == "keep me"
    assert main(["export", str(path), "--csv", "-o", str(out), "--force"]) == 0
    assert out.read_text().count("\n") == 10


def test_export_never_modifies_a_torn_session(tmp_path: Path, capsys) -> None:
    path = make_session(tmp_path)
    damaged = path.read_bytes() + b'{"seq":9'
    path.write_bytes(damaged)
    assert main(["export", str(path), "--csv"]) == 0
    assert "torn" in capsys.readouterr().err
    assert path.read_bytes() == damaged


def test_procedures_lists_builtins_and_site_overrides(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.delenv("STATION_PROCEDURES", raising=False)
    listing = station("procedures", cwd=tmp_path)
    assert listing.returncode == 0, listing.stderr
    header, *rows = listing.stdout.splitlines()
    assert header.split()[:5] == ["ID", "TITLE", "VERSION", "SECTION", "ORIGIN"]
    (row,) = (r for r in rows if r.startswith("repeatability "))
    assert row.startswith("repeatability") and "§2.6" in row and "built-in" in row

    site = tmp_path / "site"
    site.mkdir()
    builtin = discover_procedures(use_env=False).get("repeatability").path.read_text()
    (site / "rep.toml").write_text(builtin.replace('version = "1.0"', 'version = "9"'))
    ours = station("procedures", "--procedures", str(site), cwd=tmp_path)
    assert ours.returncode == 0
    assert "site, overrides built-in" in ours.stdout and "note: repeatability:" in ours.stdout
    (site / "bad.toml").write_text("id = 'bad'\n")
    bad = station("procedures", "--procedures", str(site), cwd=tmp_path)
    assert bad.returncode == 1 and "bad.toml: missing required key 'title'" in bad.stdout


def test_verify_fits_80_columns_with_the_hash_on_its_own_line(tmp_path: Path) -> None:
    """Review finding 14: the verdict and the 64-digit hash used to share one 182-column line."""
    path = make_session(tmp_path / "s")
    result = station("verify", path.name, cwd=path.parent)
    assert result.returncode == 0, result.stderr
    assert all(len(line) <= 80 for line in result.stdout.splitlines()), result.stdout
    assert result.stdout.splitlines()[-1].startswith("last hash: ")


@pytest.mark.parametrize("command", ["verify", "export", "analyze"])
@pytest.mark.parametrize("content", [b"cycle,x\n1,0.1\n", b"", b"hello", b'{"format":"other"}\n'])
def test_a_file_that_is_not_a_session_is_named_so(
    tmp_path: Path, command: str, content: bytes, capsys: pytest.CaptureFixture
) -> None:
    """Review finding 13: verify said "NOT intact: line 1: torn" (exit 1) on a CSV file."""
    path = tmp_path / "readings.jsonl"
    path.write_bytes(content)
    args = [command, str(path)] + (["--csv"] if command == "export" else [])
    assert main(args) == 2
    what = "is empty:" if not content else "is"
    assert capsys.readouterr().err == (
        f"station: {path} {what} not a station session file (its first line is not a "
        "station-session/1 header)\n"
    )
    assert path.read_bytes() == content


def test_a_session_with_an_edited_format_is_damaged_not_foreign(tmp_path: Path) -> None:
    path = make_session(tmp_path)
    path.write_bytes(path.read_bytes().replace(b"station-session/1", b"station-session/2", 1))
    result = station("verify", str(path))
    assert result.returncode == 1 and result.stdout.splitlines()[1].startswith("line 1: ")
