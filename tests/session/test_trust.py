"""Issue 27, finding 1: `station verify` passes only a session signed by a trusted station key.

A forger who edits a reading, rechains the file and strips the header's ``signer`` and the
finish's ``signature`` (or re-signs with a key of their own) must not get exit 0; verify reads
only public keys (the trust store), so a damaged private key does not stop it; a file cut
before its finish is never called signed.
"""

from __future__ import annotations

import json
import os
import subprocess
from datetime import UTC, datetime
from pathlib import Path

import pytest
from cryptography.hazmat.primitives import serialization
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey
from helpers import run_station

from station.session.journal import SessionWriter
from station.session.lines import encode_line, line_hash
from station.session.signing import KEY_FILE_NAME, config_folder, finish_message
from station.session.trust import TRUST_FILE_NAME

from .conftest import reading_fields, session_header_fields

REPO = Path(__file__).resolve().parents[2]
SINCE_SIGNING = datetime(2026, 12, 1, 8, 0, tzinfo=UTC)
OLD_UNSIGNED = REPO / "tests/tui/snapshots/sessions/2026-11-23T175031Z_R1_repeatability.jsonl"


def station(*args: str | Path) -> subprocess.CompletedProcess[str]:
    """``station ARGS`` in this process."""
    return run_station(*args, cwd=REPO)


def record_session(folder: Path, *, finish: bool = True) -> Path:
    """A session as this station records it today: dated after signing, signed."""
    with SessionWriter.create(folder, session_header_fields(), now=SINCE_SIGNING) as writer:
        for cycle in range(1, 4):
            writer.append("reading", **reading_fields(cycle))
        if finish:
            writer.append("finish", verdict="capable")
    return writer.path


def said(result: subprocess.CompletedProcess[str]) -> str:
    """What verify printed, its wrapped lines joined: sentences are matched whole."""
    return " ".join(result.stdout.split())


def records_of(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_bytes().splitlines()]


def write_rechained(path: Path, records: list[dict]) -> Path:
    """What a forger with plain sha256 does: every ``prev`` and ``hash`` computed again."""
    lines, prev = [], None
    for record in records:
        line = encode_line({k: v for k, v in record.items() if k not in ("prev", "hash")}, prev)
        lines.append(line)
        prev = line_hash(line)
    path.write_bytes(b"".join(line + b"\n" for line in lines))
    return path


def forge_reading(records: list[dict]) -> None:
    for record in records:
        if record.get("type") == "reading" and record["cycle"] == 2:
            record["channels"]["x"]["value"] = 0.0009


def test_a_forged_session_stripped_of_its_signature_does_not_verify(tmp_path: Path) -> None:
    records = records_of(record_session(tmp_path / "sessions"))
    forge_reading(records)
    del records[0]["signer"]
    del records[-1]["signature"]
    forged = write_rechained(tmp_path / "forged.jsonl", records)

    result = station("verify", forged)
    assert result.returncode == 1, result.stdout
    assert f"{forged}: NOT trusted" in result.stdout
    assert "signature was removed" in said(result)
    assert "signed by" not in result.stdout and "last hash" not in result.stdout

    allowed = station("verify", "--allow-unsigned", forged)
    assert allowed.returncode == 0, allowed.stdout
    assert "--allow-unsigned: the session is unsigned" in said(allowed)


def test_a_session_resigned_with_another_key_fails_until_that_key_is_trusted(
    tmp_path: Path,
) -> None:
    records = records_of(record_session(tmp_path / "sessions"))
    forge_reading(records)
    other = Ed25519PrivateKey.generate()
    raw = other.public_key().public_bytes(
        serialization.Encoding.Raw, serialization.PublicFormat.Raw
    )
    from station.session.signing import StationKey

    forger = StationKey(other, raw)
    records[0]["signer"] = forger.header_field()
    forged = write_rechained(tmp_path / "resigned.jsonl", records)
    # Sign the rechained finish as the forger's own station would.
    finish = records_of(forged)[-1]
    records[-1]["signature"] = forger.sign(
        finish_message(records[0]["session"], finish["prev"], finish["seq"])
    )
    write_rechained(forged, records)

    result = station("verify", forged)
    assert result.returncode == 1, result.stdout
    assert f"{forged}: NOT trusted" in result.stdout
    assert f"signed with station key {forger.id}" in said(result)
    assert "station keys trust" in said(result) and "signed by" not in result.stdout

    anyone = station("verify", "--trust-any", forged)
    assert anyone.returncode == 0, anyone.stdout
    assert "--trust-any" in said(anyone)
    assert f"signed by station key: {forger.id} (not in the trust store)" in anyone.stdout

    # The plant's other station, once trusted by name, is accepted and named.
    public_file = tmp_path / "plant-2.pub"
    from station.session.trust import PublicKey

    public_file.write_text(PublicKey(raw, "cell 2").line + "\n")
    trusted = station("keys", "trust", public_file, "--name", "plant 2")
    assert trusted.returncode == 0, trusted.stderr
    assert f"trusted station key {forger.id} as plant 2" in trusted.stdout
    now = station("verify", forged)
    assert now.returncode == 0, now.stdout
    assert f"signed by station key: {forger.id} (trusted: plant 2)" in now.stdout


def test_another_stations_session_verifies_once_its_shown_key_is_trusted(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    session = record_session(tmp_path / "sessions")
    shown = station("keys", "show")
    assert shown.returncode == 0 and shown.stdout.startswith("ed25519 "), shown
    (tmp_path / "station-a.pub").write_text(shown.stdout)

    # Station B: a config folder of its own, with a key of its own.
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "station-b"))
    record_session(tmp_path / "b-sessions")
    assert station("verify", session).returncode == 1
    assert station("keys", "trust", tmp_path / "station-a.pub").returncode == 0
    assert station("verify", session).returncode == 0
    listing = station("keys", "list").stdout.splitlines()
    assert listing[0] == f"trust store: {config_folder() / TRUST_FILE_NAME}"
    assert len(listing) == 3 and "this station" in listing[1]


def _damage(key_file: Path, how: str, tmp_path: Path) -> None:
    if how == "removed":
        key_file.unlink()
    elif how == "damaged":
        key_file.write_bytes(b"-----BEGIN PRIVATE KEY-----\nnot a key\n")
    elif how == "empty":
        key_file.write_bytes(b"")
    elif how == "a link":
        target = tmp_path / "elsewhere.pem"
        target.write_bytes(key_file.read_bytes())
        key_file.unlink()
        key_file.symlink_to(target)
    elif how == "another type":
        key_file.write_bytes(
            ec.generate_private_key(ec.SECP256R1()).private_bytes(
                serialization.Encoding.PEM,
                serialization.PrivateFormat.PKCS8,
                serialization.NoEncryption(),
            )
        )


@pytest.mark.parametrize("how", ["removed", "damaged", "empty", "a link", "another type"])
def test_verify_needs_only_public_keys(tmp_path: Path, how: str) -> None:
    session = record_session(tmp_path / "sessions")
    _damage(config_folder() / KEY_FILE_NAME, how, tmp_path)
    result = station("verify", session)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "signed by station key: " in result.stdout and "(trusted: this station" in result.stdout


def test_a_key_made_before_the_trust_store_is_still_this_stations(tmp_path: Path) -> None:
    session = record_session(tmp_path / "sessions")
    (config_folder() / TRUST_FILE_NAME).unlink()
    result = station("verify", session)
    assert result.returncode == 0, result.stdout
    assert "(trusted: this station" in result.stdout


def test_a_file_cut_before_its_finish_is_not_called_signed(tmp_path: Path) -> None:
    session = record_session(tmp_path / "sessions")
    cut = tmp_path / "cut.jsonl"
    cut.write_bytes(b"".join(line + b"\n" for line in session.read_bytes().splitlines()[:-1]))
    result = station("verify", cut)
    assert result.returncode == 0, result.stdout
    assert "signed by" not in result.stdout
    assert "unfinished, so nothing in it is signed yet" in said(result)


def test_an_unsigned_session_from_before_signing_still_verifies_and_says_so() -> None:
    result = station("verify", OLD_UNSIGNED)
    assert result.returncode == 0, result.stdout
    assert "before stations signed their sessions" in said(result)
    assert "signed by" not in result.stdout


def test_keys_trust_refuses_what_is_not_one_key_in_one_line(tmp_path: Path) -> None:
    garbage = tmp_path / "garbage.pub"
    garbage.write_text("ssh-rsa AAAA nope\n")
    result = station("keys", "trust", garbage)
    assert result.returncode == 2 and len(result.stderr.splitlines()) == 1
    assert "is not a station public key" in result.stderr
    key = tmp_path / "ok.pub"
    station("keys", "show")
    key.write_text(station("keys", "show").stdout)
    named = station("keys", "trust", key, "--name", "evil\x1b]0;title")
    assert named.returncode == 2 and "\x1b" not in named.stderr
    assert "--name" in named.stderr


def test_a_damaged_trust_store_is_one_sentence_naming_its_line(tmp_path: Path) -> None:
    session = record_session(tmp_path / "sessions")
    store = config_folder() / TRUST_FILE_NAME
    store.write_text(store.read_text() + "ed25519 !!!\n")
    result = station("verify", session)
    assert result.returncode == 2 and len(result.stderr.splitlines()) == 1, result.stderr
    assert f"{store} line 3 is not a station public key" in result.stderr


def test_the_own_key_enters_the_store_once_with_mode_0600(tmp_path: Path) -> None:
    record_session(tmp_path / "sessions")
    record_session(tmp_path / "sessions")
    store = config_folder() / TRUST_FILE_NAME
    assert oct(os.stat(store).st_mode & 0o777) == "0o600"
    assert len([line for line in store.read_text().splitlines() if line.startswith("ed25519")]) == 1
