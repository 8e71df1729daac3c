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
from station.session.journal import SessionWriter, session_header


def make_session(folder: Path, cycles: int = 3) -> Path:
    procedure = discover_procedures(use_env=False).get("repeatability")
    header = session_header(procedure, robot="cell 4", operator="ana")
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
    (line,) = intact.stdout.splitlines()
    assert "intact" in line and "3 cycles, 1 rejected" in line
    from station.session.model import load_session

    assert line.endswith(f"last hash {load_session(path, recover=False).last_hash}")

    data = bytearray(path.read_bytes())
    for line_number in (1, 3, 6):  # header, a reading, the finish line
        start = sum(len(x) + 1 for x in bytes(data).split(b"\n")[: line_number - 1])
        damaged = bytearray(data)
        damaged[start + 12] ^= 0x04
        target = tmp_path / f"damaged{line_number}.jsonl"
        target.write_bytes(bytes(damaged))
        result = station("verify", str(target))
        assert result.returncode == 1
        assert f"NOT intact: line {line_number}:" in result.stdout

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
