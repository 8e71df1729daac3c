"""The station's own data folders (below ``$XDG_DATA_HOME`` and ``$XDG_CONFIG_HOME``) are never
read or written through a symbolic link, at any level the station creates (issue 27, finding 6).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from helpers import run_station

from station.errors import StationError
from station.record.baseline import baselines_folder, store_baseline
from station.session.signing import station_key
from station.session.store import sessions_folder
from tests.record.conftest import write_repeatability


def _data_home() -> Path:
    return Path(os.environ["XDG_DATA_HOME"])


def test_a_symlinked_baselines_folder_is_refused_and_its_target_untouched(tmp_path):
    sessions = tmp_path / "sessions"
    filed = write_repeatability(sessions, robot="R1")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (_data_home() / "station").mkdir(parents=True)
    (_data_home() / "station" / "baselines").symlink_to(elsewhere)
    with pytest.raises(StationError, match="baselines is a symbolic link"):
        store_baseline("R1", filed)
    assert list(elsewhere.iterdir()) == []


def test_a_symlinked_station_data_folder_is_refused_for_every_data_file(tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    _data_home().mkdir(parents=True)
    (_data_home() / "station").symlink_to(elsewhere)
    with pytest.raises(StationError, match="symbolic link"):
        baselines_folder()
    with pytest.raises(StationError, match="symbolic link, refused for the sessions folder"):
        sessions_folder(cwd=tmp_path)
    environ = {k: v for k, v in os.environ.items() if k != "STATION_GAUGES"}
    listed = run_station("gauges", "list", env=environ)
    assert listed.returncode == 2
    assert "no gauges recorded yet" not in listed.stdout
    assert "refused for the gauge register" in listed.stderr
    assert len(listed.stderr.strip().splitlines()) == 1
    assert list(elsewhere.iterdir()) == []


def test_the_signing_key_is_not_made_through_a_symlinked_config_folder(tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    config = Path(os.environ["XDG_CONFIG_HOME"])
    config.mkdir(parents=True)
    (config / "station").symlink_to(elsewhere)
    with pytest.raises(StationError, match="symbolic link"):
        station_key()
    assert list(elsewhere.iterdir()) == []


def test_the_users_own_folders_above_the_station_may_be_links(tmp_path):
    real = tmp_path / "real-share"
    real.mkdir()
    linked = tmp_path / "share-link"
    linked.symlink_to(real)
    folder, _ = sessions_folder(cwd=tmp_path, environ={"XDG_DATA_HOME": str(linked)})
    assert folder == linked / "station" / "sessions"
