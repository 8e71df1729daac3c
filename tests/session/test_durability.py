"""Review finding 19: every new name reaches the disk (file data, then its folder entries).

``os.fsync`` is wrapped (it still syncs) to record what was synced and in which order, read
back through ``/proc/self/fd``.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from station.cli import main
from station.session.journal import SessionWriter
from station.session.model import load_session

from .conftest import session_header_fields, write_session

pytestmark = pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="needs /proc")


@pytest.fixture
def synced(monkeypatch: pytest.MonkeyPatch) -> list[Path]:
    """The paths passed to os.fsync, in order."""
    seen: list[Path] = []
    real_fsync = os.fsync

    def recording_fsync(fd: int) -> None:
        seen.append(Path(os.readlink(f"/proc/self/fd/{fd}")))
        real_fsync(fd)

    monkeypatch.setattr(os, "fsync", recording_fsync)
    return seen


def test_a_first_session_in_a_new_folder_syncs_every_created_parent(
    tmp_path: Path, synced: list[Path]
) -> None:
    folder = tmp_path / "site" / "cell4" / "sessions"
    with SessionWriter.create(folder, session_header_fields()) as writer:
        path = writer.path
    for created in (tmp_path / "site", tmp_path / "site" / "cell4", folder):
        # Each new folder is a name in its parent: the parent is synced after it exists.
        assert created.parent in synced, synced
    assert synced.index(path) < len(synced) - 1 and synced[-1] == folder


def test_the_torn_file_name_is_synced_before_the_session_is_cut(
    tmp_path: Path, synced: list[Path]
) -> None:
    path = write_session(tmp_path / "sessions", finish=False)
    path.write_bytes(path.read_bytes() + b'{"seq":99,"t":')
    synced.clear()
    session = load_session(path, recover=True)
    assert session.torn is not None and session.torn.moved_to is not None
    torn = session.torn.moved_to
    assert synced.index(torn) < synced.index(path.parent) < synced.index(path), synced


def test_export_syncs_the_file_before_the_rename_and_the_folder_after(
    tmp_path: Path, synced: list[Path], capsys: pytest.CaptureFixture
) -> None:
    path = write_session(tmp_path / "sessions")
    out = tmp_path / "out" / "export.csv"
    out.parent.mkdir()
    synced.clear()
    assert main(["export", str(path), "--csv", "-o", str(out)]) == 0
    # The private temporary file (a random name beside OUT), then the folder after the rename.
    assert len(synced) == 2 and synced[1] == out.parent, synced
    assert synced[0].name.startswith(f".{out.name}.") and synced[0].name.endswith(".partial")
    assert not synced[0].exists()
    assert out.read_text().startswith("cycle,channel,value")
